"""The free (non-contacting) membrane between the contact edge and the clamp (docs/numerics.md B1, B2).

Each stage only decides the two constants (D, C2) of eq. (38), sin(theta) = (kappa r^2 + D)/sqrt(r^2 + C2);
these kernels turn them into the material coordinate of the edge (J0 = ln(beta/rho_a)) and the gap d
(eqs. 25, 48, 58). With u = r^2, Q = (r^2 + C2) - (kappa r^2 + D)^2 = (q - kappa^2 u)(u - u_minus),
and both integrals are Carlson symmetric integrals (DLMF 19.29.4-19.29.7): exact, continuous through
kappa = 0, no tolerance. Scalar kernels, real or complex (complex-step derivatives); lengths over b,
c = 1/rs the substrate curvature (0 when flat).
"""
from __future__ import annotations

import numpy as np

from .jit import jit
from .special import carlson_rd, carlson_rf

__all__ = ["roots", "integrals", "substrate_cos", "free_membrane", "rise", "rise_many"]


@jit
def roots(kappa, D, C2):
    """q and u_minus of Q(u) = (q - kappa^2 u)(u - u_minus) (stable formulas, docs/numerics.md B2)."""
    B = 1.0 - 2.0 * kappa * D
    C = C2 - D * D
    sq = np.sqrt(1.0 - 4.0 * kappa * D + 4.0 * kappa * kappa * C2)
    if B.real >= 0.0:
        q = 0.5 * (B + sq)
    else:
        q = 2.0 * kappa * kappa * C / (sq - B)
    return q, -C / q


@jit
def _pair(C, x1, x2, x3, y1, y2, y3, span, need_j1):
    """J0 and the u-moment from the factor values at the two limits (DLMF 19.29.4, 19.29.7 with u = r^2)."""
    X1, X2, X3 = np.sqrt(x1), np.sqrt(x2), np.sqrt(x3)
    Y1, Y2, Y3 = np.sqrt(y1), np.sqrt(y2), np.sqrt(y3)
    U12 = (X1 * X2 * Y3 + Y1 * Y2 * X3) / span
    U13 = (X1 * X3 * Y2 + Y1 * Y3 * X2) / span
    U23 = (X2 * X3 * Y1 + Y2 * Y3 * X1) / span
    s12, s13, s23 = U12 * U12, U13 * U13, U23 * U23
    j0 = carlson_rf(s12, s13, s23)
    if not need_j1:
        return j0, 0.0 * j0
    return j0, C / 3.0 * carlson_rd(s13, s23, s12) + X3 * Y3 / U12


@jit
def integrals(kappa, D, C2, a, q_edge, through, need_j1):
    """J0, J1 from the edge to the clamp (eqs. 35-58), one state; ``through``: theta_a > pi/2 (eqs. 42, 47)."""
    q, um = roots(kappa, D, C2)
    k2 = kappa * kappa
    C = C2 - D * D
    ea = a * a
    L1e = q - k2 * ea
    L2e = ea - um
    if abs(L1e) < abs(L2e):
        L1e = q_edge / L2e
    else:
        L2e = q_edge / L1e
    one = 1.0 + 0.0 * ea
    if not through:
        j0, ju = _pair(C, q - k2, 1.0 - um, one, L1e, L2e, ea, 1.0 - ea, need_j1)
    else:
        zero = 0.0 * ea
        j0a, jua = _pair(C, L1e, L2e, ea, q - k2 * um, zero, um, L2e, need_j1)
        j0b, jub = _pair(C, q - k2, 1.0 - um, one, q - k2 * um, zero, um, 1.0 - um, need_j1)
        j0, ju = j0a + j0b, jua + jub
    return j0, kappa * ju + D * j0, q, um


@jit
def substrate_cos(a, c):
    return np.sqrt(1.0 - (a * c) ** 2)


@jit
def free_membrane(kappa, D, C2, a, c, cos_ta, need_j1):
    """J0, d and admissibility of one state (Q >= 0 on the free membrane, Case I at the clamp)."""
    q_edge = (a * a + C2) * cos_ta * cos_ta
    through = cos_ta.real < 0.0
    j0, j1, q, um = integrals(kappa, D, C2, a, q_edge, through, need_j1)
    ok = (q - kappa * kappa).real >= 0.0 and q_edge.real >= 0.0
    if through:
        ok = ok and um.real >= 0.0
    sag = a * a * c / (1.0 + substrate_cos(a, c))
    return j0, j1 - sag, ok


@jit
def rise(kappa, D, C2, x, y, y_is_root):
    """J1 from u = y to u = x (x > y >= u_minus): the rise of the free membrane between r = sqrt(y)
    and r = sqrt(x). ``y_is_root``: y is the lower root u_minus itself (the theta_a > pi/2 branch,
    eq. 47), whose factor is then exactly 0 (docs/numerics.md B2: a flag, not a number passed back)."""
    q, um = roots(kappa, D, C2)
    k2, C = kappa * kappa, C2 - D * D
    ly2 = 0.0 if y_is_root else y - um
    j0, ju = _pair(C, q - k2 * x, x - um, x, q - k2 * y, ly2, y, x - y, True)
    return kappa * ju + D * j0


@jit
def rise_many(kappa, D, C2, x, y, y_is_root):
    """:func:`rise` over arrays of limits ``x``, ``y`` (same size); one bool for all rows."""
    out = np.empty(x.size)
    for i in range(x.size):
        out[i] = rise(kappa, D, C2, x[i], y[i], y_is_root)
    return out
