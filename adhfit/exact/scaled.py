"""Free inflation at a given apex stretch by the scaling symmetry of the membrane equations.

The equations of a free segment (``kernels._rhs_free``) are invariant under lengths (rho, r, z) -> s
(rho, r, z) with the pressure p -> p/s: the stretches lambda1, lambda2 = r/rho and the angle are
scale-free, the curvature d theta/d rho = lambda1 (2p - T2 sin(theta)/r)/T1 scales as 1/s. The
graded mesh of ``kernels.from_apex`` (start and steps proportional to the segment end) scales with
them, so its discrete solution does too (to rounding). A shot from the apex with stretch lc at any
pressure q, integrated to the point rho* where lambda2 = r/rho = lambda0, is therefore, with lengths
over r(rho*), the free inflation of the membrane with pre-stretch lambda0 at the pressure q r(rho*):
apex deflection z(rho*)/r(rho*), clamp angle theta(rho*).

Free inflation at a given apex stretch is then one shot (at the pressure predicted for it, to the
clamp rho = 1/lambda0) and a few single Runge-Kutta steps of Newton in rho on lambda2 = lambda0 from
there, instead of a secant iteration in p of three to four shots. The point rho* differs from the
clamp of the shot's mesh by the error of the prediction; the discretization error of the result
then differs from that of a direct solve (mesh ending at rho*) by about that relative distance times
the error itself (1e-3 left <= 3e-12 at lambda0 = 1.1-3, p up to 0.6, n = 12): beyond ``RESHOOT``
the shot is repeated at the pressure just found, whose rho* then lies much closer to the clamp.
"""
from __future__ import annotations

import math

import numpy as np

from . import kernels as K
from .jit import jit

__all__ = ["RESHOOT", "end_node", "free_at_points", "free_at_stretch", "free_at_stretches"]

RESHOOT = 1e-3  # largest relative distance of rho* from the shot's end kept (see above)
STEP_CAP = 0.1  # largest Newton step in rho, over rho (one Runge-Kutta step of the mesh's last size)


@jit
def _settle(y, rho, lambda0, q):
    """Newton in rho on lambda2 = r/rho = lambda0 from the free state y at rho (pressure q), one
    Runge-Kutta step per iteration (d lambda2/d rho = (lambda1 cos(theta) - lambda2)/rho). Returns
    (y, rho) at the root; rho NaN when it does not converge."""
    for _ in range(30):  # (capped steps: a prediction off by a factor 2 takes ~8)
        g = y[0] / rho - lambda0
        gp = (y[3] * math.cos(y[2]) - y[0] / rho) / rho
        if not (math.isfinite(g) and math.isfinite(gp)) or gp == 0.0:
            return y, math.nan
        dl = -g / gp
        # done: g at rounding (a few ulp), or a step so small that the one after it would be ~1e-14 of
        # it (quadratic convergence)
        done = abs(g) <= 4e-15 * lambda0 or abs(dl) < 1e-7 * rho
        if dl != 0.0:  # the last step too: near p = 0 (gp ~ p^2) a few ulp of g are a large step
            dl = max(-STEP_CAP * rho, min(STEP_CAP * rho, dl))
            y = K.integrate(K.FREE, y, rho, rho + dl, 1.0, 1.0, q, K.A, K.B, K.C)
            rho += dl
        if done:
            return y, rho
    return y, math.nan


@jit
def _shot(lc, lambda0, n, q):
    """One shot at the pressure q to the clamp and ``_settle``: (p, d0, theta_end, moved), moved the
    relative distance of rho* from the clamp; NaN when the shot leaves the domain or Newton fails."""
    beta = 1.0 / lambda0
    y = K.from_apex(K.FREE, lc, beta, n, q, K.A, K.B, K.C)
    y, rho = _settle(y, beta, lambda0, q)
    if not (math.isfinite(rho) and math.isfinite(y[1]) and y[0] > 0.0):
        return math.nan, math.nan, math.nan, math.nan
    return q * y[0], y[1] / y[0], y[2], abs(rho - beta) / beta


@jit
def free_at_stretch(lc, lambda0, n, q):
    """Free inflation of pre-stretch lambda0 with apex stretch lc: (p, d0, theta_end) (p >= 0), q a
    prediction of p (> 0; see the module docstring); NaN when the shot leaves the domain or the
    Newton in rho fails."""
    for _ in range(3):
        p, d, th, moved = _shot(lc, lambda0, n, q)
        if not math.isfinite(p):
            break
        if moved <= RESHOOT:
            return p, d, th
        q = p
    return math.nan, math.nan, math.nan


@jit
def _rational_root(ua, pa, ub, pb, aim):
    """u with p(u) = aim on p = a u/(1 + b u^2) through (ua, pa) and (ub, pb): odd in u and with a
    maximum, like free inflation's p(u); the secant through them where that fit is singular (a point
    at u = 0). The root on the rising branch; the model's maximum where aim lies above it."""
    det = ua * ub * (pa * ua - pb * ub)
    if det != 0.0:
        a = pa * pb * (ua * ua - ub * ub) / det
        b = (ua * pb - ub * pa) / det
        den = a + math.copysign(math.sqrt(max(a * a - 4.0 * aim * aim * b, 0.0)), a)
        if den != 0.0 and math.isfinite(den):
            return 2.0 * aim / den
    return ua + (aim - pa) * (ub - ua) / (pb - pa)


@jit
def end_node(target, cover, lambda0, n, ua, pa, ub, pb):
    """A node beyond the rows' pressures: (u, p, d0, theta_end) with (p - target)/cover in [0, 1] (u =
    sign(p) sqrt(lc - lambda0), d0 signed), from the free states (ua, pa), (ub, pb) (distinct p; (0, 0)
    is the flat membrane) by ``_rational_root`` through the last two, each new state a ``_shot`` (a
    secant crept up on the concave p(u) near the pressure maximum: 5-7 shots where this takes 1-4).
    NaN when not found."""
    aim = target + 0.3 * cover
    for _ in range(8):
        u = _rational_root(ua, pa, ub, pb, aim)
        if not (math.isfinite(u) and u != 0.0):
            break
        p, d, th, moved = _shot(lambda0 + u * u, lambda0, n, abs(aim))
        if not math.isfinite(p):
            break
        p, d = math.copysign(p, u), math.copysign(d, u)
        if 0.0 <= (p - target) / cover <= 1.0:
            if moved > RESHOOT:  # the same stretch again, shot at the pressure just found
                p, d, th = free_at_stretch(lambda0 + u * u, lambda0, n, abs(p))
                p, d = math.copysign(p, u), math.copysign(d, u)
            return u, p, d, th
        ua, pa, ub, pb = ub, pb, u, p
    return math.nan, math.nan, math.nan, math.nan


@jit
def _extrapolate(xs, ys, i, x, order):
    """Lagrange extrapolation to x through the (up to) ``order`` points before index i."""
    k = min(i, order)
    out = 0.0
    for a in range(i - k, i):
        w = 1.0
        for b in range(i - k, i):
            if b != a:
                w *= (x - xs[b]) / (xs[a] - xs[b])
        out += w * ys[a]
    return out


@jit
def free_at_stretches(us, lambda0, n, known, pred):
    """Free inflation at the apex stretches lc = lambda0 + u^2 for u in ``us`` (in order: continuation),
    u carrying the sign of p. ``known`` (3, len(us)): (p, d0, theta_end) of nodes already solved (NaN:
    unknown; the first must be known), ``pred`` predictions of |p| (NaN: none). Each unknown node is
    ``free_at_stretch`` from its prediction, else from p/u (smooth, even in u, ~constant near u = 0,
    where p itself is hard to predict relatively) extrapolated in u through the (up to 4) nodes before
    it. Returns (p, d0, theta_end) per node (d0, theta_end for |p|); NaN from the first that fails."""
    m = us.shape[0]
    out = known.copy()
    ratio = np.full(m, np.nan)
    for i in (0, m - 1):
        if us[i] != 0.0:
            ratio[i] = out[0, i] / us[i]
    for i in range(1, m):
        if math.isfinite(out[0, i]):
            if us[i] != 0.0:
                ratio[i] = out[0, i] / us[i]
            continue
        if us[i] == 0.0:
            out[0, i], out[1, i], out[2, i] = 0.0, 0.0, 0.0
            continue
        if pred[i] > 0.0:
            q = pred[i]
        elif i == 1 and math.isfinite(ratio[m - 1]) and us[m - 1] ** 2 != us[0] ** 2:  # p/u linear in u^2
            s = (us[1] ** 2 - us[0] ** 2) / (us[m - 1] ** 2 - us[0] ** 2)  # through both ends
            q = abs(us[1] * (ratio[0] + s * (ratio[m - 1] - ratio[0])))
        else:
            q = abs(us[i] * _extrapolate(us, ratio, i, us[i], 4))
        if not q > 0.0:  # a node before at u = 0 (p = 0 at an end)
            q = abs(_extrapolate(us, out[0], i, us[i], 4))
        p, d, th = free_at_stretch(lambda0 + us[i] * us[i], lambda0, n, q)
        if not math.isfinite(p):
            out[:, i:] = np.nan
            return out
        out[0, i], out[1, i], out[2, i] = math.copysign(p, us[i]), d, th
        ratio[i] = abs(p / us[i])
    return out


@jit
def free_at_points(lcs, qs, lambda0, n):
    """``free_at_stretch`` at each apex stretch lcs[i] from the pressure qs[i] (>= 0): (3, m) rows p,
    d0, theta_end (independent free-inflation states near given pressures, to check an interpolant)."""
    m = lcs.shape[0]
    out = np.empty((3, m))
    for i in range(m):
        if qs[i] == 0.0:  # the flat membrane (lc = lambda0)
            out[0, i], out[1, i], out[2, i] = 0.0, 0.0, 0.0
        else:
            out[0, i], out[1, i], out[2, i] = free_at_stretch(lcs[i], lambda0, n, qs[i])
    return out
