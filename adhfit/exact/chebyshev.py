"""Compiled Chebyshev interpolation on Chebyshev-Lobatto points and its inversion (for ``free_curve``).

Values f_j at x_j = cos(pi j/(N-1)) give the coefficients of the interpolating Chebyshev series by the
discrete cosine sum; Clenshaw's recurrence evaluates it. ``invert`` solves P(x) = p for many p by
Newton on the series and returns a second series D at the roots (and the roots): numpy's polynomial classes cost
~1 ms for a 200-row history, this ~0.05 ms. ``bary_weights`` and ``bary_eval``: the polynomial through
values at arbitrary distinct points (barycentric form), to resample it at the Lobatto points.
"""
from __future__ import annotations

import math

import numpy as np

from .jit import jit

__all__ = ["coefficients", "clenshaw", "derivative", "invert", "bary_weights", "bary_eval", "tail_bound", "curve", "roots"]


@jit
def coefficients(f):
    """Chebyshev coefficients of the interpolant of f at the Lobatto points x_j = cos(pi j/(N-1))."""
    n = f.shape[0]
    m = n - 1
    cs = np.empty(2 * m)  # cos(pi l/m), l = j k mod 2m
    for l in range(2 * m):
        cs[l] = math.cos(math.pi * l / m)
    c = np.empty(n)
    for k in range(n):
        acc = 0.0
        for j in range(n):
            w = 0.5 if (j == 0 or j == m) else 1.0
            acc += w * f[j] * cs[(j * k) % (2 * m)]
        c[k] = 2.0 * acc / m
    c[0] *= 0.5
    c[m] *= 0.5
    return c


@jit
def clenshaw(c, x):
    """The Chebyshev series with coefficients c at x (Clenshaw's recurrence)."""
    b1, b2 = 0.0, 0.0
    for k in range(c.shape[0] - 1, 0, -1):
        b1, b2 = 2.0 * x * b1 - b2 + c[k], b1
    return x * b1 - b2 + c[0]


@jit
def derivative(c):
    """Coefficients of the derivative of the Chebyshev series c (in its own variable x)."""
    n = c.shape[0]
    d = np.zeros(n + 1)
    for k in range(n - 1, 0, -1):
        d[k - 1] = d[k + 1] + 2.0 * k * c[k]
    d[0] *= 0.5
    return d[:n]


@jit
def invert(pn, dn, p, x0):
    """For each p[i]: the root x of P(x) = p[i] (Newton from x0[i], or, when p[i] is within 2 % of P's
    range from p[i-1], from the tangent at the root of p[i-1]: the rows of a history; P interpolates
    pn at the Lobatto points, x in [-1, 1]) and the interpolant of dn there. Returns (D(x), x) per p
    (NaN: no convergence)."""
    cp, cd = coefficients(pn), coefficients(dn)
    dp = derivative(cp)
    near = 0.02 * (np.max(pn) - np.min(pn))
    out = np.empty((2, p.shape[0]))
    ok, xp, slope = False, 0.0, 0.0
    for i in range(p.shape[0]):
        x = x0[i]
        if ok and abs(p[i] - p[i - 1]) <= near:
            x = xp + (p[i] - p[i - 1]) / slope
        ok = False
        for _ in range(30):
            slope = clenshaw(dp, x)
            step = (clenshaw(cp, x) - p[i]) / slope
            x -= step
            if not abs(x) <= 1.5:
                break
            if abs(step) < 1e-8:  # quadratic convergence: x is then off by ~(P''/2P') 1e-16
                ok = True
                break
        xp = x
        out[0, i] = clenshaw(cd, x) if ok else np.nan
        out[1, i] = x if ok else np.nan
    return out


@jit
def bary_weights(t):
    """Weights of the barycentric (second form) polynomial interpolation at the distinct points t,
    scaled to a largest magnitude of 1."""
    n = t.shape[0]
    w = np.ones(n)
    for j in range(n):
        for k in range(n):
            if k != j:
                w[j] /= t[j] - t[k]
    return w / np.max(np.abs(w))


@jit
def bary_eval(t, w, f, x):
    """The polynomial through (t_j, f_j) (``bary_weights`` w) at the points x."""
    out = np.empty(x.shape[0])
    for i in range(x.shape[0]):
        num, den, hit = 0.0, 0.0, -1
        for j in range(t.shape[0]):
            dx = x[i] - t[j]
            if dx == 0.0:
                hit = j
                break
            c = w[j] / dx
            num += c * f[j]
            den += c
        out[i] = f[hit] if hit >= 0 else num / den
    return out


@jit
def tail_bound(c):
    """The truncation estimate of the roots of P(x) = p for the series c: its last two coefficients
    over the least |dP/dx| at the Lobatto points."""
    n = c.shape[0]
    dp = derivative(c)
    lo = math.inf
    for j in range(n):
        lo = min(lo, abs(clenshaw(dp, math.cos(math.pi * j / (n - 1)))))
    return (abs(c[n - 1]) + abs(c[n - 2])) / lo


@jit
def curve(t, f, th):
    """The interpolant of f(t) through nodes t (both decreasing; ``th`` their clamp angles, < pi/2):
    barycentric weights w, the Lobatto points tc of [t[-1], t[0]], the values fc there, and the
    truncation estimate (in t) of the roots of f(t) = p (``tail_bound``). ok False when a node is not
    finite or not Case I (0 <= theta < pi/2 and, the meridian convex, |t| <= tan(theta) with the sign of
    f: a free-inflation node t = d0 at p = f), or t, f or fc is not strictly decreasing."""
    n = t.shape[0]
    ok = True
    for j in range(n):
        ok = ok and math.isfinite(t[j]) and math.isfinite(f[j]) and 0.0 <= th[j] < 0.5 * math.pi
        ok = ok and abs(t[j]) <= math.tan(th[j]) and t[j] * f[j] >= 0.0
        if j > 0:
            ok = ok and t[j] < t[j - 1] and f[j] < f[j - 1]
    tc, fc = np.empty(n), np.empty(n)
    if not ok:
        return tc, tc, fc, math.inf, False
    w = bary_weights(t)
    mid, half = 0.5 * (t[0] + t[n - 1]), 0.5 * (t[0] - t[n - 1])
    for j in range(n):
        tc[j] = mid + half * math.cos(math.pi * j / (n - 1))
    fc[:] = bary_eval(t, w, f, tc)
    for j in range(1, n):
        ok = ok and fc[j] < fc[j - 1]
    return w, tc, fc, half * tail_bound(coefficients(fc)), ok


@jit
def roots(tc, fc, p):
    """t with F(t) = p for each p (F through fc at the Lobatto points tc, decreasing): ``invert`` from
    linear interpolation between them. ok False where Newton failed."""
    n = tc.shape[0]
    mid, half = 0.5 * (tc[0] + tc[n - 1]), 0.5 * (tc[0] - tc[n - 1])
    x0 = np.empty(p.shape[0])
    for i in range(p.shape[0]):
        j = 1
        while j < n - 1 and fc[j] > p[i]:
            j += 1
        s = (p[i] - fc[j - 1]) / (fc[j] - fc[j - 1])
        x0[i] = (tc[j - 1] + s * (tc[j] - tc[j - 1]) - mid) / half
    out = invert(fc, tc, p, x0)
    ok = True
    for i in range(p.shape[0]):
        ok = ok and math.isfinite(out[0, i])
    return out[0], ok
