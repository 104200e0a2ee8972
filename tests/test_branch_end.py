"""Where the no-slip delamination branch ends, under both loading modes.

With weak adhesion (or a strongly curved substrate) the quasi-static no-slip delamination branch
ends at a finite contact radius: the stretch-mismatch part of the release rate, (t - 1)^2 / 2,
alone reaches w, the contact angle goes to 0 and no state with G = w exists at smaller radii. The
history then ends there and records the radius in ``inputs["delamination_ends_at_a"]`` (detachment
from there on is dynamic, outside the quasi-static model).

Checked against the independent mpmath reference (``tests/reference/mp_model.py``): just above the
recorded radius both models have the same state (to 1e-9, the reference tolerance, even though the
branch folds there); just below it neither has one.
"""
from __future__ import annotations

import numpy as np
import pytest

from adhfit.errors import ConvergenceError
from adhfit.loading import history, state_at

from tests.reference import mp_model as M

CASES = [
    ("pressure", dict(d=0.0, w=0.2, rs=0.3, a_max=0.25)),
    ("displacement", dict(p=0.3, w=0.01, rs=0.5, a_max=0.25)),
]
IDS = [c for c, _ in CASES]


@pytest.mark.parametrize("control,kw", CASES, ids=IDS)
def test_history_ends_where_the_branch_ends(control, kw):
    h = history(control, "no-slip", **kw)
    end = h.inputs["delamination_ends_at_a"]
    cols = h.columns
    dl = cols["stage"] == "delamination"
    assert 0.0 < end < kw["a_max"]
    assert cols["stage"][-1] == "delamination" and cols["a"][-1] == pytest.approx(end, rel=1e-12)
    assert cols["G"][dl] == pytest.approx(kw["w"], rel=1e-12)
    # alpha -> 0 at the end of the branch (alpha ~ sqrt(a - a_end) there)
    assert cols["alpha"][-1] < 1e-3 * cols["alpha"][dl][0]
    assert all(cols["alpha"][dl][-5:][i] > cols["alpha"][dl][-5:][i + 1] for i in range(4))


@pytest.mark.parametrize("control,kw", CASES, ids=IDS)
def test_branch_end_agrees_with_the_reference(control, kw):
    end = history(control, "no-slip", **kw).inputs["delamination_ends_at_a"]
    # above the end (1e-2 and 1e-4 relative: the second one next to the fold)
    for a in (end * 1.01, end * 1.0001):
        ref = M.state(control, "no-slip", "delamination", a=a, **kw)
        got = state_at(control, "no-slip", "delamination", a=a, **kw)
        for k in ("f", "p", "d", "alpha"):
            assert got[k] == pytest.approx(float(ref[k]), abs=1e-9), (a, k)
    # below it: no quasi-static state in either model
    a = end * 0.999
    with pytest.raises((M.NoConvergence, M.Inadmissible)):
        M.state(control, "no-slip", "delamination", a=a, **kw)
    with pytest.raises(ConvergenceError):
        state_at(control, "no-slip", "delamination", a=a, **kw)


#: histories whose force minimum sits next to the end of the branch (found by the stress run):
#: the state at that end cannot be re-solved (a fold), so the extremum searches there fall back on
#: the rows and on each other's solved state
FOLD_EXTREMA = [
    ("displacement", dict(p=0.7055031730751964, w=0.00015430059527361725, rs=float("inf"),
                          a_max=0.5285278931100347)),
    ("pressure", dict(d=0.8686112266428161, w=0.0031809970016505513, rs=0.1587287739460948,
                      a_max=0.04720687647560918)),
]


@pytest.mark.parametrize("control,kw", FOLD_EXTREMA, ids=[c for c, _ in FOLD_EXTREMA])
def test_extrema_next_to_the_branch_end_bound_every_row(control, kw):
    h = history(control, "no-slip", points=50, **kw)
    cols, summ = h.columns, h.summary
    retraction = cols["stage"] != "making_contact"
    assert "delamination_ends_at_a" in h.inputs
    assert summ["f_min"]["f"] <= cols["f"][retraction].min()
    # the turning point of the control variable: the least p (pressure control) or the largest
    # gap d, i.e. the least displacement delta = d0(p) - d (displacement control)
    key, sign = ("p", -1.0) if control == "pressure" else ("delta", -1.0)
    tp = sign * summ["turning_point"][key]
    assert tp >= np.nanmax(sign * cols[key][retraction]) - 1e-15
