"""The history contract of ``adhfit.simulate`` (docs/contracts.md A2, A2b) over every control x slip x
substrate, and starts at p <= 0 and d < 0 (issue 2)."""
from __future__ import annotations

import doctest
import math

import numpy as np
import pandas as pd
import pytest

import adhfit
import adhfit.simulation
from adhfit.core.inflation import apex_deflection

INF = math.inf
COLUMNS = ["stage", "a", "alpha", "p", "d", "delta", "f", "G", "stable"]
STAGES = ["making_contact", "pinning", "delamination"]
SLIPS = ("no-slip", "frictionless")
BASES = {
    "displacement-curved": ("displacement", dict(p=0.6, rs=0.5)),
    "displacement-flat": ("displacement", dict(p=0.6, rs=INF)),
    "pressure-curved": ("pressure", dict(d=0.0, rs=0.5)),
    "pressure-flat": ("pressure", dict(d=0.2, rs=INF)),
    "displacement-p0": ("displacement", dict(p=0.0, rs=0.5)),
    "displacement-p-neg": ("displacement", dict(p=-0.3, rs=0.5)),
    "pressure-d-neg": ("pressure", dict(d=-0.2, rs=0.5)),
}
W, A_MAX = 0.2, 0.25


@pytest.fixture(scope="module", params=[(b, s) for b in BASES for s in SLIPS], ids=lambda x: f"{x[0]}-{x[1]}")
def run(request):
    base, slip = request.param
    control, kw = BASES[base]
    return control, slip, kw, adhfit.simulate(control, slip, w=W, a_max=A_MAX, **kw)


def _ctrl(control, frame_or_point):
    return frame_or_point["delta" if control == "displacement" else "p"]


def test_columns_types_and_size(run):
    control, slip, kw, r = run
    fr = r.frame
    assert isinstance(fr, pd.DataFrame) and list(fr.columns) == COLUMNS
    assert fr.stable.dtype == bool
    for col in COLUMNS[1:-1]:
        assert fr[col].dtype == np.float64, col
    assert 200 <= len(fr) <= 205                        # points=200 default, "approximate"
    assert fr.index.equals(pd.RangeIndex(len(fr)))


def test_stage_order_and_stability(run):
    control, slip, kw, r = run
    fr = r.frame
    assert set(fr.stage) == set(STAGES)
    rank = fr.stage.map(STAGES.index).to_numpy()
    assert np.all(np.diff(rank) >= 0)
    st = fr.stable.to_numpy()
    assert st[0] and not st[-1] and np.all(np.diff(st.astype(int)) <= 0)
    assert fr.stable[fr.stage == "making_contact"].all()


def test_values_finite_and_in_range(run):
    control, slip, kw, r = run
    fr = r.frame
    for col in ("a", "alpha", "p", "d", "f", "G"):
        assert np.isfinite(fr[col]).all(), col
    assert fr.delta.isna().equals(fr.p.abs() > 1)
    np.testing.assert_allclose(fr.delta, apex_deflection(fr.p.to_numpy()) - fr.d, rtol=0, atol=1e-15)  # eq. (21)
    assert fr.G.between(0, W * (1 + 1e-12)).all()
    assert (fr.G[fr.stage == "making_contact"] == 0).all()
    np.testing.assert_allclose(fr.G[fr.stage == "delamination"], W, rtol=1e-12)
    assert fr.alpha.between(0, math.pi).all()
    # the fixed variable is fixed
    if control == "displacement":
        assert (fr.p == kw["p"]).all()
    else:
        assert (fr.d == kw["d"]).all()


def test_stage_geometry(run):
    control, slip, kw, r = run
    fr = r.frame
    mc, pin, dl = (fr[fr.stage == s] for s in STAGES)
    # making contact: a from 0 (free inflation) up to a_max, alpha = 0
    assert mc.a.iloc[0] == 0 and mc.a.iloc[-1] == A_MAX and mc.a.is_monotonic_increasing
    assert mc.f.iloc[0] == 0 and mc.f.is_monotonic_increasing
    # pinning: G grows from 0 to w; no slip keeps a = a_m
    assert pin.G.is_monotonic_increasing and pin.G.iloc[-1] == pytest.approx(W, rel=1e-12)
    if slip == "no-slip":
        assert (pin.a == A_MAX).all()
    # delamination: a shrinks toward detachment, ending at a small a with f and delta near 0
    assert dl.a.is_monotonic_decreasing
    last = fr.iloc[-1]
    assert last.a <= 1e-2 * A_MAX
    assert abs(last.f) <= 1e-2 * r.summary["f_max"]
    assert abs(last.delta) <= 2e-2 * (fr.delta.max() - fr.delta.min())


def test_summary_keys_and_values(run):
    control, slip, kw, r = run
    s = r.summary
    assert set(s) == {"f_max", "onset", "f_min", "turning_point"}
    assert isinstance(s["f_max"], float) and math.isfinite(s["f_max"])
    for key in ("onset", "f_min", "turning_point"):
        assert set(s[key]) == {"f", "delta", "p", "a"}
        for q, v in s[key].items():
            if v is None:
                assert q == "delta" and abs(s[key]["p"]) > 1
            else:
                assert isinstance(v, float) and math.isfinite(v), (key, q)
        if s[key]["delta"] is not None:
            fixed_d = kw["d"] if control == "pressure" else None
            if fixed_d is not None:
                assert s[key]["delta"] == pytest.approx(float(apex_deflection(s[key]["p"])) - fixed_d, abs=1e-15)
    mc = r.frame[r.frame.stage == "making_contact"]
    assert s["f_max"] == mc.f.iloc[-1]


def test_onset_is_where_G_reaches_w(run):
    control, slip, kw, r = run
    fr, on = r.frame, r.summary["onset"]
    pin = fr[fr.stage == "pinning"]
    row = pin.iloc[-1]
    assert row.G == pytest.approx(W, rel=1e-12)
    assert row.a == pytest.approx(on["a"], abs=1e-14) and row.f == pytest.approx(on["f"], abs=1e-12)
    assert row.p == pytest.approx(on["p"], abs=1e-12)
    assert (pin.G.iloc[:-1] < W).all()
    if slip == "frictionless":
        assert row.alpha == pytest.approx(math.atan(math.sqrt(2 * W)), rel=1e-13)   # eqs. (60), (63)


def _row_of(fr, point):
    hit = (np.abs(fr.a - point["a"]) <= 1e-13) & (np.abs(fr.f - point["f"]) <= 1e-13) \
        & (np.abs(fr.p - point["p"]) <= 1e-13)
    return np.flatnonzero(hit.to_numpy())


def test_extrema_are_rows_and_extreme(run):
    control, slip, kw, r = run
    fr, s = r.frame, r.summary
    i_fmin = _row_of(fr, s["f_min"])
    i_tp = _row_of(fr, s["turning_point"])
    assert i_fmin.size >= 1 and i_tp.size >= 1
    f = fr.f.to_numpy()
    assert np.all(s["f_min"]["f"] <= f + 1e-12)
    assert s["f_min"]["f"] == pytest.approx(f.min(), abs=1e-8)
    c = _ctrl(control, fr).to_numpy()
    tp = _ctrl(control, s["turning_point"])
    assert np.all(tp <= c[~np.isnan(c)] + 1e-12)
    # the turning point is the last stable row; the rows after it are the unstable branch
    assert fr.stable.to_numpy().nonzero()[0][-1] == i_tp[-1]
    # both extrema lie on the way out (pinning or delamination) and the force minimum is negative
    assert fr.stage[i_fmin[0]] != "making_contact" and fr.stage[i_tp[0]] != "making_contact"
    assert s["f_min"]["f"] < 0


def test_extrema_are_located_not_picked(run):
    """The extremum is solved between rows (docs/contracts.md A2, 'to 1e-8'): its neighbours on both sides in
    the same stage are no more extreme."""
    control, slip, kw, r = run
    fr, s = r.frame, r.summary
    for key, col in (("f_min", "f"), ("turning_point", "delta" if control == "displacement" else "p")):
        i = _row_of(fr, s[key])[0]
        v = fr[col].to_numpy()
        for j in (i - 1, i + 1):
            if 0 <= j < len(fr) and fr.stage[j] == fr.stage[i] and not np.isnan(v[j]):
                assert v[j] >= v[i] - 1e-12, (key, j)


def test_docstring_example_runs():
    finder = doctest.DocTestFinder()
    runner = doctest.DocTestRunner(optionflags=doctest.ELLIPSIS)
    tests = [t for t in finder.find(adhfit.simulation.simulate, "simulate",
                                    globs={"simulate": adhfit.simulate}) if t.examples]
    assert tests, "adhfit.simulate has no docstring example"
    for t in tests:
        runner.run(t)
    result = runner.summarize(verbose=False)
    assert result.failed == 0 and result.attempted >= 2


def test_python_api_matches_A2b_signature():
    import inspect
    sig = inspect.signature(adhfit.simulate)
    params = sig.parameters
    assert list(params)[:2] == ["control", "slip"]
    for name, default in (("p", None), ("d", None), ("a_max", None), ("delta_max", None), ("p_max", None),
                          ("lambda0", 2.0), ("points", 200)):
        assert params[name].default == default and params[name].kind is inspect.Parameter.KEYWORD_ONLY
    for name in ("w", "rs"):
        assert params[name].default is inspect.Parameter.empty
        assert params[name].kind is inspect.Parameter.KEYWORD_ONLY


def test_f_min_is_least_force_for_weak_adhesion():
    # w at the table's lower bound: the pull-off region a ~ sqrt(2w)/(2(p + 1/rs)) must be reached
    r = adhfit.simulate("displacement", "frictionless", p=0.6, w=1e-6, rs=0.5, a_max=0.25)
    assert r.summary["f_min"]["f"] < 0
    assert r.summary["f_min"]["f"] <= r.frame.f.min() + 1e-12
