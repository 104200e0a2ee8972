"""The extremum of an observable along a branch between two locators (the turning point of the
control variable, the force minimum), located to ~1e-15 in the locator by a root of its exact
derivative along the branch (complex steps through the solves), Brent's method as in scipy's brentq.

A state inside the bracket is solved from predictors interpolated on the rows, else by continuation
from the nearest row (a coarse grid's predictors can be too far off). An end of the bracket that
does not solve (the no-slip delamination branch's own end, alpha -> 0, where the unknown meets its
bound) is approached from inside until the slope changes sign or the states stop solving, so that
an extremum between the last row and the branch end is located whatever the row grid (issue 24).
"""
from __future__ import annotations

import math

import numpy as np

from .branches import DEL_FR, DEL_NS, PIN_NS, admissible, is_implicit, observe, state
from .continuation import F_OK, SCALE_LINEAR, SCALE_LOG, SCALE_SQRT, follow
from .jit import jit
from .newton import STEP
from .solve import derivative_row, solve_one

__all__ = ["E_OK", "E_SOLVE", "E_SEARCH", "E_NOCONV", "BRENT_XTOL", "BRENT_RTOL", "BRENT_MAXITER",
           "END_PROBES", "ROOT_TOL", "extremum"]

E_OK, E_SOLVE, E_SEARCH, E_NOCONV = 0, 1, 2, 3
#: the root search's tolerances (brentq's xtol, rtol and maxiter)
BRENT_XTOL = 1e-15
BRENT_RTOL = 4 * 2.220446049250313e-16
BRENT_MAXITER = 200
#: probes toward an end of the bracket that does not solve, at 1/2, 1/4, ... of the way left (2^-30
#: of a row spacing is far below the 1e-8 the summary values are held to)
END_PROBES = 30
#: on the no-slip delamination branch next to its own end, a root of the slope is kept over a point
#: better by at most this (relative): the states there differ in value by their rounding only
ROOT_TOL = 1e-11
#: step budget of the continuation that solves a state whose predictor failed (a row spacing away at
#: most: a few steps where the branch is there, and no long stall where it is not)
FALLBACK_STEPS = 24


@jit
def _solve_at(code, pressure, loc, rl, rx, rk, kappa, c, w, a_m, L_m, d_fix, fallback=True):
    """The state at ``loc`` from predictors interpolated on the rows (rl, rx, rk), else (``fallback``)
    by continuation from the nearest rows."""
    kg = np.interp(loc, rl, rk) if pressure else kappa
    xg = np.interp(loc, rl, rx)
    x, k, st = solve_one(code, pressure, loc, kg, xg, c, w, a_m, L_m, d_fix)
    if st == 0 or not fallback:
        return x, k, st
    # the predictor was too far off (a coarse grid): continuation from the nearest rows, in the
    # stage's own step variable (G from 0 in sqrt(G), a radius in log a)
    if code == PIN_NS:
        scale = SCALE_SQRT
    elif code == DEL_NS or code == DEL_FR:
        scale = SCALE_LOG
    else:
        scale = SCALE_LINEAR
    order = np.argsort(np.abs(rl - loc))
    for q in range(min(2, rl.size)):
        j = order[q]
        if rl[j] == loc or (is_implicit(code) and not math.isfinite(rx[j])):
            continue
        res = follow(code, pressure, rl[j], np.array([loc]), rx[j], rk[j] if pressure else kappa, c,
                     w, a_m, L_m, d_fix, scale, FALLBACK_STEPS, False)
        if res[0] == F_OK and res[1] == 1:
            return res[2][0], res[3][0], 0
    return x, k, st


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
def _toward(code, pressure, good, s_good, bad, rl, rx, rk, kappa, c, w, a_m, L_m, d_fix, key, sign,
            pts, slopes, vals, n):
    """Probes from ``good`` (finite slope ``s_good``) toward ``bad`` (an end whose slope is not
    finite), at 1/2, 1/4, ... of the way left, appended to (pts, slopes, vals) from ``n``: they stop
    at the first slope of the other sign (an extremum between the last two) or the first state that
    does not solve. Returns the new count."""
    obs = np.empty(7)
    for q in range(1, END_PROBES + 1):
        loc = bad + (good - bad) * 0.5 ** q
        if loc == bad:
            break
        v, s = _probe(code, pressure, loc, rl, rx, rk, kappa, c, w, a_m, L_m, d_fix, key, sign, obs)
        if not math.isfinite(s):
            break
        pts[n], slopes[n], vals[n] = loc, s, v
        n += 1
        if s * s_good < 0:
            break
    return n


@jit
def extremum(code, pressure, lo, hi, mid, rl, rx, rk, kappa, c, w, a_m, L_m, d_fix, key, sign,
             xtol, rtol, maxiter, open_lo=False):
    """The state in [lo, hi] where ``sign * obs[key]`` is largest: a root of the slope, or an end.

    The slope is taken at lo, hi and ``mid`` (the best row inside, when lo < mid < hi; NaN for none);
    an end without a finite slope is approached from its neighbour (:func:`_toward`), and so is
    ``lo`` when ``open_lo`` (the no-slip delamination branch's own end, a fold in the locator a,
    where the slope's sign is not to be trusted: seed 7 had it the wrong way); every pair of
    neighbouring points whose slopes differ in sign is searched (Brent), and the best state found
    is kept.

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
        cap = 3 + 2 * END_PROBES
        pts, slopes, vals = np.empty(cap), np.empty(cap), np.empty(cap)
        v_best, s_lo = _probe(code, pressure, lo, rl, rx, rk, kappa, c, w, a_m, L_m, d_fix, key,
                              sign, best_obs)
        pts[0], slopes[0], vals[0] = lo, (math.nan if open_lo else s_lo), v_best
        n = 1
        if lo < mid < hi:
            v, s = _probe(code, pressure, mid, rl, rx, rk, kappa, c, w, a_m, L_m, d_fix, key, sign,
                          obs)
            if v > v_best:
                best, v_best = mid, v
                best_obs[:] = obs
            pts[n], slopes[n], vals[n] = mid, s, v
            n += 1
        v, s_hi = _probe(code, pressure, hi, rl, rx, rk, kappa, c, w, a_m, L_m, d_fix, key, sign,
                         obs)
        if v > v_best:
            best, v_best = hi, v
            best_obs[:] = obs
        pts[n], slopes[n], vals[n] = hi, s_hi, v
        n += 1
        n_main = n
        # an end whose slope is not finite (its state does not solve): approached from inside
        if not math.isfinite(slopes[0]) and math.isfinite(slopes[1]):
            n = _toward(code, pressure, pts[1], slopes[1], pts[0], rl, rx, rk, kappa, c, w, a_m,
                        L_m, d_fix, key, sign, pts, slopes, vals, n)
        if not math.isfinite(slopes[n_main - 1]) and math.isfinite(slopes[n_main - 2]):
            n = _toward(code, pressure, pts[n_main - 2], slopes[n_main - 2], pts[n_main - 1], rl, rx,
                        rk, kappa, c, w, a_m, L_m, d_fix, key, sign, pts, slopes, vals, n)
        order = np.argsort(pts[:n])
        # next to the no-slip delamination end (a fold in the locator) the states' values carry a
        # rounding of ~1e-11 (seed 7): a probe toward that end is kept over the bracket's points only
        # when better beyond it, and a root of the slope replaces a row within it. Elsewhere the
        # comparisons are exact (a tolerance there moved fits of frictionless curves)
        tol = ROOT_TOL * (1.0 + abs(v_best)) if code == DEL_NS else 0.0
        for q in range(n):
            margin = 0.0 if order[q] < n_main else tol
            if vals[order[q]] > v_best + margin:
                best, v_best = pts[order[q]], vals[order[q]]
        soft = False  # the best is a row, not a probe toward the open end
        for q in range(n_main):
            if pts[q] == best and not (q == 0 and open_lo):
                soft = code == DEL_NS
        for q in range(n - 1):
            ia, ib = order[q], order[q + 1]
            sa, sb = slopes[ia], slopes[ib]
            if not (math.isfinite(sa) and math.isfinite(sb) and sa * sb < 0):
                continue
            root, st = _brent(code, pressure, pts[ia], pts[ib], sa, sb, rl, rx, rk, kappa, c, w, a_m,
                              L_m, d_fix, key, xtol, rtol, maxiter)
            if st != E_OK:
                return st, root, obs, False
            v = _value(code, pressure, root, rl, rx, rk, kappa, c, w, a_m, L_m, d_fix, key, sign,
                       obs)
            if v > v_best - (ROOT_TOL * (1.0 + abs(v_best)) if soft else 0.0):
                best, v_best, soft = root, v, False
        if v_best > -math.inf:  # admissible, so ok
            x, k, st = _solve_at(code, pressure, best, rl, rx, rk, kappa, c, w, a_m, L_m, d_fix)
            if st == 0:
                ok = observe(code, x, k, best, c, w, a_m, obs)
                return E_OK, best, obs, ok
    x, k, st = _solve_at(code, pressure, best, rl, rx, rk, kappa, c, w, a_m, L_m, d_fix,
                          lo != hi)
    if st != 0:
        return E_SOLVE, best, obs, False
    ok = observe(code, x, k, best, c, w, a_m, obs)
    return E_OK, best, obs, ok
