"""Compiled (numba) continuation and extremum refinement: :mod:`.continuation` as single kernel calls.

A history follows branches step by step and refines two extrema by root-finding on an exact
derivative; in Python each of those steps is a few backend calls (~10-20 us of overhead each, one
state per call). Here each loop is one call. The semantics are those of :mod:`.continuation` line by
line (same step control, same predictors, same admissibility tests, scipy's Brent method transcribed);
only the floating-point order of operations differs. Kernels never raise: they return a status and
the Python layer (:mod:`.backend`) raises :class:`~adhfit.errors.ConvergenceError`.

Dimensionless throughout (DESIGN.md A1).
"""
from __future__ import annotations

import math

import numpy as np

from .compiled import (STEP, _derivative_row, _implicit, _jit, _state, solve_batch)

__all__ = ["follow_kernel", "extremum_kernel", "F_OK", "F_STALLED", "F_STEPS", "E_OK", "E_SOLVE",
           "E_SEARCH", "E_NOCONV", "KEY_CODES"]

F_OK, F_STALLED, F_STEPS = 0, 1, 2
E_OK, E_SOLVE, E_SEARCH, E_NOCONV = 0, 1, 2, 3
#: rows of an observation vector (as in compiled.evaluate_batch)
KEY_CODES = {"a": 0, "alpha": 1, "p": 2, "d": 3, "f": 4, "G": 5, "J0": 6}


@_jit
def _solve_one(code, pressure, loc, k, xg, c, w, a_m, L_m, d_fix):
    """One state at ``loc``: (x, kappa, status); kappa fixed at ``k`` or solved from the gap from ``k``."""
    xs, ks, status = solve_batch(code, pressure, np.array([loc]), np.array([k]), np.array([xg]),
                                 _implicit(code), c, w, a_m, L_m, d_fix)
    return xs[0], ks[0], status[0]


@_jit
def _observe(code, x, k, loc, c, w, a_m, out):
    """Observables a, alpha, p, d, f, G, J0 of one real state into ``out``; returns ``ok``."""
    a, alpha, d, f, G, j0, ok = _state(code, x, k, loc, c, w, a_m, True)
    out[0], out[1], out[2], out[3], out[4], out[5], out[6] = a, alpha, k, d, f, G, j0
    return ok


@_jit
def _admissible(ok, out):
    """ok and a, alpha, p, d, f, G finite (continuation.extremum's test)."""
    if not ok:
        return False
    for j in range(6):
        if not math.isfinite(out[j]):
            return False
    return True


@_jit
def follow_kernel(code, pressure, l0, targets, x0, k0, c, w, a_m, L_m, d_fix, log, max_steps,
                  allow_end):
    """continuation.follow in one call.

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
    """
    implicit = _implicit(code)
    n_t = targets.size
    cap = max_steps + 2
    ss, xs, ks = np.empty(cap), np.empty(cap), np.empty(cap)
    out_x, out_k = np.empty(n_t), np.empty(n_t)
    ss[0] = math.log(l0) if log else l0
    xs[0] = x0 if implicit else math.nan
    ks[0] = k0
    m = 1
    last = math.log(targets[n_t - 1]) if log else targets[n_t - 1]
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
        goal = math.log(targets[i]) if log else targets[i]
        gap = goal - ss[m - 1]
        s_new = goal if abs(gap) <= h else ss[m - 1] + math.copysign(h, gap)
        if m > 1 and ss[m - 1] != ss[m - 2]:
            r = (s_new - ss[m - 1]) / (ss[m - 1] - ss[m - 2])
            xg, kg = xs[m - 1] + r * (xs[m - 1] - xs[m - 2]), ks[m - 1] + r * (ks[m - 1] - ks[m - 2])
        else:
            xg, kg = xs[m - 1], ks[m - 1]
        loc = math.exp(s_new) if log else s_new
        x, k, st = _solve_one(code, pressure, loc, kg if pressure else k0, xg, c, w, a_m, L_m, d_fix)
        good = st == 0
        if good:
            good = _observe(code, x, k, loc, c, w, a_m, obs) and math.isfinite(obs[4])
        if not good:
            h *= 0.5
            if h < 1e-10 * span:
                if not (allow_end and m > 1):
                    status = F_STALLED
                break
            continue
        ss[m], xs[m], ks[m] = s_new, (x if implicit else math.nan), k
        last_obs[:] = obs
        m += 1
        if s_new == goal:
            out_x[n_out], out_k[n_out] = xs[m - 1], ks[m - 1]
            n_out += 1
            i += 1
        h = min(1.6 * h, span / 8.0)
    path_l = np.empty(m)
    for j in range(m):
        path_l[j] = math.exp(ss[j]) if log else ss[j]
    return status, n_out, out_x, out_k, path_l, xs[:m].copy(), ks[:m].copy(), last_obs


@_jit
def _solve_at(code, pressure, loc, rl, rx, rk, kappa, c, w, a_m, L_m, d_fix):
    """continuation.extremum's solve: predictors interpolated from the rows."""
    kg = np.interp(loc, rl, rk) if pressure else kappa
    xg = np.interp(loc, rl, rx)
    return _solve_one(code, pressure, loc, kg, xg, c, w, a_m, L_m, d_fix)


@_jit
def _slope_of(code, pressure, loc, x, k, c, w, a_m, L_m, key):
    """d(observable ``key``)/d(locator) at a solved state (compiled.derivative_batch, one row)."""
    xc, kc = _derivative_row(code, pressure, loc, x, k, c, w, a_m, L_m)
    if key == 2:
        return kc.imag / STEP
    a, alpha, d, f, G, j0, _ = _state(code, xc, kc, complex(loc, STEP), c, w, a_m, True)
    if key == 0:
        return a.imag / STEP
    if key == 1:
        return alpha.imag / STEP
    if key == 3:
        return d.imag / STEP
    if key == 4:
        return f.imag / STEP
    if key == 5:
        return G.imag / STEP
    return j0.imag / STEP


@_jit
def _slope_at(code, pressure, loc, rl, rx, rk, kappa, c, w, a_m, L_m, d_fix, key):
    x, k, st = _solve_at(code, pressure, loc, rl, rx, rk, kappa, c, w, a_m, L_m, d_fix)
    if st != 0:
        return math.nan, st
    return _slope_of(code, pressure, loc, x, k, c, w, a_m, L_m, key), 0


@_jit
def _value(code, pressure, loc, rl, rx, rk, kappa, c, w, a_m, L_m, d_fix, key, sign, obs):
    """sign * key at the solved state, -inf where it does not solve or is not admissible."""
    x, k, st = _solve_at(code, pressure, loc, rl, rx, rk, kappa, c, w, a_m, L_m, d_fix)
    if st != 0:
        return -math.inf
    ok = _observe(code, x, k, loc, c, w, a_m, obs)
    return sign * obs[key] if _admissible(ok, obs) else -math.inf


@_jit
def _brent(code, pressure, xa, xb, fa, fb, rl, rx, rk, kappa, c, w, a_m, L_m, d_fix, key,
           xtol, rtol, maxiter):
    """scipy.optimize.brentq (scipy/optimize/Zeros/brentq.c) on the slope: (root, status)."""
    xpre, xcur, fpre, fcur = xa, xb, fa, fb
    xblk, fblk, spre, scur = 0.0, 0.0, 0.0, 0.0
    if fpre == 0:
        return xpre, E_OK
    if fcur == 0:
        return xcur, E_OK
    for _ in range(maxiter):
        if fpre != 0 and fcur != 0 and (math.copysign(1.0, fpre) != math.copysign(1.0, fcur)):
            xblk, fblk = xpre, fpre
            spre = scur = xcur - xpre
        if abs(fblk) < abs(fcur):
            xpre, xcur, xblk = xcur, xblk, xcur
            fpre, fcur, fblk = fcur, fblk, fcur
        delta = (xtol + rtol * abs(xcur)) / 2
        sbis = (xblk - xcur) / 2
        if fcur == 0 or abs(sbis) < delta:
            return xcur, E_OK
        if abs(spre) > delta and abs(fcur) < abs(fpre):
            if xpre == xblk:
                stry = -fcur * (xcur - xpre) / (fcur - fpre)   # interpolate
            else:                                              # extrapolate
                dpre = (fpre - fcur) / (xpre - xcur)
                dblk = (fblk - fcur) / (xblk - xcur)
                stry = -fcur * (fblk * dblk - fpre * dpre) / (dblk * dpre * (fblk - fpre))
            if 2 * abs(stry) < min(abs(spre), 3 * abs(sbis) - delta):
                spre, scur = scur, stry                        # good short step
            else:
                spre, scur = sbis, sbis                        # bisect
        else:
            spre, scur = sbis, sbis
        xpre, fpre = xcur, fcur
        if abs(scur) > delta:
            xcur += scur
        else:
            xcur += delta if sbis > 0 else -delta
        fcur, st = _slope_at(code, pressure, xcur, rl, rx, rk, kappa, c, w, a_m, L_m, d_fix, key)
        if st != 0:
            return xcur, E_SEARCH
    return xcur, E_NOCONV


@_jit
def extremum_kernel(code, pressure, lo, hi, rl, rx, rk, kappa, c, w, a_m, L_m, d_fix, key, sign,
                    xtol, rtol, maxiter):
    """continuation.extremum in one call.

    Returns
    -------
    status : int
        ``E_OK``; ``E_SOLVE`` (the state at the chosen locator does not solve), ``E_SEARCH`` (a solve
        inside the root search failed) or ``E_NOCONV`` (the search did not converge).
    loc : float
    obs : ndarray, shape (7,)
        a, alpha, p, d, f, G, J0 at ``loc``.
    ok : bool
    """
    obs = np.empty(7)
    best = lo
    if lo != hi:
        s_lo, _ = _slope_at(code, pressure, lo, rl, rx, rk, kappa, c, w, a_m, L_m, d_fix, key)
        s_hi, _ = _slope_at(code, pressure, hi, rl, rx, rk, kappa, c, w, a_m, L_m, d_fix, key)
        v_best = _value(code, pressure, lo, rl, rx, rk, kappa, c, w, a_m, L_m, d_fix, key, sign, obs)
        v = _value(code, pressure, hi, rl, rx, rk, kappa, c, w, a_m, L_m, d_fix, key, sign, obs)
        if v > v_best:
            best, v_best = hi, v
        if math.isfinite(s_lo) and math.isfinite(s_hi) and s_lo * s_hi < 0:
            root, st = _brent(code, pressure, lo, hi, s_lo, s_hi, rl, rx, rk, kappa, c, w, a_m, L_m,
                              d_fix, key, xtol, rtol, maxiter)
            if st != E_OK:
                return st, root, obs, False
            v = _value(code, pressure, root, rl, rx, rk, kappa, c, w, a_m, L_m, d_fix, key, sign,
                       obs)
            if v > v_best:
                best = root
    x, k, st = _solve_at(code, pressure, best, rl, rx, rk, kappa, c, w, a_m, L_m, d_fix)
    if st != 0:
        return E_SOLVE, best, obs, False
    ok = _observe(code, x, k, best, c, w, a_m, obs)
    return E_OK, best, obs, ok


@_jit
def solve_observe_batch(code, pressure, loc, kappa, x0, has_x0, c, w, a_m, L_m, d_fix):
    """compiled.solve_batch followed by compiled.evaluate_batch at the solved states (one call).

    Returns
    -------
    x, kappa, status : as solve_batch
    out, ok : as evaluate_batch (meaningless where status is not OK)
    bad : int
        First row outside the model or with a non-finite a, alpha, p, d, f, G (compiled.first_bad);
        -1 if none.
    """
    xs, ks, status = solve_batch(code, pressure, loc, kappa, x0, has_x0, c, w, a_m, L_m, d_fix)
    n = loc.size
    out = np.empty((7, n))
    ok = np.zeros(n, dtype=np.bool_)
    implicit = _implicit(code)
    bad = -1
    for i in range(n):
        if status[i] != 0:
            out[:, i] = math.nan
            bad = i if bad < 0 else bad
            continue
        ok[i] = _observe(code, xs[i] if implicit else loc[i], ks[i], loc[i], c, w, a_m, out[:, i])
        if bad < 0 and not _admissible(ok[i], out[:, i]):
            bad = i
    return xs, ks, status, out, ok, bad
