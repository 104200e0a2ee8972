"""Continuation along a branch: from a solved state through target locators, with step control.

The physical state at a locator is the one connected to where the branch starts (at fixed G the
material condition can have a second root): :func:`follow` reaches every target by steps from the
last accepted state, each solved from a polynomial predictor, halving the step where a solve fails.
"""
from __future__ import annotations

import math

import numpy as np

from .branches import admissible, is_implicit, observe
from .jit import jit
from .solve import solve_one

__all__ = ["F_OK", "F_STALLED", "F_STEPS", "GAP_CLOSE", "SCALE_LINEAR", "SCALE_LOG", "SCALE_SQRT",
           "follow", "max_steps"]

F_OK, F_STALLED, F_STEPS = 0, 1, 2
#: a gap to the goal within this relative distance is closed in one step
GAP_CLOSE = 1e-12
#: steps above this fraction of the span solve with the nested pressure solve cut short
SHORT_UNTIL = 1e-8
#: step variables of follow: the locator, its logarithm, its square root
SCALE_LINEAR, SCALE_LOG, SCALE_SQRT = 0, 1, 2


@jit
def max_steps(n_targets):
    """Step budget of :func:`follow` through ``n_targets`` targets: each target takes at least one
    accepted step; 2000 more for the halvings and the path between targets."""
    return 2000 + 4 * n_targets


@jit
def _to_step(scale, loc):
    if scale == SCALE_LOG:
        return math.log(loc)
    if scale == SCALE_SQRT:
        return math.sqrt(loc)
    return loc


@jit
def _from_step(scale, s):
    if scale == SCALE_LOG:
        return math.exp(s)
    if scale == SCALE_SQRT:
        return s * s
    return s


@jit
def _predict(ss, xs, ks, m, s):
    """x, kappa at s extrapolated from the last accepted states (quadratic
    through three, linear through two, else the last one)."""
    if m > 2 and ss[m - 3] != ss[m - 2] and ss[m - 2] != ss[m - 1] and ss[m - 3] != ss[m - 1]:
        s0, s1, s2 = ss[m - 3], ss[m - 2], ss[m - 1]
        l0 = (s - s1) * (s - s2) / ((s0 - s1) * (s0 - s2))
        l1 = (s - s0) * (s - s2) / ((s1 - s0) * (s1 - s2))
        l2 = (s - s0) * (s - s1) / ((s2 - s0) * (s2 - s1))
        return (l0 * xs[m - 3] + l1 * xs[m - 2] + l2 * xs[m - 1],
                l0 * ks[m - 3] + l1 * ks[m - 2] + l2 * ks[m - 1])
    if m > 1 and ss[m - 1] != ss[m - 2]:
        r = (s - ss[m - 1]) / (ss[m - 1] - ss[m - 2])
        return xs[m - 1] + r * (xs[m - 1] - xs[m - 2]), ks[m - 1] + r * (ks[m - 1] - ks[m - 2])
    return xs[m - 1], ks[m - 1]


@jit
def follow(code, pressure, l0, targets, x0, k0, c, w, a_m, L_m, d_fix, scale, max_steps,
                  allow_end):
    """Follow a branch from locator ``l0`` (solved: x0, k0) through ``targets`` (in order).

    ``scale`` is the step variable: ``SCALE_LINEAR`` (the locator), ``SCALE_LOG`` (``log=True``) or
    ``SCALE_SQRT`` (``sqrt=True``).

    Returns
    -------
    status : int
        ``F_OK``, ``F_STALLED`` (the step fell below 1e-10 of the span) or ``F_STEPS``.
    n_out : int
        Targets reached (their x, kappa are ``out_x[:n_out]``, ``out_k[:n_out]``).
    out_x, out_k : ndarray
    path_l, path_x, path_k : ndarray
        Every accepted step (locators, x, kappa); x NaN on explicit branches.
    last : ndarray, shape (7,)
        Observables a, alpha, p, d, f, G, J0 of the last accepted step (NaN if none).
    out_obs : ndarray, shape (7, n_targets)
        The same at the targets reached (``out_obs[:, :n_out]``).
    """
    implicit = is_implicit(code)
    n_t = targets.size
    cap = max_steps + 2
    ss, xs, ks = np.empty(cap), np.empty(cap), np.empty(cap)
    out_x, out_k = np.empty(n_t), np.empty(n_t)
    out_obs = np.empty((7, n_t))
    ss[0] = _to_step(scale, l0)
    xs[0] = x0 if implicit else math.nan
    ks[0] = k0
    m = 1
    last = _to_step(scale, targets[n_t - 1])
    span = abs(last - ss[0])
    if span == 0.0:
        span = 1.0
    h = span / 16.0
    i, steps, n_out, status = 0, 0, 0, F_OK
    obs = np.empty(7)
    last_obs = np.full(7, math.nan)
    while i < n_t:
        steps += 1
        if steps > max_steps:
            status = F_STEPS
            break
        goal = _to_step(scale, targets[i])
        gap = goal - ss[m - 1]
        # a gap within rounding of the goal is closed in one step (a step below the spacing of
        # floats would not move)
        near = abs(gap) <= h or abs(gap) <= GAP_CLOSE * (1.0 + abs(goal))
        s_new = goal if near else ss[m - 1] + math.copysign(h, gap)
        xg, kg = _predict(ss, xs, ks, m, s_new)
        loc = _from_step(scale, s_new)
        # a failed step is halved, so the nested pressure solve is cut short (solve.FALLBACK_ITER)
        # while the step is long and the predictor quadratic; the first steps of a branch (a poor
        # predictor) and steps halved to SHORT_UNTIL of the span run it in full
        short = m > 2 and h > SHORT_UNTIL * span
        x, k, st = solve_one(code, pressure, loc, kg if pressure else k0, xg, c, w, a_m, L_m, d_fix,
                             short)
        good = st == 0
        if good:
            # every observable finite: at the Case I limit J0 can be finite where the gap is not
            good = admissible(observe(code, x, k, loc, c, w, a_m, obs), obs)
        if not good:
            # halved until the step changes: a step that closed the gap to the goal stays that
            # step while the halved h still spans the gap, and would be solved again as it was
            # and fail again (from the first state of a stage, up to ~25 times over); each
            # skipped repeat still counts as a step
            ended = False
            while True:
                h *= 0.5
                if h < 1e-10 * span:
                    if not (allow_end and m > 1):
                        status = F_STALLED
                    ended = True
                    break
                near = abs(gap) <= h or abs(gap) <= GAP_CLOSE * (1.0 + abs(goal))
                if ((goal if near else ss[m - 1] + math.copysign(h, gap)) != s_new
                        or (m > 2 and h > SHORT_UNTIL * span) != short):
                    break
                steps += 1
                if steps > max_steps:
                    status = F_STEPS
                    ended = True
                    break
            if ended:
                break
            continue
        ss[m], xs[m], ks[m] = s_new, (x if implicit else math.nan), k
        last_obs[:] = obs
        m += 1
        if s_new == goal:
            out_x[n_out], out_k[n_out] = xs[m - 1], ks[m - 1]
            out_obs[:, n_out] = obs
            n_out += 1
            i += 1
        h = min(1.6 * h, span / 8.0)
    path_l = np.empty(m)
    for j in range(m):
        path_l[j] = _from_step(scale, ss[j])
    return status, n_out, out_x, out_k, path_l, xs[:m].copy(), ks[:m].copy(), last_obs, out_obs
