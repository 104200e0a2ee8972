"""Large-stretch stress scenes (issue 24) whose summary values depended on the row count: each one's
fix, checked against a dense grid and the branch's own rows."""
import numpy as np
import pytest

import adhfit

# frictionless pinning under pressure control: two branches leave the end of loading. At 10 rows the
# state 1e-4 of the first row's locator was predicted from rows far away and solved on the branch that
# presses on (a = 1.0021 a_max, p up), so the turning point was put at the end of loading: 0.115 off
# in f (stress seed 11).
TWO_BRANCHES_PRESSURE = {"control": "pressure", "slip": "frictionless", "d": 0.727574087834012,
                         "w": 0.03514234879420914, "rs": 0.04659354112850265,
                         "a_max": 0.03993424853679094, "lambda0": 4.791440127254249}


@pytest.mark.parametrize("points", [10, 11, 50])
def test_turning_point_on_the_rows_branch(points):
    sc = TWO_BRANCHES_PRESSURE
    dense = adhfit.simulate(**sc, points=1001)
    frame = dense.frame
    stage, p = frame["stage"].to_numpy(), frame["p"].to_numpy()
    end = np.flatnonzero(stage == "making_contact")[-1]
    # independent of the summary: on 1001 rows the pressure falls as pinning starts, so the turning
    # point (the first minimum of p on the way out) is not the end of loading
    assert p[end + 1] < p[end]
    p_min_rows = p[end:].min()
    s = adhfit.simulate(**sc, points=points).summary
    assert s["turning_point"]["p"] < p[end]
    assert s["turning_point"]["p"] <= p_min_rows + 1e-12
    for q in ("f", "p", "a"):
        assert abs(s["turning_point"][q] - dense.summary["turning_point"][q]) < 1e-8
