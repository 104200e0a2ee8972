"""The five solvable branches of a history: (stage, slip) as a code, a locator and at most one unknown.

* ``MC`` making contact (both slips), locator a, explicit: D = -(kappa + c) a^2, C2 = 0;
* ``PIN_NS`` no-slip pinning, locator G (0 -> w), unknown the edge stretch ratio t (eqs. 39, 52);
* ``PIN_FR`` frictionless pinning, locator alpha, unknown a (eqs. 55, 56);
* ``DEL_NS`` no-slip delamination, locator a, unknown t, G = w;
* ``DEL_FR`` frictionless delamination, locator a, explicit (alpha = atan sqrt(2 w)).

An implicit branch's unknown solves the material condition J0 = target (eq. 57 / eq. 61). States are
(x, kappa, loc) with the context c = 1/rs, w and the end of loading (a_m, L_m = its J0). Scalar
kernels, real or complex; observables a, alpha, p, d, f, G, J0 in that order (``KEY_CODES``).
"""
from __future__ import annotations

import math

import numpy as np

from .jit import jit
from .membrane import free_membrane, substrate_cos

__all__ = ["MC", "PIN_NS", "PIN_FR", "DEL_NS", "DEL_FR", "KEY_CODES", "state", "material_target",
           "material_residual", "bracket", "is_implicit", "evaluate_batch", "first_bad", "observe",
           "admissible", "CLAMP_NEAR", "clamp_margin"]

MC, PIN_NS, PIN_FR, DEL_NS, DEL_FR = 0, 1, 2, 3, 4
#: a state with 1 - |sin theta(1)| below this is at the Case I limit (the clamp tangent vertical),
#: where a branch leaves the model (:mod:`.limit` confirms it by a solve on the limit)
CLAMP_NEAR = 1e-6
#: rows of an observation vector
KEY_CODES = {"a": 0, "alpha": 1, "p": 2, "d": 3, "f": 4, "G": 5, "J0": 6}


@jit
def _noslip_constants(kappa, a, c, alpha, t):
    s, ac = substrate_cos(a, c), a * c
    sin_ta = s * np.sin(alpha) - ac * np.cos(alpha)
    return sin_ta * a * t - kappa * a * a, a * a * (t * t - 1.0)


@jit
def _frictionless_constants(kappa, a, c, alpha):
    ta = np.tan(alpha)
    return a * substrate_cos(a, c) * ta - (kappa + c) * a * a, (a * ta) ** 2


@jit
def _edge_angle(t, G):
    """The contact angle alpha of eq. (62), (t - 1)^2 / 2 + t (1 - cos alpha) = G, for t and G of one
    type. As 2 asin(sqrt(y / 2)), y = 1 - cos alpha: arccos(1 - y) loses all but ~sqrt(eps) of alpha
    where y is small (1 - y rounds to the floats next to 1), and next to the no-slip delamination
    end, alpha -> 0, that noise moved the rows' gap by 4e-10 and the turning point found on them by
    1e-7 (issue 24, stress seed 11). A y below 0 by rounding only (|y| < 2e-16, where 1 - y rounded to
    1 before) is alpha = 0."""
    y = (G - 0.5 * (t - 1.0) ** 2) / t
    if y.real < 0.0 and y.real > -2.0 * 2.220446049250313e-16:
        y = y - y.real
    return 2.0 * np.arcsin(np.sqrt(0.5 * y))


@jit
def unpack(code, x, kappa, loc, c, w, a_m):
    """(a, alpha, D, C2, G) of one state on branch ``code`` (its stage's eqs.: making contact, 39/52, 55/56, 57, 61)."""
    # all three share one dtype (the batch functions see to it), so every branch returns one type
    zero = 0.0 * loc
    if code == MC:
        D = -(kappa + c) * loc * loc
        return loc + zero, zero, D + zero, zero, zero
    if code == PIN_NS:
        # located by G (0 -> w): alpha from eq. (52) solved for alpha, as in delamination
        a = a_m + zero
        alpha = _edge_angle(x, loc)
        D, C2 = _noslip_constants(kappa, a, c, alpha, x)
        return a, alpha + zero, D + zero, C2 + zero, loc + zero
    if code == PIN_FR:
        D, C2 = _frictionless_constants(kappa, x, c, loc)
        ta = np.tan(loc)
        return x + zero, loc + zero, D + zero, C2 + zero, 0.5 * ta * ta + zero
    if code == DEL_NS:
        alpha = _edge_angle(x, w + 0.0 * x)
        D, C2 = _noslip_constants(kappa, loc, c, alpha, x)
        return loc + zero, alpha + zero, D + zero, C2 + zero, w + zero
    alpha = math.atan(math.sqrt(2.0 * w))
    D, C2 = _frictionless_constants(kappa, loc, c, alpha)
    return loc + zero, alpha + zero, D + zero, C2 + zero, w + zero


@jit
def state(code, x, kappa, loc, c, w, a_m, need_j1):
    """Observables of one state: (a, alpha, d, f, G, J0, ok); p is kappa."""
    a, alpha, D, C2, G = unpack(code, x, kappa, loc, c, w, a_m)
    s, ac = substrate_cos(a, c), a * c
    cos_ta = s * np.cos(alpha) + ac * np.sin(alpha)
    j0, d, ok = free_membrane(kappa, D, C2, a, c, cos_ta, need_j1)
    return a, alpha, d, -np.pi * D, G, j0, ok


@jit
def material_target(code, loc, c, a_m, L_m):
    """The J0 an implicit branch's state must have (eq. 57 / eq. 61)."""
    if code == DEL_NS:
        return (L_m + np.log(a_m / loc)
                + np.log((1.0 + substrate_cos(loc, c)) / (1.0 + substrate_cos(a_m, c))))
    return L_m + 0.0 * loc


@jit
def material_residual(code, x, kappa, loc, c, w, a_m, L_m):
    """Material condition J0 - target (NaN outside the model); J1 is not needed."""
    st = state(code, x, kappa, loc, c, w, a_m, False)
    if not st[6]:  # outside the model: NaN even under complex evaluation, where sqrt stays finite
        return complex(math.nan, math.nan)
    return st[5] - material_target(code, loc, c, a_m, L_m)


@jit
def bracket(code, loc, c, w, a_m):
    """(lo, hi) of the unknown (no slip: t where eq. 62 has a real angle; frictionless: a inside the substrate)."""
    if code == PIN_FR:
        lim = min(1.0, 1.0 / c) if c > 0 else 1.0
        return 1e-9 * a_m, (1.0 - 1e-9) * lim
    # t where eq. (62) has a real angle, for G = loc (no-slip pinning) or G = w (delamination)
    s = math.sqrt(2.0 * (loc if code == PIN_NS else w))
    return max(1.0 - s, s - 1.0, 0.0) + 1e-12, 1.0 + s - 1e-12


@jit
def is_implicit(code):
    return code == PIN_NS or code == PIN_FR or code == DEL_NS


@jit
def evaluate_batch(code, x, kappa, loc, c, w, a_m):
    """Observables row by row; x, kappa, loc share one dtype (float64 or complex128).

    Returns
    -------
    out : ndarray, shape (7, n), dtype of the inputs
        Rows ``a, alpha, p, d, f, G, J0``.
    ok : ndarray of bool
    """
    n = loc.size
    out = np.empty((7, n), dtype=loc.dtype)
    ok = np.empty(n, dtype=np.bool_)
    for i in range(n):
        st = state(code, x[i], kappa[i], loc[i], c, w, a_m, True)
        a, alpha, d, f, G, j0, good = st
        out[0, i], out[1, i], out[2, i], out[3, i] = a, alpha, kappa[i] + 0.0 * f, d
        out[4, i], out[5, i], out[6, i] = f, G, j0
        ok[i] = good
    return out, ok


@jit
def first_bad(ok, a, alpha, p, d, f, G):
    """Index of the first state outside the model or with a non-finite observable; -1 if none."""
    for i in range(ok.size):
        if not (ok[i] and math.isfinite(a[i]) and math.isfinite(alpha[i]) and math.isfinite(p[i])
                and math.isfinite(d[i]) and math.isfinite(f[i]) and math.isfinite(G[i])):
            return i
    return -1


@jit
def observe(code, x, k, loc, c, w, a_m, out):
    """Observables a, alpha, p, d, f, G, J0 of one real state into ``out``; returns ``ok``."""
    a, alpha, d, f, G, j0, ok = state(code, x, k, loc, c, w, a_m, True)
    out[0], out[1], out[2], out[3], out[4], out[5], out[6] = a, alpha, k, d, f, G, j0
    return ok


@jit
def admissible(ok, out):
    """ok and a, alpha, p, d, f, G finite (an accepted state)."""
    if not ok:
        return False
    for j in range(6):
        if not math.isfinite(out[j]):
            return False
    return True


@jit
def clamp_margin(code, x, kappa, loc, c, w, a_m):
    """1 - |sin theta| at the clamp, sin theta(1) = (kappa + D)/sqrt(1 + C2): 0 at the Case I limit."""
    _, _, D, C2, _ = unpack(code, x, kappa, loc, c, w, a_m)
    return 1.0 - abs((kappa + D) / math.sqrt(1.0 + C2))
