"""Seed-7 stress scenes of the exact membrane (issue 24): each one's fix, checked independently."""
import numpy as np
import pytest

import adhfit

# frictionless pinning from the end of loading: two branches leave it with alpha > 0; the bracket's long
# step found the onset on the one that retracts, the rows' small steps marched the one that presses on
# (delta to 0.329 above delta_max = 0.277, G to 1.014 w): G > w, an invariant violation
TWO_BRANCHES = {"control": "displacement", "slip": "frictionless", "p": -0.4962363076740124,
                "w": 0.0004312961328937199, "rs": 0.1164326084950816, "delta_max": 0.27683608787610026,
                "lambda0": 1.2957849492660565}


@pytest.mark.parametrize("points", [10, 200])
def test_pinning_rows_on_the_onsets_branch(points):
    sc = TWO_BRANCHES
    f = adhfit.simulate(**sc, points=points, membrane="exact").frame
    G, delta, stage = f["G"].to_numpy(), f["delta"].to_numpy(), f["stage"].to_numpy()
    assert G.min() >= 0.0 and G.max() <= sc["w"] * (1 + 1e-9)
    pin = np.flatnonzero(stage == "pinning")
    end = delta[np.flatnonzero(stage == "making_contact")[-1]]
    assert pin.size
    # the history retracts: delta falls, G rises along pinning, every row stable, none above delta_max
    assert np.all(delta[pin] <= end + 1e-12)
    assert np.all(np.diff(delta[pin]) < 0) and np.all(np.diff(G[pin]) > 0)
    assert f["stable"].to_numpy()[pin].all()


def test_pinning_rows_match_a_finer_grid():
    """Independent: on 1001 rows (a march on other alpha values) the onset and the pinning rows' path
    (delta as a function of alpha, interpolated) agree with the 200-row history."""
    sc = TWO_BRANCHES
    r1 = adhfit.simulate(**sc, points=200, membrane="exact")
    r2 = adhfit.simulate(**sc, points=1001, membrane="exact")
    for k in ("f", "delta", "a"):
        assert abs(r1.summary["onset"][k] - r2.summary["onset"][k]) < 1e-8
    f1, f2 = r1.frame, r2.frame
    p1, p2 = f1[f1.stage == "pinning"], f2[f2.stage == "pinning"]
    x = p1["alpha"].to_numpy()
    y2 = np.interp(x, p2["alpha"].to_numpy(), p2["delta"].to_numpy())
    assert np.max(np.abs(y2 - p1["delta"].to_numpy())) < 1e-5
    assert abs(r1.summary["onset"]["delta"] - 0.221366) < 1e-5 and r1.summary["onset"]["delta"] < sc["delta_max"]


# pressure control, frictionless: on 10 and 11 rows the delamination march's first step (rho_a 0.646 ->
# 0.510) landed on another branch (a = 0.955 beyond the onset's 0.915, p rising to 11) and stalled at
# a = 0.661 (a ConvergenceError), where 50 and 1001 rows run to detachment
COARSE_JUMP = {"control": "pressure", "slip": "frictionless", "d": 0.00047629419930195205,
               "w": 0.0014415770553646212, "rs": 10.469916439767628, "p_max": 4.976477065575025,
               "lambda0": 1.3979752782183414}


def test_delamination_on_few_rows_follows_the_fine_grids_branch():
    """Independent: the 1001-row history (its own march, 500 delamination steps) gives the same summary
    values to 1e-8 as 10 and 11 rows; every delamination row lies on the 1001-row path (p against a)."""
    sc = COARSE_JUMP
    ref = adhfit.simulate(**sc, points=1001, membrane="exact")
    fr = ref.frame[ref.frame.stage == "delamination"]
    order = np.argsort(fr["a"].to_numpy())
    for points in (10, 11):
        r = adhfit.simulate(**sc, points=points, membrane="exact")
        for k in ("f_max",):
            assert abs(r.summary[k] - ref.summary[k]) < 1e-8
        for part in ("onset", "f_min", "turning_point"):
            for k in ("f", "p", "a"):
                assert abs(r.summary[part][k] - ref.summary[part][k]) < 1e-8, (points, part, k)
        d = r.frame[r.frame.stage == "delamination"]
        a = d["a"].to_numpy()
        assert np.all(a <= ref.summary["onset"]["a"] * (1 + 1e-12)) and np.all(np.diff(a) < 0)
        p_ref = np.interp(a, fr["a"].to_numpy()[order], fr["p"].to_numpy()[order])
        assert np.max(np.abs(p_ref - d["p"].to_numpy())) < 1e-4 * (1 + np.abs(p_ref).max())
