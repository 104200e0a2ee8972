"""Issue 24 item 4: summary values that do not depend on ``points``, held against the 30-digit
reference (``tests/reference/mp_model.py``), on scenes where they did (stress run, seed 24).
"""
from __future__ import annotations

import math

import mpmath as mp
import pytest

import adhfit
from tests.reference import mp_model as M

#: the turning point lies in delamination between the onset and the first delamination row: on
#: 10 rows the search stayed in pinning and put it at the onset (f off by 0.079)
PAST_ONSET = dict(control="displacement", slip="no-slip", p=0.29005668780559546, w=0.9538405037973043,
                  rs=math.inf, a_max=0.3376478745702898)
#: pressure control on a small, strongly curved substrate: at p_cr a contact of the second row's
#: radius is outside the model, and on 10 rows (a predictor too far off) the making-contact solve
#: failed there, reported as "a_max must be in [0.001, 0.0105]" (1001 rows solved it)
COARSE_LOADING = dict(control="pressure", slip="no-slip", d=-0.9233514634542666, w=0.014262658686865845,
                      rs=0.03338358998530069, a_max=0.027248583315855397)
#: a flat turn: on 1001 rows the first clearly falling row came several rows past the extremum,
#: and the turning point's contact radius was 9e-8 off
FLAT_TURN = dict(control="displacement", slip="no-slip", p=-0.905915986456308, w=0.000490407490258893,
                 rs=0.04476362210836107, a_max=0.011411708935500073)


def test_the_turning_point_past_the_onset_is_found_on_any_grid():
    ref = M.summary(**PAST_ONSET)["turning_point"]
    assert ref["stage"] == "delamination"
    for n in (10, 11, 50, 1001):
        tp = adhfit.simulate(**PAST_ONSET, points=n).summary["turning_point"]
        for q in ("f", "delta", "a"):
            assert tp[q] == pytest.approx(float(ref[q]), abs=1e-8), (n, q)


def test_a_coarse_grid_solves_pressure_control_loading_near_the_critical_pressure():
    with mp.workdps(30):
        rs, a_m, d = mp.mpf(COARSE_LOADING["rs"]), mp.mpf(COARSE_LOADING["a_max"]), mp.mpf(COARSE_LOADING["d"])
        kap = mp.findroot(lambda k: M.contact_profile(k, a_m, rs).gap - d, mp.mpf("-0.96"))
        f_max = float(M.contact_profile(kap, a_m, rs).f)
    for n in (10, 11, 50, 1001):
        r = adhfit.simulate(**COARSE_LOADING, points=n)
        assert r.summary["f_max"] == pytest.approx(f_max, abs=1e-12), n
        end = r.frame[r.frame.stage == "making_contact"].iloc[-1]
        assert end.p == pytest.approx(float(kap), abs=1e-12)


def test_a_flat_turn_is_located_on_dense_and_coarse_grids():
    # the reference cannot follow this no-slip delamination branch (w = 5e-4, it ends toward
    # alpha -> 0); single states (loading.state_at: their own continuation from the onset, no rows)
    # are the second method: the reported turning point is a least delta among its neighbours
    from adhfit.loading import state_at
    kw = {k: v for k, v in FLAT_TURN.items() if k not in ("control", "slip")}
    tps = [adhfit.simulate(**FLAT_TURN, points=n).summary["turning_point"] for n in (10, 200, 1001)]
    for tp in tps:
        assert tp["delta"] == pytest.approx(tps[0]["delta"], abs=1e-12)
        assert tp["a"] == pytest.approx(tps[0]["a"], abs=1e-9)
    a_tp = tps[0]["a"]
    at = state_at("displacement", "no-slip", "delamination", **kw, a=a_tp)
    assert at["delta"] == pytest.approx(tps[0]["delta"], abs=1e-12)
    # neighbours either side (the branch ends 1.3e-4 below, at alpha -> 0)
    for rel in (-3e-5, -1e-5, 1e-5, 1e-4):
        near = state_at("displacement", "no-slip", "delamination", **kw, a=a_tp * (1 + rel))
        assert near["delta"] > at["delta"]
