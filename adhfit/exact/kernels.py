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

from .dop853 import A, B, C
from .jit import fast_jit, jit

FREE = 0
CONTACT = 1
START = 3e-3  # apex series start, as a fraction of the segment end (series error ~1e-11; 1e-3 needs
# 20 % more steps for the same accuracy, 1e-2 leaves a floor of ~5e-10)
K_APEX = math.asinh(1.0 / START - 1.0)  # e-folds of the graded mesh of a segment from the apex
FREE_APEX = 3.0  # free inflation (a free segment from the apex) takes this many times n steps: its last
# steps reach the clamp, where the membrane curves most; at 2 n (n = 8) its d0 was smooth in the
# pressure only to ~4e-10 through p = 0 at lambda0 = 1.1, too rough for the d0(p) interpolant of
# pressure control (``inflation.free_curve``, checked to 1e-10); 3 n: 2e-11
EDGE_EFOLD = 2.0  # a free segment from a small contact edge takes this many times n steps per K_APEX
# e-folds of its mesh (``free_from_edge``: it resembles one from the apex)
CONTACT_STEPS = 1.3  # a contact segment takes this many times n steps: at n steps it set the error of a
# history at lambda0 >= 2 (3.7e-7 at n = 8; 1.3 n: 4e-8, 0.7 n: 1.2e-6; benchmarks/results/exact_n.md)
EDGE_GRADING = 0.25  # the free mesh from a contact edge is graded on this fraction of min(rho_a, beta -
# rho_a): near a no-slip edge the stretch jumps and the membrane bends over a short length. Graded on
# the full distance, the worst error of a history at n = 8 was 1.6e-6 (lambda0 = 1.1, alpha ~ 0.9) and
# a no-slip f_min near alpha = 0 was 9e-7 off on half of it (lambda0 = 1.8, p ~ 0.58); on a quarter
# <= 9e-8 over 120 random cases (lambda0 = 1.1-3, both controls and slips, rs = 0.5, 1, flat)


@jit
def tensions(l1, l2):
    """Neo-Hookean line tensions over mu h (paper eqs. 8-9)."""
    j = 1.0 / (l1 * l2) ** 3
    return l1 / l2 - j, l2 / l1 - j


@jit
def _dt1(l1, l2):
    d1 = 1.0 / l2 + 3.0 / (l1 ** 4 * l2 ** 3)
    d2 = -l1 / l2 ** 2 + 3.0 / (l1 ** 3 * l2 ** 4)
    return d1, d2


@fast_jit
def _field(rho, r, l1, c):
    """(d lambda1/d rho, 1/r, T1, T2, stored-energy density pi (I1 - 3) rho) at one point.

    d lambda1/d rho follows from d(T1 r)/d rho = T2 dr/d rho (tangential equilibrium, eq. 4); the
    reciprocals are shared so that one evaluation costs four divisions.
    """
    irho = 1.0 / rho
    ir = 1.0 / r
    il1 = 1.0 / l1
    l2 = r * irho
    il2 = rho * ir
    q = il1 * il2
    j = q * q * q
    t1 = l1 * il2 - j
    t2 = l2 * il1 - j
    d1 = il2 + 3.0 * j * il1
    d2 = -l1 * il2 * il2 + 3.0 * j * il2
    l2p = (l1 * c - l2) * irho
    t1p = (t2 - t1) * l1 * c * ir
    e = math.pi * (l1 * l1 + l2 * l2 + q * q - 3.0) * rho
    return (t1p - d2 * l2p) / d1, ir, t1, t2, e


@fast_jit
def _rhs_free(rho, r, c, s, l1, par):
    """Right-hand side of a free segment, y = (r, cos theta, sin theta, lambda1, z, u, v)."""
    dl1, ir, t1, t2, e = _field(rho, r, l1, c)
    k = l1 * (2.0 * par - t2 * s * ir) / t1
    return l1 * c, -s * k, c * k, dl1, l1 * s, e, math.pi * r * r * l1 * s


@fast_jit
def _rhs_contact(rho, r, l1, par):
    """Right-hand side of a contacting segment, y = (r, lambda1, u, v)."""
    s = -r * par
    c = math.sqrt(1.0 - s * s)
    dl1, _, _, _, e = _field(rho, r, l1, c)
    return l1 * c, dl1, e, math.pi * r * r * l1 * s


# the nonzero Runge-Kutta matrix entries, row by row (50 of 66): row j uses _AV[_AP[j]:_AP[j + 1]]
_AP = np.zeros(13, dtype=np.int64)
_AL = np.array([l for j in range(12) for l in range(j) if A[j, l] != 0.0], dtype=np.int64)
_AV = np.array([A[j, l] for j in range(12) for l in range(j) if A[j, l] != 0.0])
for _j in range(12):
    _AP[_j + 1] = _AP[_j] + sum(1 for _l in range(_j) if A[_j, _l] != 0.0)


@jit
def _stage_exps(kh, ec, ie):
    """exp(kh C_j) and its reciprocal for the 12 stages (in place)."""
    for j in range(12):
        ec[j] = math.exp(kh * C[j])
        ie[j] = 1.0 / ec[j]


@fast_jit
def _steps(kind, y, rho1, eps, K, mu, par):
    """mu (>= 1, real) steps of DOP853's 8th-order solution in s on [0, 1], rho = rho1 + eps sinh(K s);
    y in place: floor(mu) steps of 1/mu and a last partial one, so that the result is continuous in
    mu (a step count that jumps with a state's data would make the discretization error jump).

    Only the first ``mo`` components of y enter the right-hand side; the others are quadratures, whose
    stage values are never needed (the same result, fewer operations). The mesh's exp(K s) at the
    stages comes from exp(K s0) exp(K C_j h), the former by a recurrence (reset every 8 steps).
    """
    m = y.shape[0]
    mo = 4 if kind == FREE else 2
    hf = 1.0 / mu
    nf = int(mu)
    rem = 1.0 - nf * hf
    total = nf + 1 if rem > 1e-9 * hf else nf
    h = hf
    k = np.empty((12, m))
    yt = np.empty(m)
    ec = np.empty(12)
    ie = np.empty(12)
    _stage_exps(K * h, ec, ie)
    g, ig = math.exp(K * h), math.exp(-K * h)
    e0, ie0 = 1.0, 1.0
    he, hk = 0.5 * eps, 0.5 * eps * K
    for i in range(total):
        if i == nf:  # the partial last step
            h = rem
            e0 = math.exp(K * nf * hf)
            ie0 = 1.0 / e0
            _stage_exps(K * h, ec, ie)
        for j in range(12):
            for q in range(mo):
                yt[q] = y[q]
            for t in range(_AP[j], _AP[j + 1]):
                a = h * _AV[t]
                l = _AL[t]
                for q in range(mo):
                    yt[q] += a * k[l, q]
            ep, em = e0 * ec[j], ie0 * ie[j]
            rho = rho1 + he * (ep - em)
            jac = hk * (ep + em)
            if kind == FREE:
                f = _rhs_free(rho, yt[0], yt[1], yt[2], yt[3], par)
                k[j, 0], k[j, 1], k[j, 2], k[j, 3] = f[0] * jac, f[1] * jac, f[2] * jac, f[3] * jac
                k[j, 4], k[j, 5], k[j, 6] = f[4] * jac, f[5] * jac, f[6] * jac
            else:
                f = _rhs_contact(rho, yt[0], yt[1], par)
                k[j, 0], k[j, 1], k[j, 2], k[j, 3] = f[0] * jac, f[1] * jac, f[2] * jac, f[3] * jac
        for q in range(m):
            acc = 0.0
            for j in range(12):
                acc += B[j] * k[j, q]
            y[q] += h * acc
        if i % 8 == 7:
            e0 = math.exp(K * (i + 1) * hf)
            ie0 = 1.0 / e0
        else:
            e0 *= g
            ie0 *= ig


@jit
def integrate(kind, y0, rho1, rho2, eps, n, par, A, B, C):
    """Integrate from rho1 to rho2 in n (real, >= 1: see ``_steps``) fixed steps of s on the graded mesh
    rho = rho1 + eps sinh(K s).

    eps sets the grading (steps ~ eps near rho1, geometric growth beyond); K = asinh((rho2-rho1)/eps).
    (A, B, C: the Dormand-Prince tableau, kept in the signature; the module's own copy is used.)
    """
    y = y0.copy()
    if rho2 == rho1:
        return y
    K = math.asinh((rho2 - rho1) / eps)
    if kind == FREE:  # the angle as its cosine and sine while integrating
        w = np.array([y[0], math.cos(y[2]), math.sin(y[2]), y[3], y[1], y[4], y[5]])
        _steps(FREE, w, rho1, eps, K, float(n), par)
        y[0], y[1], y[2], y[3], y[4], y[5] = w[0], w[4], math.atan2(w[2], w[1]), w[3], w[5], w[6]
    else:
        _steps(CONTACT, y, rho1, eps, K, float(n), par)
    return y


@jit
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


@jit
def from_apex(kind, lc, rho_end, n, par, A, B, C):
    """Integrate a segment that starts at the apex (rho = 0) with centre stretch lc."""
    rs0 = START * rho_end
    y0 = _apex(kind, lc, rs0, par)
    return integrate(kind, y0, rs0, rho_end, rs0, (CONTACT_STEPS if kind == CONTACT else FREE_APEX) * n, par,
                     A, B, C)


@jit
def free_from_edge(y0, rho_a, beta, n, p, A, B, C):
    """Integrate the free membrane from the contact edge rho_a to the clamp beta.

    The mesh is graded towards the edge (steps ~ ``EDGE_GRADING`` rho_a there); a small contact is near
    the apex, whose 1/rho terms the grading resolves geometrically, so the steps grow with the number of
    e-folds K = asinh((beta - rho_a)/eps): EDGE_EFOLD n per ``K_APEX`` e-folds (a free segment from a
    small edge resembles one from the apex), at least n (rho_a >~ 0.13 beta). The count is real (``_steps``): a
    count rounded up jumped by a step at some rho_a, the discretization error with it, and such a jump
    inside the stencil of an extremum's refinement (``history._extremum``) moved the extremum (by
    1.5e-7 in a at n = 12 before, where a turning point lay).
    """
    eps = EDGE_GRADING * min(rho_a, beta - rho_a)
    if eps <= 0.0:
        return y0.copy()
    m = max(float(n), EDGE_EFOLD * n * math.asinh((beta - rho_a) / eps) / K_APEX)
    return integrate(FREE, y0, rho_a, beta, eps, m, p, A, B, C)


CONTINUOUS = 0
FRICTIONLESS = 1
GIVEN = 2
N_OUT = 11  # r_end, d, theta_end, a, f, G, l1m, l1p, l2, u, v


@jit
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


@jit
def release_rate(alpha, l1p, l1m, l2):
    """Energy release rate over mu h, paper eq. (23) with the exact tension T1+."""
    t1p = tensions(l1p, l2)[0]
    q = l1m / l1p
    return (t1p * (1.0 - math.cos(alpha))
            + 0.5 * ((l1p - l1m) ** 2 / (l1m * l2) + (1.0 - 3.0 * q * q + 2.0 * q ** 3) / (l1m * l2) ** 3))


@jit
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


@jit
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

