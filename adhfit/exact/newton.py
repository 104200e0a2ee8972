"""Compiled Newton on the shooting unknowns of one exact-membrane state (the loop of solve.py).

The unknowns are indices into the value vector ``vals = (p, lc, rho_a, alpha, l1p)``; the residuals
are codes (``CLAMP``: r(beta) = 1, ``A``: contact radius, ``D``: gap, ``G``: G = w) with targets
``tg = (a, d, w)``. Newton with a forward-difference Jacobian reused between calls and updated by
Broyden's rule, recomputed when a step fails to halve the residual, then a backtracking line search:
the algorithm the Python loop had, without its per-shot interpreter cost. The contact field of the
last (lc, rho_a) is kept (a no-slip or pinned state does not change it between shots).

The Jacobian carried is that of all N_OUT observables (the residuals' rows among them), so that the
last Newton step can be taken without a shot (``_finish``): once a step has contracted the residual
well enough that the next one would leave it far below the tolerance, that next step is applied to
the unknowns and, linearly, to the observables. A continuation row then costs two shots (predictor,
one step) where it cost three.
"""
from __future__ import annotations

import math

import numpy as np

from . import kernels as K
from .jit import jit

CLAMP, A_RES, D_RES, G_RES = 0, 1, 2, 3
OUT_OF = np.array([0, 3, 1, 5])  # the observable each residual code reads: r_end, a, d, G
OK, BAD_START, BAD_JAC, SINGULAR, NO_LINE, NO_CONV = 0, 1, 2, 3, 4, 5
FINISH_SAFETY = 3.0  # the shotless last step (``_finish``) when SAFETY * (its predicted residual) < tol
FINISH_CAP = 30.0  # ... and the residual it starts from is below CAP * tol (the observables move by the
# step times the Broyden Jacobian's error: rows agree with re-solves to 1e-9 at tol 1e-10,
# tests/test_exact_history.py::test_rows_and_extrema_are_solved_states)


@jit
def shot_vals(edge, crv, beta, n, vals, cache):
    """Shoot at ``vals``; ``cache`` = (lc, rho_a, yc[4]) of the last contact field. NaN out: outside."""
    lc, rho_a, alpha, p = vals[1], max(vals[2], 0.0), vals[3], vals[0]
    l1 = vals[4] if edge == K.GIVEN else 0.0
    bad = lc <= 1.0 or vals[2] < 0.0 or vals[2] >= beta or (edge == K.GIVEN and l1 <= 0.0)
    bad = bad or (edge == K.FRICTIONLESS and not (0.0 <= alpha < 0.5 * math.pi))
    if bad:
        return np.full(K.N_OUT, np.nan)
    cache[6] += 1.0
    if rho_a == 0.0:
        o = K.shot(edge, p, crv, beta, n, lc, 0.0, alpha, l1, K.A, K.B, K.C)
    else:
        if not (cache[0] == lc and cache[1] == rho_a):
            yc = K.from_apex(K.CONTACT, lc, rho_a, n, crv, K.A, K.B, K.C)
            cache[0], cache[1] = lc, rho_a
            cache[2:6] = yc
        o = K.shot_from_edge(edge, p, crv, beta, n, cache[2:6], rho_a, alpha, l1, K.A, K.B, K.C)
    for i in (0, 1, 2, 4, 5):
        if not math.isfinite(o[i]):
            return np.full(K.N_OUT, np.nan)
    return o


@jit
def _residual(o, res, tg):
    out = np.empty(res.shape[0])
    for i in range(res.shape[0]):
        c = res[i]
        if c == CLAMP:
            out[i] = o[0] - 1.0
        elif c == A_RES:
            out[i] = o[3] - tg[0]
        elif c == D_RES:
            out[i] = o[1] - tg[1]
        else:
            out[i] = o[5] - tg[2]
    return out


@jit
def _at(edge, crv, beta, n, vals, unk, x, cache):
    v = vals.copy()
    for i in range(unk.shape[0]):
        v[unk[i]] = x[i]
    return shot_vals(edge, crv, beta, n, v, cache)


@jit
def _lin_solve(J, b):
    """Gaussian elimination with partial pivoting (k <= 3); ok False for a singular matrix."""
    k = b.shape[0]
    M = J.copy()
    y = b.copy()
    for c in range(k):
        piv = c
        for r in range(c + 1, k):
            if abs(M[r, c]) > abs(M[piv, c]):
                piv = r
        if not (abs(M[piv, c]) > 0.0) or not math.isfinite(M[piv, c]):
            return y, False
        if piv != c:
            for q in range(k):
                M[c, q], M[piv, q] = M[piv, q], M[c, q]
            y[c], y[piv] = y[piv], y[c]
        for r in range(c + 1, k):
            fct = M[r, c] / M[c, c]
            for q in range(c, k):
                M[r, q] -= fct * M[c, q]
            y[r] -= fct * y[c]
    for c in range(k - 1, -1, -1):
        acc = y[c]
        for q in range(c + 1, k):
            acc -= M[c, q] * y[q]
        y[c] = acc / M[c, c]
    return y, True


@jit
def _jacobian(edge, crv, beta, n, vals, unk, x, o0, cache):
    """Forward differences of all N_OUT observables in the unknowns (backward where the forward shot
    leaves the domain)."""
    k = x.shape[0]
    Jo = np.empty((K.N_OUT, k))
    for j in range(k):
        h = 1e-7 * max(1e-3, abs(x[j]))
        xp = x.copy()
        xp[j] += h
        o = _at(edge, crv, beta, n, vals, unk, xp, cache)
        if math.isnan(o[0]):
            xp[j] -= 2 * h
            h = -h
            o = _at(edge, crv, beta, n, vals, unk, xp, cache)
            if math.isnan(o[0]):
                return Jo, False
        Jo[:, j] = (o - o0) / h
    return Jo, True


@jit
def _rows(Jo, res):
    """The residuals' Jacobian: their observables' rows of ``Jo``."""
    J = np.empty((res.shape[0], Jo.shape[1]))
    for i in range(res.shape[0]):
        J[i] = Jo[OUT_OF[res[i]]]
    return J


@jit
def _line_search(edge, crv, beta, n, vals, unk, res, tg, x, dx, nrm, cache):
    lam = 1.0
    while lam > 1e-4:
        xn = x + lam * dx
        o = _at(edge, crv, beta, n, vals, unk, xn, cache)
        if not math.isnan(o[0]):
            rn = _residual(o, res, tg)
            if np.max(np.abs(rn)) < (1 - 1e-4 * lam) * nrm or nrm < 1e-9:
                return xn, o, rn, True
        lam *= 0.5
    return x, np.full(K.N_OUT, np.nan), np.full(res.shape[0], np.nan), False


@jit
def newton_packed(edge, crv, beta, n, vals, unk, res, tg, x0, J0, tol, max_iter):
    """``newton`` with its results in one array (status, shots, x[k], out[N_OUT], J[k*k]): one array
    to hand back to Python instead of three."""
    status, x, o, J, shots = newton(edge, crv, beta, n, vals, unk, res, tg, x0, J0, tol, max_iter)
    k = x.shape[0]
    out = np.empty(2 + k + K.N_OUT + J.size)
    out[0], out[1] = status, shots
    out[2:2 + k] = x
    out[2 + k:2 + k + K.N_OUT] = o
    out[2 + k + K.N_OUT:] = J.ravel()
    return out


@jit
def newton(edge, crv, beta, n, vals, unk, res, tg, x0, J0, tol, max_iter):
    """Solve the residuals for the unknowns from ``x0``; ``J0`` a Jacobian to start from (NaN: none).

    Returns (status, x, out, J, shots) with ``J`` the last Jacobian of the N_OUT observables (NaN when
    it should not be reused) and ``shots`` the number of shots taken.
    """
    cache = np.full(7, np.nan)
    return newton_cached(edge, crv, beta, n, vals, unk, res, tg, x0, J0, tol, max_iter, cache)


@jit
def newton_cached(edge, crv, beta, n, vals, unk, res, tg, x0, J0, tol, max_iter, cache):
    """``newton`` with the contact field's cache (see ``shot_vals``) kept by the caller: a no-slip
    pinning march reuses one contact field for all its rows. ``J0`` and the returned Jacobian are
    those of the N_OUT observables."""
    cache[6] = 0.0
    x = x0.copy()
    o = _at(edge, crv, beta, n, vals, unk, x, cache)
    if math.isnan(o[0]):
        return BAD_START, x, o, J0, cache[6]
    r = _residual(o, res, tg)
    Jo = J0.copy()
    have = not math.isnan(Jo[0, 0])
    fresh = False
    for _ in range(max_iter):
        nrm = np.max(np.abs(r))
        if nrm < tol:
            return OK, x, o, Jo, cache[6]
        if not have:
            Jo, good = _jacobian(edge, crv, beta, n, vals, unk, x, o, cache)
            if not good:
                return BAD_JAC, x, o, np.full(Jo.shape, np.nan), cache[6]
            have, fresh = True, True
        dx, ok = _lin_solve(_rows(Jo, res), -r)
        if ok:
            on = _at(edge, crv, beta, n, vals, unk, x + dx, cache)
            if not math.isnan(on[0]):
                rn = _residual(on, res, tg)
                nn = np.max(np.abs(rn))
                if nn < 0.5 * nrm:
                    Jo = Jo + np.outer((on - o) - Jo @ dx, dx) / np.dot(dx, dx)
                    x, o, r, fresh = x + dx, on, rn, False
                    if FINISH_SAFETY * nn * (nn / nrm) < tol and nn < FINISH_CAP * tol:
                        return _finish(x, o, r, Jo, res, cache)
                    continue
        if not fresh:
            have = False
            continue
        if not ok:
            return SINGULAR, x, o, np.full(Jo.shape, np.nan), cache[6]
        x, o, r, good = _line_search(edge, crv, beta, n, vals, unk, res, tg, x, dx, nrm, cache)
        if not good:
            return NO_LINE, x, o, np.full(Jo.shape, np.nan), cache[6]
        have = False
    Jo = np.full(Jo.shape, np.nan)
    if np.max(np.abs(r)) < 1e3 * tol:
        return OK, x, o, Jo, cache[6]
    return NO_CONV, x, o, Jo, cache[6]


@jit
def _finish(x, o, r, Jo, res, cache):
    """The last Newton step without a shot: the step that a step just taken predicts will leave the
    residual far below the tolerance (its contraction, applied once more), applied to the unknowns
    and, through the observables' Jacobian, to the observables."""
    dx, ok = _lin_solve(_rows(Jo, res), -r)
    if not ok:
        return OK, x, o, Jo, cache[6]
    return OK, x + dx, o + Jo @ dx, Jo, cache[6]


@jit
def free_newton(q, beta, n, x, slope):
    """Apex stretch of free inflation at pressure q from a close guess ``x``: secant iterations from
    the slope ``slope`` of r(beta) in lc (NaN: a difference quotient). Returns (lc, slope, y) with y
    the clamp state (r, z, theta, lambda1, u, v); lc NaN when it does not converge quickly (the caller
    brackets instead)."""
    y = K.from_apex(K.FREE, x, beta, n, q, K.A, K.B, K.C)
    fx = y[0] - 1.0
    if not (math.isfinite(slope) and slope > 0.0):
        h = 1e-7 * x
        slope = (K.from_apex(K.FREE, x + h, beta, n, q, K.A, K.B, K.C)[0] - 1.0 - fx) / h
    for _ in range(20):
        if not (math.isfinite(fx) and math.isfinite(slope)) or slope <= 0.0:
            break
        if abs(fx) < 1e-14:
            return x, slope, y
        xn = x - fx / slope
        y = K.from_apex(K.FREE, xn, beta, n, q, K.A, K.B, K.C)
        fn = y[0] - 1.0
        if xn != x and math.isfinite(fn):
            slope = (fn - fx) / (xn - x)
        x, fx = xn, fn
    return np.nan, np.nan, y
