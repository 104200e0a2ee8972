"""Compiled kernels of the exact neo-Hookean membrane: the ODEs in the material coordinate and a
fixed-step 8th-order Runge-Kutta integrator (Dormand-Prince 8(5,3) weights, used without error
control on a graded mesh).

Everything is dimensionless: lengths over b, tensions over mu h, pressure as p = P b/(2 mu h) (so
P b/(mu h) = 2p), the material coordinate rho over b (0 <= rho <= beta = 1/lambda0).

State of a free (non-contacting) segment: ``(r, z, theta, lambda1, u, v)``; of a contacting segment on
the substrate (frictionless, tangential equilibrium kept): ``(r, lambda1, u, v)``. ``u`` accumulates
the stored energy U/(mu h b^2) = pi * int (I1 - 3) rho d rho and ``v`` the enclosed volume
V/b^3 = pi * int r^2 dz (both used only by energy checks).
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit
from .dop853 import A, B, C

FREE = 0
CONTACT = 1
START = 1e-3  # apex series start, as a fraction of the segment end


@njit(cache=True)
def tensions(l1, l2):
    """Neo-Hookean line tensions over mu h (paper eqs. 8-9)."""
    j = 1.0 / (l1 * l2) ** 3
    return l1 / l2 - j, l2 / l1 - j


@njit(cache=True)
def _dt1(l1, l2):
    d1 = 1.0 / l2 + 3.0 / (l1 ** 4 * l2 ** 3)
    d2 = -l1 / l2 ** 2 + 3.0 / (l1 ** 3 * l2 ** 4)
    return d1, d2


@njit(cache=True)
def _lambda1_rate(rho, r, l1, c):
    """d lambda1/d rho from d(T1 r)/d rho = T2 dr/d rho (tangential equilibrium, eq. 4)."""
    l2 = r / rho
    t1, t2 = tensions(l1, l2)
    d1, d2 = _dt1(l1, l2)
    l2p = (l1 * c - l2) / rho
    t1p = (t2 - t1) * l1 * c / r
    return (t1p - d2 * l2p) / d1


@njit(cache=True)
def _rhs(kind, rho, y, par, out):
    if kind == FREE:
        r, th, l1 = y[0], y[2], y[3]
        l2 = r / rho
        t1, t2 = tensions(l1, l2)
        c = math.cos(th)
        s = math.sin(th)
        out[0] = l1 * c
        out[1] = l1 * s
        out[2] = l1 * (2.0 * par - t2 * s / r) / t1
        out[3] = _lambda1_rate(rho, r, l1, c)
        out[4] = math.pi * (l1 * l1 + l2 * l2 + 1.0 / (l1 * l2) ** 2 - 3.0) * rho
        out[5] = math.pi * r * r * l1 * s
    else:
        r, l1 = y[0], y[1]
        l2 = r / rho
        s = -r * par
        c = math.sqrt(1.0 - s * s)
        out[0] = l1 * c
        out[1] = _lambda1_rate(rho, r, l1, c)
        out[2] = math.pi * (l1 * l1 + l2 * l2 + 1.0 / (l1 * l2) ** 2 - 3.0) * rho
        out[3] = math.pi * r * r * l1 * s


@njit(cache=True)
def integrate(kind, y0, rho1, rho2, eps, n, par, A, B, C):
    """Integrate from rho1 to rho2 in n fixed steps of s on the graded mesh rho = rho1 + eps sinh(K s).

    eps sets the grading (steps ~ eps near rho1, geometric growth beyond); K = asinh((rho2-rho1)/eps).
    """
    m = y0.shape[0]
    y = y0.copy()
    if rho2 == rho1:
        return y
    K = math.asinh((rho2 - rho1) / eps)
    h = 1.0 / n
    k = np.empty((12, m))
    yt = np.empty(m)
    f = np.empty(m)
    for i in range(n):
        s0 = i * h
        for j in range(12):
            for q in range(m):
                acc = y[q]
                for l in range(j):
                    acc += h * A[j, l] * k[l, q]
                yt[q] = acc
            sj = s0 + C[j] * h
            rho = rho1 + eps * math.sinh(K * sj)
            jac = eps * K * math.cosh(K * sj)
            _rhs(kind, rho, yt, par, f)
            for q in range(m):
                k[j, q] = f[q] * jac
        for q in range(m):
            acc = 0.0
            for j in range(12):
                acc += B[j] * k[j, q]
            y[q] += h * acc
    return y


@njit(cache=True)
def _apex(kind, lc, rho, par):
    """Regular series at the apex (lambda1 = lambda2 = lc): start values at small rho."""
    tc = 1.0 - lc ** -6
    if kind == FREE:
        k = lc * par / tc
    else:
        k = -lc * par
    d1, d2 = _dt1(lc, lc)
    a2 = lc * k * k * (3.0 * d2 - d1) / (16.0 * d1)
    b3 = (a2 - 0.5 * lc * k * k) / 3.0
    r = lc * rho + b3 * rho ** 3
    l1 = lc + a2 * rho * rho
    u = 0.5 * math.pi * (2.0 * lc * lc + lc ** -4 - 3.0) * rho * rho
    if kind == FREE:
        return np.array([r, 0.5 * lc * k * rho * rho, k * rho, l1, u, 0.0])
    return np.array([r, l1, u, 0.0])


@njit(cache=True)
def from_apex(kind, lc, rho_end, n, par, A, B, C):
    """Integrate a segment that starts at the apex (rho = 0) with centre stretch lc."""
    rs0 = START * rho_end
    y0 = _apex(kind, lc, rs0, par)
    return integrate(kind, y0, rs0, rho_end, rs0, n, par, A, B, C)


@njit(cache=True)
def free_from_edge(y0, rho_a, beta, n, p, A, B, C):
    """Integrate the free membrane from the contact edge rho_a to the clamp beta."""
    eps = min(rho_a, beta - rho_a)
    if eps <= 0.0:
        return y0.copy()
    return integrate(FREE, y0, rho_a, beta, eps, n, p, A, B, C)


CONTINUOUS = 0
FRICTIONLESS = 1
GIVEN = 2
N_OUT = 11  # r_end, d, theta_end, a, f, G, l1m, l1p, l2, u, v


@njit(cache=True)
def l1_frictionless(l1m, l2, alpha):
    """lambda1+ from t1(lambda1+, l2) cos(alpha) = t1(lambda1-, l2) (t1 increases with lambda1)."""
    ca = math.cos(alpha)
    target = tensions(l1m, l2)[0] / ca
    x = l1m / math.sqrt(ca)
    for _ in range(60):
        t = tensions(x, l2)[0]
        d1 = 1.0 / l2 + 3.0 / (x ** 4 * l2 ** 3)
        step = (t - target) / d1
        x = max(x - step, 0.5 * x)
        if abs(step) < 1e-15 * x:
            break
    return x


@njit(cache=True)
def release_rate(alpha, l1p, l1m, l2):
    """Energy release rate over mu h, paper eq. (23) with the exact tension T1+."""
    t1p = tensions(l1p, l2)[0]
    q = l1m / l1p
    return (t1p * (1.0 - math.cos(alpha))
            + 0.5 * ((l1p - l1m) ** 2 / (l1m * l2) + (1.0 - 3.0 * q * q + 2.0 * q ** 3) / (l1m * l2) ** 3))


@njit(cache=True)
def shot(edge, p, crv, beta, n, lc, rho_a, alpha, l1p, A, B, C):
    """One state shot from the apex to the clamp; returns the N_OUT observables (see state.py)."""
    if rho_a <= 0.0:
        out = np.empty(N_OUT)
        y = from_apex(FREE, lc, beta, n, p, A, B, C)
        out[0], out[1], out[2] = y[0], y[1], y[2]
        out[3] = out[4] = out[5] = 0.0
        out[6] = out[7] = out[8] = lc
        out[9], out[10] = y[4], y[5]
        return out
    yc = from_apex(CONTACT, lc, rho_a, n, crv, A, B, C)
    return shot_from_edge(edge, p, crv, beta, n, yc, rho_a, alpha, l1p, A, B, C)


@njit(cache=True)
def shot_from_edge(edge, p, crv, beta, n, yc, rho_a, alpha, l1p, A, B, C):
    """The free part of a shot, given the contact field's end state ``yc`` = (a, lambda1-, u, v)."""
    out = np.empty(N_OUT)
    a, l1m = yc[0], yc[1]
    l2 = a / rho_a
    if edge == CONTINUOUS:
        l1p = l1m
    elif edge == FRICTIONLESS:
        l1p = l1_frictionless(l1m, l2, alpha)
    theta_a = alpha - math.asin(min(a * crv, 1.0))
    drop = a * a * crv / (1.0 + math.sqrt(max(1.0 - (a * crv) ** 2, 0.0)))
    y0 = np.array([a, -drop, theta_a, l1p, yc[2], yc[3]])
    y = free_from_edge(y0, rho_a, beta, n, p, A, B, C)
    t1p = tensions(l1p, l2)[0]
    out[0], out[1], out[2] = y[0], y[1], y[2]
    out[3] = a
    out[4] = math.pi * a * (a * p - t1p * math.sin(theta_a))
    out[5] = release_rate(alpha, l1p, l1m, l2)
    out[6], out[7], out[8] = l1m, l1p, l2
    out[9], out[10] = y[4], y[5]
    return out
