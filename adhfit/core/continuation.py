"""Continuation along a branch and extremum refinement: the numpy reference of the compiled kernels.

Two loops that a history runs many times with one state each, written here once in plain Python on
top of :mod:`.branches` (the readable reference); :mod:`.compiled` runs the same loops as single
kernel calls (``follow_kernel``, ``extremum_kernel``) and :mod:`.backend` dispatches between them.

* :func:`follow` walks a branch from a solved state to target locators with step control (the
  predictor for every solve is a quadratic extrapolation of the last three accepted states).
* :func:`extremum` locates where an observable (or kappa) is extremal between two locators: the root
  of its exact complex-step derivative along the branch (scipy ``brentq``), compared with the ends;
  only admissible states compete.

Dimensionless throughout (DESIGN.md A1).
"""
from __future__ import annotations

import math

import numpy as np
from scipy.optimize import brentq

from ..errors import ConvergenceError
from .branches import Branch, Context, derivative, evaluate, solve_state

__all__ = ["follow", "extremum", "KEYS", "BRENT_XTOL", "BRENT_RTOL", "BRENT_MAXITER"]

#: the observables a solved state must have finite (its admissibility test besides ``ok``)
KEYS = ("a", "alpha", "p", "d", "f", "G")
BRENT_XTOL = 1e-15
BRENT_RTOL = 4 * np.finfo(float).eps
BRENT_MAXITER = 200
#: follow closes a remaining gap below GAP_CLOSE (1 + |goal|) in one step
GAP_CLOSE = 1e-12


def _solve_one(branch, loc, ctx, d_fix, k, xg):
    """One state at locator ``loc``: kappa fixed at ``k`` (d_fix None) or solved from the gap."""
    x0 = None if branch.target is None else np.array([xg])
    if d_fix is None:
        return solve_state(branch, np.array([loc]), ctx, kappa=np.array([k]), x0=x0)
    return solve_state(branch, np.array([loc]), ctx, d_fix=d_fix, kappa0=np.array([k]), x0=x0)


def _predict(ss, xs, ks, s):
    """x, kappa at s extrapolated from the accepted states: quadratic (Lagrange) through the last
    three, linear through the last two, else the last one."""
    if len(ss) > 2 and len({ss[-3], ss[-2], ss[-1]}) == 3:
        s0, s1, s2 = ss[-3:]
        l0 = (s - s1) * (s - s2) / ((s0 - s1) * (s0 - s2))
        l1 = (s - s0) * (s - s2) / ((s1 - s0) * (s1 - s2))
        l2 = (s - s0) * (s - s1) / ((s2 - s0) * (s2 - s1))
        return (l0 * xs[-3] + l1 * xs[-2] + l2 * xs[-1], l0 * ks[-3] + l1 * ks[-2] + l2 * ks[-1])
    if len(ss) > 1 and ss[-1] != ss[-2]:
        r = (s - ss[-1]) / (ss[-1] - ss[-2])
        return xs[-1] + r * (xs[-1] - xs[-2]), ks[-1] + r * (ks[-1] - ks[-2])
    return xs[-1], ks[-1]


def follow(branch: Branch, l0, targets, x0, k0, ctx: Context, d_fix, *, log: bool,
           sqrt: bool = False, max_steps: int = 2000, allow_end: bool = False):
    """Follow a branch from locator l0 (solved: x0, k0) through ``targets`` (continuation).

    ``d_fix`` None means displacement control (kappa fixed at k0); else kappa is solved from the gap.

    Steps are taken in the locator, in its logarithm (``log=True``, for the contact radius on the
    way to detachment) or in its square root (``sqrt=True``, for no-slip pinning located by G, where
    the state is smooth in sqrt(G) ~ alpha but not in G) and land exactly on every target; each state starts from a
    quadratic extrapolation of the last three (:func:`_predict`); a failed or out-of-domain step is
    halved.

    ``allow_end``: where the branch itself ends before the last target (no-slip delamination can),
    return the path up to its end (located to ~1e-10 of the span) instead of raising; the targets not
    reached are then missing from ``at_targets``.

    Returns
    -------
    at_targets, path : tuple of ndarray
        (locators, x, kappa) at the targets, in order, and at every accepted step (predictors for
        later solves); x is NaN on explicit branches.

    Raises
    ------
    ConvergenceError
        The step fell below 1e-10 of the span (the state leaves the model's domain), or more than
        ``max_steps`` steps were needed.
    """
    if log:
        fwd, back = np.log, np.exp
    elif sqrt:
        fwd, back = np.sqrt, np.square
    else:
        fwd = back = (lambda z: z)
    targets = np.atleast_1d(np.asarray(targets, float))
    ss = [fwd(l0)]
    xs, ks = [np.nan if x0 is None else float(x0)], [float(k0)]
    span = abs(fwd(targets[-1]) - ss[0]) or 1.0
    h = span / 16.0
    out, i, steps = [], 0, 0
    while i < targets.size:
        steps += 1
        if steps > max_steps:
            raise ConvergenceError(f"{branch.stage} ({branch.slip}): too many continuation steps",
                                   {"locator": float(back(ss[-1])), "d": d_fix, "w": ctx.w})
        goal = fwd(targets[i])
        gap_ = goal - ss[-1]
        # a gap within rounding of the goal is closed in one step (a step below the spacing of
        # floats would not move)
        near = abs(gap_) <= h or abs(gap_) <= GAP_CLOSE * (1.0 + abs(goal))
        s_new = goal if near else ss[-1] + np.sign(gap_) * h
        xg, kg = _predict(ss, xs, ks, s_new)
        loc = back(s_new)
        try:
            x, k = _solve_one(branch, loc, ctx, d_fix, k0 if d_fix is None else kg, xg)
            st = evaluate(branch, x, k, np.array([loc]), ctx)
            good = bool(st["ok"][0]) and bool(np.isfinite(np.real(st["f"][0])))
        except ConvergenceError:
            good = False
        if not good:
            h *= 0.5
            if h < 1e-10 * span:
                if allow_end and len(ss) > 1:
                    break
                raise ConvergenceError(f"{branch.stage} ({branch.slip}): continuation "
                                       f"stalled (the state leaves the model's domain)",
                                       {"locator": float(back(ss[-1])), "kappa": ks[-1], "d": d_fix,
                                        "w": ctx.w})
            continue
        ss.append(s_new)
        xs.append(np.nan if x is None else float(x[0]))
        ks.append(float(k[0]))
        if s_new == goal:
            out.append((targets[i], xs[-1], ks[-1]))
            i += 1
        h = min(1.6 * h, span / 8.0)
    path = (back(np.array(ss)), np.array(xs), np.array(ks))
    if not out:
        return (np.array([]), np.array([]), np.array([])), path
    return tuple(np.array(v) for v in zip(*out)), path


def extremum(branch: Branch, lo: float, hi: float, ctx: Context, d_fix, kappa, key: str,
             sign: float, rows):
    """The state in [lo, hi] where ``sign * key`` is largest: brentq on its exact derivative.

    Parameters
    ----------
    lo, hi : float
        Locators bounding the search (lo <= hi); lo == hi solves the state there.
    d_fix, kappa :
        Pressure control (``d_fix``, kappa solved) or displacement control (``kappa`` fixed).
    key : {"p", "d", "f"}
        The observable.
    rows : tuple of ndarray
        (locators, x, kappa) of solved rows around [lo, hi], sorted by locator: predictors by linear
        interpolation (x NaN on explicit branches).

    Returns
    -------
    loc, state : float, dict
        The locator and the solved state there (``evaluate`` output, ``ok`` included).

    Raises
    ------
    ConvergenceError
        A solve inside the search failed, or the search did not converge.
    """
    rl, rx, rk = rows
    pc = d_fix is not None

    def solve(loc):
        kg = float(np.interp(loc, rl, rk))
        return _solve_one(branch, loc, ctx, d_fix, kg if pc else kappa,
                          float(np.interp(loc, rl, rx)))

    def slope(loc):
        x, k = solve(loc)
        return float(derivative(branch, np.array([loc]), ctx, x, k, pressure_control=pc)[key][0])

    def state(loc):
        x, k = solve(loc)
        return evaluate(branch, x, k, np.array([loc]), ctx)

    def value(loc):
        try:
            st = state(loc)
        except ConvergenceError:
            return -math.inf
        v = sign * float(np.real(st[key][0]))
        finite = all(np.isfinite(np.real(st[k][0])) for k in KEYS)
        return v if (bool(st["ok"][0]) and finite) else -math.inf  # only admissible states compete

    if lo == hi:
        return lo, state(lo)

    def safe_slope(z):
        try:
            return slope(z)
        except ConvergenceError:
            return math.nan

    candidates = [lo, hi]
    s_lo, s_hi = safe_slope(lo), safe_slope(hi)
    if math.isfinite(s_lo) and math.isfinite(s_hi) and s_lo * s_hi < 0:
        try:
            candidates.append(brentq(slope, lo, hi, xtol=BRENT_XTOL, rtol=BRENT_RTOL,
                                     maxiter=BRENT_MAXITER))
        except RuntimeError as err:
            if isinstance(err, ConvergenceError):
                raise
            raise ConvergenceError(f"{branch.stage} ({branch.slip}): extremum of {key}: {err}",
                                   {"lo": lo, "hi": hi}) from None
    # the extremum of a smooth function on [lo, hi] is a stationary point or an end
    best = max(candidates, key=value)
    return best, state(best)
