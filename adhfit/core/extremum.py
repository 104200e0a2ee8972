"""The extremum of an observable along a branch between two locators (the turning point of the
control variable, the force minimum), located to ~1e-15 in the locator by a root of its exact
derivative along the branch (complex steps through the solves), Brent's method as in scipy's brentq.
"""
from __future__ import annotations

import math

import numpy as np

from .branches import admissible, observe, state
from .jit import jit
from .newton import STEP
from .solve import derivative_row, solve_one

__all__ = ["E_OK", "E_SOLVE", "E_SEARCH", "E_NOCONV", "BRENT_XTOL", "BRENT_RTOL", "BRENT_MAXITER",
           "extremum"]

E_OK, E_SOLVE, E_SEARCH, E_NOCONV = 0, 1, 2, 3
#: the root search's tolerances (brentq's xtol, rtol and maxiter)
BRENT_XTOL = 1e-15
BRENT_RTOL = 4 * 2.220446049250313e-16
BRENT_MAXITER = 200


@jit
def _solve_at(code, pressure, loc, rl, rx, rk, kappa, c, w, a_m, L_m, d_fix):
    """The state at ``loc`` from predictors interpolated on the rows (rl, rx, rk)."""
    kg = np.interp(loc, rl, rk) if pressure else kappa
    xg = np.interp(loc, rl, rx)
    return solve_one(code, pressure, loc, kg, xg, c, w, a_m, L_m, d_fix)


@jit
def _slope_of(code, pressure, loc, x, k, c, w, a_m, L_m, key):
    """d(observable ``key``)/d(locator) at a solved state (:func:`.solve.derivative_row`)."""
    xc, kc = derivative_row(code, pressure, loc, x, k, c, w, a_m, L_m)
    if key == 2:
        return kc.imag / STEP
    a, alpha, d, f, G, j0, _ = state(code, xc, kc, complex(loc, STEP), c, w, a_m, True)
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


@jit
def _slope_at(code, pressure, loc, rl, rx, rk, kappa, c, w, a_m, L_m, d_fix, key):
    x, k, st = _solve_at(code, pressure, loc, rl, rx, rk, kappa, c, w, a_m, L_m, d_fix)
    if st != 0:
        return math.nan, st
    return _slope_of(code, pressure, loc, x, k, c, w, a_m, L_m, key), 0


@jit
def _value(code, pressure, loc, rl, rx, rk, kappa, c, w, a_m, L_m, d_fix, key, sign, obs):
    """sign * key at the solved state, -inf where it does not solve or is not admissible."""
    x, k, st = _solve_at(code, pressure, loc, rl, rx, rk, kappa, c, w, a_m, L_m, d_fix)
    if st != 0:
        return -math.inf
    ok = observe(code, x, k, loc, c, w, a_m, obs)
    return sign * obs[key] if admissible(ok, obs) else -math.inf


@jit
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


@jit
def _probe(code, pressure, loc, rl, rx, rk, kappa, c, w, a_m, L_m, d_fix, key, sign, obs):
    """:func:`_value` and :func:`_slope_at` at ``loc`` from one solve: (value, slope); the
    observables go to ``obs``."""
    x, k, st = _solve_at(code, pressure, loc, rl, rx, rk, kappa, c, w, a_m, L_m, d_fix)
    if st != 0:
        return -math.inf, math.nan
    ok = observe(code, x, k, loc, c, w, a_m, obs)
    v = sign * obs[key] if admissible(ok, obs) else -math.inf
    return v, _slope_of(code, pressure, loc, x, k, c, w, a_m, L_m, key)


@jit
def extremum(code, pressure, lo, hi, rl, rx, rk, kappa, c, w, a_m, L_m, d_fix, key, sign,
                    xtol, rtol, maxiter):
    """The state in [lo, hi] where ``sign * obs[key]`` is largest: a root of the slope, or an end.

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
        # each candidate is solved once; the best one's observables are kept
        best_obs = np.empty(7)
        v_best, s_lo = _probe(code, pressure, lo, rl, rx, rk, kappa, c, w, a_m, L_m, d_fix, key,
                              sign, best_obs)
        v, s_hi = _probe(code, pressure, hi, rl, rx, rk, kappa, c, w, a_m, L_m, d_fix, key, sign,
                         obs)
        if v > v_best:
            best, v_best = hi, v
            best_obs[:] = obs
        if math.isfinite(s_lo) and math.isfinite(s_hi) and s_lo * s_hi < 0:
            root, st = _brent(code, pressure, lo, hi, s_lo, s_hi, rl, rx, rk, kappa, c, w, a_m, L_m,
                              d_fix, key, xtol, rtol, maxiter)
            if st != E_OK:
                return st, root, obs, False
            v = _value(code, pressure, root, rl, rx, rk, kappa, c, w, a_m, L_m, d_fix, key, sign,
                       obs)
            if v > v_best:
                best, v_best = root, v
                best_obs[:] = obs
        if v_best > -math.inf:  # admissible, so ok
            return E_OK, best, best_obs, True
    x, k, st = _solve_at(code, pressure, best, rl, rx, rk, kappa, c, w, a_m, L_m, d_fix)
    if st != 0:
        return E_SOLVE, best, obs, False
    ok = observe(code, x, k, best, c, w, a_m, obs)
    return E_OK, best, obs, ok
