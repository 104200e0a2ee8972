"""Issue 24 item 7, the slow tail: solver loops that repeated one failing evaluation to their limit.

The scene is the slowest history of the large-stretch stress run (seed 24, scene 981: pressure
control, no slip, a nearly flat substrate). Its delamination starts from the onset with a constant
predictor that lies outside the model; the first steps failed, each by a nested pressure solve of
60 outer iterations whose inner Newton, started at NaN, stepped "halfway back" to itself 60 times,
and the continuation retried the same step while the halved step still spanned the gap (11 identical
solves). These tests run the loops in Python (``py_func``, the compiled callees beneath them) and
count: no timing is asserted here (benchmarks/results/stress_domain_large-stretch.md has it).
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from adhfit.core import continuation, history, newton, solve
from adhfit.core.branches import DEL_NS
from adhfit.loading import A_END, _grids, _prepare

#: stress run seed 24, scene 981 (50 ms a history before; the median history takes 0.4 ms)
SLOW = dict(control="pressure", slip="no-slip", d=0.36253722307889746, w=5.934437501012719,
            rs=25.18551583760682, a_max=0.4274671762310771, lambda0=2.0)


def _delamination_args(points=200):
    """The arguments with which the kernel follows this scene's no-slip delamination branch."""
    from adhfit.core.inflation import critical_pressure
    v, c, pc, end = _prepare(**SLOW, delta_max=None, p_max=None, p=None, points=points)
    d_fix, w, a_m = float(v["d"]), float(v["w"]), end[0]
    u_mc, u_pin, u_dl = _grids(points)
    err = np.full(5, math.nan)
    k_mc, out_mc, st = history._making_contact(True, c, 0.0, d_fix, float(critical_pressure(d_fix)),
                                               a_m * u_mc, err)
    assert st == history.H_OK
    L_m, kappa_m = out_mc[6, -1], k_mc[-1]
    lp, x_pin, out_pin, st = history._pinning(True, True, c, w, a_m, L_m, kappa_m, d_fix, u_pin, err)
    assert st == history.H_OK
    onset = out_pin[:, -1]
    a_on = onset[0]
    pull_off = math.sqrt(2.0 * w) / (2.0 * (abs(onset[2]) + c + 1.0))
    a_end = min(A_END * a_m, 0.1 * pull_off)
    targets = a_end + (a_on - a_end) * u_dl
    return (DEL_NS, True, a_on, targets, x_pin[-1], onset[2], c, w, a_m, L_m, d_fix,
            continuation.SCALE_LOG, continuation.max_steps(targets.size), True)


@pytest.fixture(scope="module")
def first_steps():
    """Every solve the continuation asks for on this branch, in order (Python loop, compiled solves)."""
    calls = []
    compiled = continuation.solve_one

    def counting(*args):
        res = compiled(*args)
        calls.append((args, res))
        return res

    args = _delamination_args()
    mp = pytest.MonkeyPatch()
    mp.setattr(continuation, "solve_one", counting)
    try:
        res = continuation.follow.py_func(*args)
    finally:
        mp.undo()
    return args, calls, res


def test_the_continuation_never_repeats_a_failed_solve(first_steps):
    args, calls, res = first_steps
    failed = [a for a, r in calls if r[2] != newton.OK]
    assert failed, "the scene's first delamination steps fail (the situation under test)"
    for (a, r), (b, _) in zip(calls, calls[1:]):
        assert not (r[2] != newton.OK and a == b), "a failed solve asked for again unchanged"
    # and the Python loop is the compiled one: the same branch, to the bit
    ref = continuation.follow(*args)
    assert res[0] == ref[0] == continuation.F_OK and res[1] == ref[1] == args[3].size
    np.testing.assert_array_equal(res[2], ref[2])
    np.testing.assert_array_equal(res[3], ref[3])
    np.testing.assert_array_equal(res[8], ref[8])


def test_a_nested_pressure_solve_that_cannot_move_stops_at_once(first_steps, monkeypatch):
    args, calls, _ = first_steps
    (code, pressure, loc, k, xg, c, w, a_m, L_m, d_fix, short), res = next(
        (a, r) for a, r in calls if r[2] != newton.OK)
    inner = []
    compiled = solve.inner_one
    monkeypatch.setattr(solve, "inner_one", lambda *a: inner.append(a) or compiled(*a))
    x, kappa, st = solve.pressure_one.py_func(code, loc, c, w, a_m, L_m, d_fix, k, xg, True, short)
    assert st == newton.FAIL_OUTER and math.isnan(x) and kappa == res[1]
    # no inner solution at the start and a NaN gap: every further iteration would repeat the first
    assert len(inner) == 1, len(inner)  # was 60 (MAXITER)


def test_newton_from_a_start_outside_the_model_fails_at_once(first_steps, monkeypatch):
    _, calls, _ = first_steps
    (code, _, loc, k, xg, c, w, a_m, L_m, _, _), _ = next((a, r) for a, r in calls if r[2] != newton.OK)
    z = newton.material_residual(code, complex(xg, 0.0), complex(k, 0.0), complex(loc, 0.0), c, w, a_m, L_m)
    assert not math.isfinite(z.real), "the predictor is outside the model (the situation under test)"
    steps = []
    compiled = newton.damped_step
    monkeypatch.setattr(newton, "damped_step", lambda *a: steps.append(a) or compiled(*a))
    x, st = newton._newton_free.py_func(code, k, loc, c, w, a_m, L_m, xg)
    assert st == newton.FAIL_INNER and math.isnan(x)
    assert len(steps) == 1, len(steps)  # was 60 (MAXITER)
    # the bracketed solve inner_one falls back to finds no root here either: the failure stands
    assert newton.inner_one(code, k, loc, c, w, a_m, L_m, xg, True)[1] != newton.OK
