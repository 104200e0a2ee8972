"""Compiled continuation along one stage: many rows in one call (the row loop of ``history.march``).

For each parameter value in turn: a Lagrange predictor through the last (up to) eight solved states,
then ``newton.newton`` from it with the Jacobian carried from row to row (Broyden-updated). The loop
stops at the first row that fails or turns past vertical at the clamp; the caller handles that row
(step splitting, or the error) in Python, as before. ``bracket_rows`` is the adaptive stepping in
the contact angle that brackets the onset of delamination (G = w) along pinning, also in one call.
"""
from __future__ import annotations

import math

import numpy as np

from . import kernels as K
from . import newton as N
from .jit import jit

__all__ = ["march_rows", "bracket_rows", "abscissa", "vertex", "PREDICT"]

PREDICT = 8  # states the predictor extrapolates through (degree 7: median error of the unknowns along
# delamination 3e-10 against 8e-9 through six, lambda0 = 1.5; ~4 % fewer shots a history)


@jit
def predict(v, vs, xs, cnt, x0):
    """Lagrange extrapolation to ``v`` through the last (up to) ``PREDICT`` of the ``cnt`` solved
    (vs, xs); ``x0`` when none is solved, the last state when parameter values repeat."""
    k = min(cnt, PREDICT)
    if k == 0:
        return x0.copy()
    for a in range(cnt - k, cnt):
        for b in range(a + 1, cnt):
            if vs[a] == vs[b]:
                return xs[cnt - 1].copy()
    out = np.zeros(xs.shape[1])
    for i in range(cnt - 1, cnt - k - 1, -1):
        li = 1.0
        for j in range(cnt - 1, cnt - k - 1, -1):
            if j != i:
                li *= (v - vs[j]) / (vs[i] - vs[j])
        for q in range(xs.shape[1]):
            out[q] += li * xs[i, q]
    return out


@jit
def abscissa(v, scale):
    """The predictor's variable for the parameter value v: v itself (``scale`` = 0); sqrt(v) for
    making contact (``scale`` < 0: the unknowns are not smooth in a at a = 0; predictor residuals of
    the first ~25 rows fall from ~1e-6 to ~1e-8, 167 -> 158 shots at lambda0 = 1.5); for delamination
    (``scale`` > 0: the edge's rho_a at the onset) the uniform variable u of its grid, v = scale (1 -
    c(u))^1.5 with c(u) = (1 - cos(pi u))/2 (``history._delamination``), in which the unknowns stay
    smooth as rho_a -> 0 (in rho_a the last 30 rows had residuals of ~1e-6 and a third shot; in u
    ~1e-9)."""
    if scale < 0.0:
        return math.sqrt(max(v, 0.0))
    if not scale > 0.0:
        return v
    q = (max(v, 0.0) / scale) ** (2.0 / 3.0)
    return math.acos(min(1.0, max(-1.0, 2.0 * q - 1.0))) / math.pi


@jit
def march_rows(edge, crv, beta, n, vals, unk, res, tg, in_tg, pidx, values, vs0, xs0, x0, J0, tol,
               max_iter, scale):
    """Solve the stage at each of ``values`` (the parameter: ``vals[pidx]``, or ``tg[pidx]`` when
    ``in_tg``) continuing from the solved history (``vs0``, ``xs0``), the predictor in the variable
    ``abscissa(v, scale)``. Returns (rows solved, per row the unknowns then the N_OUT observables,
    the last Jacobian, shots taken)."""
    m, k, h = values.shape[0], unk.shape[0], vs0.shape[0]
    vs = np.empty(h + m)
    xs = np.empty((h + m, k))
    for i in range(h):
        vs[i] = abscissa(vs0[i], scale)
    xs[:h] = xs0
    rows = np.full((m, k + K.N_OUT), np.nan)
    J = J0.copy()
    total = 0.0
    cache = np.full(7, np.nan)
    for i in range(m):
        v = values[i]
        vv, tt = vals.copy(), tg.copy()
        if in_tg:
            tt[pidx] = v
        else:
            vv[pidx] = v
        guess = predict(abscissa(v, scale), vs, xs, h + i, x0)
        status, x, o, J, shots = N.newton_cached(edge, crv, beta, n, vv, unk, res, tt, guess, J, tol,
                                                  max_iter, cache)
        total += shots
        if status != N.OK or not abs(o[2]) < 0.5 * math.pi:
            return i, rows, J, total
        vs[h + i] = abscissa(v, scale)
        xs[h + i] = x
        rows[i, :k] = x
        rows[i, k:] = o
    return m, rows, J, total


@jit
def vertex(x, y, c, h):
    """The minimum of the polynomial through (x, y) nearest the centre c (scale h): Newton on its
    derivative from the least sample; NaN if it does not converge within 2.5 h of c (or at a point
    that is not a minimum)."""
    m = x.shape[0]
    t = (x - c) / h
    V = np.empty((m, m))
    for i in range(m):
        for j in range(m):
            V[i, j] = t[i] ** (m - 1 - j)
    coef, ok = N._lin_solve(V, y)
    if not ok:
        return np.nan
    r = t[np.argmin(y)]
    for _ in range(30):
        d1, d2 = _derivatives(coef, r)
        step = d1 / d2
        r -= step
        if not abs(r) <= 2.5:
            return np.nan
        if abs(step) < 1e-13:
            return c + h * r if _derivatives(coef, r)[1] > 0.0 else np.nan
    return np.nan


@jit
def _derivatives(coef, r):
    """First and second derivative at r of the polynomial with coefficients ``coef`` (highest first)."""
    m = coef.shape[0]
    d1, d2 = 0.0, 0.0
    for j in range(m - 1):
        pw = m - 1 - j
        d1 += pw * coef[j] * r ** (pw - 1)
        if pw >= 2:
            d2 += pw * (pw - 1) * coef[j] * r ** (pw - 2)
    return d1, d2


@jit
def bracket_rows(edge, crv, beta, n, vals, unk, res, tg, pidx, x_m, g_m, w, top, J0, tol, max_iter):
    """Step ``vals[pidx]`` (pinning: the contact angle alpha) from 0 (unknowns ``x_m``, G = ``g_m``) until
    G >= w: the step loop of ``history._bracket`` compiled. A step aims 3 % past where G ~ alpha^2
    reaches w (at most 4 times the last step and 0.3); a failed step (Newton, or past vertical at the
    clamp), one longer than 0.04 finding G falling (a fold, another branch) and one longer than 1e-3
    turning the clamp tangent by more than 0.1 (it may have passed over a stretch of the branch beyond
    vertical at the clamp onto another branch) are halved and steps no longer grow; one reaching
    ``top`` is cut to 0.04, then ends the search. Returns (found, alpha and row of the last state
    below w, alpha and row of the first at or above w, Jacobian, shots); a row is the unknowns then
    the N_OUT observables."""
    k = unk.shape[0]
    cap = 64
    vs = np.empty(cap)
    xs = np.empty((cap, k))
    vs[0], cnt = 0.0, 1
    xs[0] = x_m
    prev, row = np.full(k + K.N_OUT, np.nan), np.full(k + K.N_OUT, np.nan)
    prev[:k] = x_m
    prev_a, prev_g, step, grow, total = 0.0, g_m, 0.04, True, 0.0
    J, cache = J0.copy(), np.full(7, np.nan)
    while True:
        alpha = prev_a + step
        if alpha >= top and step > 0.04:
            step, grow = 0.04, False
            continue
        if alpha >= top or step < 1e-9:
            return False, prev_a, prev, alpha, row, J, total
        v = vals.copy()
        v[pidx] = alpha
        status, x, o, J, shots = N.newton_cached(edge, crv, beta, n, v, unk, res, tg,
                                                  predict(alpha, vs, xs, cnt, x_m), J, tol, max_iter, cache)
        total += shots
        if status != N.OK or not abs(o[2]) < 0.5 * math.pi or (step > 0.04 and o[5] < prev_g) \
                or (step > 1e-3 and abs(o[2] - prev[k + 2]) > 0.1):
            step, grow = 0.5 * step, False
            continue
        row[:k] = x
        row[k:] = o
        if o[5] >= w:
            return True, prev_a, prev, alpha, row, J, total
        if grow and o[5] > 0.0:
            step = min(max(1.03 * alpha * math.sqrt(w / o[5]) - alpha, step), 4.0 * step, 0.3)
        prev = row.copy()
        prev_a, prev_g = alpha, o[5]
        if cnt == cap:  # only the last PREDICT are extrapolated through
            vs[:PREDICT] = vs[cnt - PREDICT:].copy()
            xs[:PREDICT] = xs[cnt - PREDICT:].copy()
            cnt = PREDICT
        vs[cnt] = alpha
        xs[cnt] = x
        cnt += 1
