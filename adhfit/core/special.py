"""Carlson's symmetric elliptic integrals R_F and R_D (Carlson 1995, DLMF 19.36), real or complex.

Compiled scalar kernels, generic in the argument type: numba compiles them for float64 (plain
evaluations) and complex128 (complex-step derivatives). Outside the cut plane they return NaN, as
``scipy.special.elliprf`` / ``elliprd`` do.
"""
from __future__ import annotations

import math

import numpy as np

from .jit import jit

__all__ = ["carlson_rf", "carlson_rd"]

#: relative truncation error aimed at in the series (both are 7th-degree, DLMF 19.36.1-2)
_RERR = 1e-16
_RF_FACTOR = 1.0 / (3.0 * _RERR) ** 0.125
_RD_FACTOR = 1.0 / (0.25 * _RERR) ** 0.125


@jit
def _ph_good(z):
    """Argument in the cut plane (not on the negative real axis, not NaN), as scipy checks it."""
    zr, zi = z.real, z.imag
    if zr != zr or zi != zi:
        return False
    if zi == 0.0:
        return zr >= 0.0
    return abs(zr) < math.inf


@jit
def carlson_rf(x, y, z):
    """R_F(x, y, z) by duplication (DLMF 19.36.1, 7th-degree series); NaN outside the cut plane."""
    if not (_ph_good(x) and _ph_good(y) and _ph_good(z)):
        return (x + y + z) * math.nan
    if (x == 0.0) + (y == 0.0) + (z == 0.0) >= 2:
        return (x + y + z) * math.inf
    A0 = (x + y + z) / 3.0
    dx, dy = A0 - x, A0 - y
    Q = max(abs(dx), abs(dy), abs(A0 - z)) * _RF_FACTOR
    xm, ym, zm, Am = x, y, z, A0
    f = 1.0
    for _ in range(100):
        if abs(Am) > Q * f:
            break
        sx, sy, sz = np.sqrt(xm), np.sqrt(ym), np.sqrt(zm)
        lam = sx * (sy + sz) + sy * sz
        xm, ym, zm, Am = 0.25 * (xm + lam), 0.25 * (ym + lam), 0.25 * (zm + lam), 0.25 * (Am + lam)
        f *= 0.25
    X = f * dx / Am
    Y = f * dy / Am
    Z = -(X + Y)
    E2 = X * Y - Z * Z
    E3 = X * Y * Z
    s = (1.0 - E2 / 10.0 + E3 / 14.0 + E2 * E2 / 24.0 - 3.0 * E2 * E3 / 44.0
         - 5.0 * E2 * E2 * E2 / 208.0 + 3.0 * E3 * E3 / 104.0 + E2 * E2 * E3 / 16.0)
    return s / np.sqrt(Am)


@jit
def carlson_rd(x, y, z):
    """R_D(x, y, z) by duplication (DLMF 19.36.2, 7th-degree series); NaN outside the cut plane."""
    if not (_ph_good(x) and _ph_good(y) and _ph_good(z)):
        return (x + y + z) * math.nan
    if z == 0.0 or (x == 0.0 and y == 0.0):
        return (x + y + z) * math.inf
    A0 = (x + y + 3.0 * z) / 5.0
    dx, dy = A0 - x, A0 - y
    Q = max(abs(dx), abs(dy), abs(A0 - z)) * _RD_FACTOR
    xm, ym, zm, Am = x, y, z, A0
    f = 1.0
    acc = 0.0 * A0
    for _ in range(100):
        if abs(Am) > Q * f:
            break
        sx, sy, sz = np.sqrt(xm), np.sqrt(ym), np.sqrt(zm)
        lam = sx * (sy + sz) + sy * sz
        acc += f / (sz * (zm + lam))
        xm, ym, zm, Am = 0.25 * (xm + lam), 0.25 * (ym + lam), 0.25 * (zm + lam), 0.25 * (Am + lam)
        f *= 0.25
    X = f * dx / Am
    Y = f * dy / Am
    Z = -(X + Y) / 3.0
    XY, Z2 = X * Y, Z * Z
    E2 = XY - 6.0 * Z2
    E3 = (3.0 * XY - 8.0 * Z2) * Z
    E4 = 3.0 * (XY - Z2) * Z2
    E5 = XY * Z2 * Z
    s = (1.0 - 3.0 * E2 / 14.0 + E3 / 6.0 + 9.0 * E2 * E2 / 88.0 - 3.0 * E4 / 22.0
         - 9.0 * E2 * E3 / 52.0 + 3.0 * E5 / 26.0 - E2 * E2 * E2 / 16.0 + 3.0 * E3 * E3 / 40.0
         + 3.0 * E2 * E4 / 20.0 + 45.0 * E2 * E2 * E3 / 272.0 - 9.0 * (E3 * E4 + E2 * E5) / 68.0)
    return f * s / (Am * np.sqrt(Am)) + 3.0 * acc
