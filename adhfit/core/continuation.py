"""Continuation along a branch: from a solved state through target locators, with step control.

The physical state at a locator is the one connected to where the branch starts (at fixed G the
material condition can have a second root): :func:`follow` reaches every target by steps from the
last accepted state, each solved from a polynomial predictor, halving the step where a solve fails.
"""
from __future__ import annotations

import math

import numpy as np

from .branches import PIN_NS, admissible, clamp_margin, is_implicit, observe
from .jit import jit
from .newton import STEP
from .solve import derivative_row, solve_one

__all__ = ["F_OK", "F_STALLED", "F_STEPS", "GAP_CLOSE", "JUMP", "JUMP_FLOOR", "SCALE_LINEAR", "SCALE_LOG",
           "SCALE_SQRT", "follow", "max_steps"]

F_OK, F_STALLED, F_STEPS = 0, 1, 2
#: a gap to the goal within this relative distance is closed in one step
GAP_CLOSE = 1e-12
#: steps above this fraction of the span solve with the nested pressure solve cut short
SHORT_UNTIL = 1e-8
#: step variables of follow: the locator, its logarithm, its square root
SCALE_LINEAR, SCALE_LOG, SCALE_SQRT = 0, 1, 2
#: a solved step whose root lies farther from its predictor than JUMP times the change the predictor
#: made (plus JUMP_FLOOR, relative) is taken for another branch's root and halved. Near the start of
#: a frictionless pinning branch a second branch can run close by (issue 24, stress scene 0.283:
#: under pressure control at rs = 0.040, a_max = 0.035 a branch from a = 0.0355 at alpha = 0 that
#: ends on the sphere's equator); a first step of span/16 from a constant predictor converged onto
#: it, so the history depended on the row grid. On a smooth branch the predictor's error is O(h^2)
#: of the change (linear, quadratic predictor), so the test only shortens steps where the branch
#: bends within one step.
JUMP = 0.5
JUMP_FLOOR = 1e-9


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
def _tangent(code, pressure, scale, l0, x0, k0, c, w, a_m, L_m):
    """(dx/ds, dkappa/ds) at the solved start of a branch in the step variable s, by complex steps
    (:func:`.solve.derivative_row`); NaN where not finite or not defined (no-slip pinning at G = 0,
    where x is smooth in sqrt(G) only)."""
    if code == PIN_NS and l0 == 0.0:
        return math.nan, math.nan
    xc, kc = derivative_row(code, pressure, l0, x0, k0, c, w, a_m, L_m)
    if scale == SCALE_LOG:
        dl = l0
    elif scale == SCALE_SQRT:
        dl = 2.0 * math.sqrt(l0)
    else:
        dl = 1.0
    tx = xc.imag / STEP * dl if is_implicit(code) else 0.0
    tk = kc.imag / STEP * dl if pressure else 0.0
    if not (math.isfinite(tx) and math.isfinite(tk)) or (tx == 0.0 and tk == 0.0):
        return math.nan, math.nan
    return tx, tk


@jit
def _near(implicit, pressure, x, k, xp, kp, x_last, k_last):
    """Whether a solved state (x, k) lies within JUMP of the change the prediction (xp, kp) made
    from the last state (plus JUMP_FLOOR); x and kappa weighted by 1/(1 + |.|)."""
    wx = 1.0 / (1.0 + abs(x)) if implicit else 0.0
    wk = 1.0 / (1.0 + abs(k)) if pressure else 0.0
    pred = max(abs(xp - x_last) * wx if implicit else 0.0, abs(kp - k_last) * wk)
    corr = max(abs(x - xp) * wx if implicit else 0.0, abs(k - kp) * wk)
    return corr <= JUMP * pred + JUMP_FLOOR


@jit
def _dips(s0, m0, s1, m1, s2, m2):
    """Whether the parabola through three (step variable, clamp margin) points, the last two the
    step just taken (s1 -> s2), falls below 0 between s1 and s2: the branch would leave Case I inside
    the step (the clamp tangent past vertical) though both its ends are inside the model. A long step
    can pass over such a gap (stress seeds 3 and 5: histories at 10 rows through states past
    vertical that 50 and 1001 rows end at as a DomainError)."""
    d01, d12 = (m1 - m0) / (s1 - s0), (m2 - m1) / (s2 - s1)
    curv = (d12 - d01) / (s2 - s0)
    if not curv > 0.0:
        return False
    # the parabola m0 + d01 (s - s0) + curv (s - s0)(s - s1), about s1: m1 + slope1 (s - s1) + curv (s - s1)^2
    slope1 = d01 + curv * (s1 - s0)
    sv = s1 - slope1 / (2.0 * curv)
    if not (min(s1, s2) < sv < max(s1, s2)):
        return False
    return m1 + slope1 * (sv - s1) + curv * (sv - s1) ** 2 < 0.0


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
    ss, xs, ks, mgs = np.empty(cap), np.empty(cap), np.empty(cap), np.empty(cap)
    out_x, out_k = np.empty(n_t), np.empty(n_t)
    out_obs = np.empty((7, n_t))
    ss[0] = _to_step(scale, l0)
    xs[0] = x0 if implicit else math.nan
    ks[0] = k0
    mgs[0] = clamp_margin(code, x0 if implicit else 0.0, k0, l0, c, w, a_m)
    m = 1
    last = _to_step(scale, targets[n_t - 1])
    span = abs(last - ss[0])
    if span == 0.0:
        span = 1.0
    h = span / 16.0
    # the tangent at the start: the first step (from the start itself) is checked against it;
    # later, the tangent at the last state (t_m: the state count it was taken at)
    tx, tk = _tangent(code, pressure, scale, l0, xs[0], k0, c, w, a_m, L_m)
    t_m = 1
    solved = implicit or pressure
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
        if good and solved:
            # the step must not pass over a stretch outside Case I: a parabola in the step variable
            # through the clamp margins of the last two states and this one (the first step: of the
            # start, the step's midpoint, solved for it, and this one)
            mg = clamp_margin(code, x, k, loc, c, w, a_m)
            if m > 1:
                good = not _dips(ss[m - 2], mgs[m - 2], ss[m - 1], mgs[m - 1], s_new, mg)
            else:
                s_mid = 0.5 * (ss[0] + s_new)
                l_mid = _from_step(scale, s_mid)
                xm, km, stm = solve_one(code, pressure, l_mid, 0.5 * (ks[0] + k) if pressure else k0,
                                        0.5 * (xs[0] + x) if implicit else 0.0, c, w, a_m, L_m, d_fix)
                # no state at the midpoint: the step's ends lie on two branches (stress seed 5: no-slip
                # pinning from t = 1 meets the Case I limit at G = 0.0054, and a first step to G =
                # 0.03 landed on the branch with t = 0.76)
                good = stm == 0
                if good:
                    mg_mid = clamp_margin(code, xm, km, l_mid, c, w, a_m)
                    good = mg_mid >= 0.0 and not _dips(ss[0], mgs[0], s_mid, mg_mid, s_new, mg)
        if good and solved and m > 1:
            # the root must be the one the predictor points at, not another branch's: held to the
            # polynomial predictor, else to the tangent at the last state (a polynomial through
            # states before a bend errs in proportion to the step, however short)
            good = _near(implicit, pressure, x, k, xg, kg, xs[m - 1], ks[m - 1])
            if not good:
                if t_m != m:
                    tx, tk = _tangent(code, pressure, scale, _from_step(scale, ss[m - 1]), xs[m - 1],
                                      ks[m - 1], c, w, a_m, L_m)
                    t_m = m
                good = math.isfinite(tx) and _near(implicit, pressure, x, k,
                                                   xs[m - 1] + tx * (s_new - ss[m - 1]),
                                                   ks[m - 1] + tk * (s_new - ss[m - 1]),
                                                   xs[m - 1], ks[m - 1])
        elif good and solved and math.isfinite(tx):
            # the first step, solved from the start itself: held to the tangent's prediction
            good = _near(implicit, pressure, x, k, xs[0] + tx * (s_new - ss[0]),
                         ks[0] + tk * (s_new - ss[0]), xs[0], ks[0])
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
        mgs[m] = clamp_margin(code, x, k, loc, c, w, a_m)
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
