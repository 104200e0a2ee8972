"""Closed forms of the two integrals over the free membrane (DESIGN.md B2).

Every integral of the paper's sections 3.1-3.3 is one of (lengths over b, u = r^2)::

    J0 = int dr / sqrt(Q),   J1 = int (kappa r^2 + D) dr / sqrt(Q),
    Q(r) = (r^2 + C2) - (kappa r^2 + D)^2 = (q - kappa^2 u)(u - u_minus)

J0 is the log-material coordinate ln(beta / rho) of eqs. (35), (37), (41), (42), (57); J1 is the rise of
the free membrane, -z at the inner limit (eqs. 24-25, 46-47, 58, without the paper's spurious 1/b).
With u = r^2 the integrand has three linear factors, so both are Carlson symmetric integrals (DLMF
19.29.4-19.29.7): exact, continuous through kappa = 0, no tolerance.

All functions accept real or complex arrays: complex inputs carry complex-step derivatives through
the engine's solves.  Dimensionless throughout.
"""
from __future__ import annotations

import numpy as np
from scipy.special import elliprd, elliprf

__all__ = ["quadratic_roots", "free_membrane_integrals"]


def quadratic_roots(kappa, D, C2):
    """Factor Q(u) = (q - kappa^2 u)(u - u_minus) without dividing by kappa.

    Parameters
    ----------
    kappa, D, C2 : array_like
        Dimensionless pressure Pb/(2 mu h), D = kappa C1/b^2, C2 = C2bar/b^2.

    Returns
    -------
    q, u_minus : ndarray
        ``u_plus = q / kappa^2`` is the upper root (infinite at kappa = 0) and ``u_minus = -C/q`` the
        lower one, with C = C2 - D^2.  Stable formulas of DESIGN.md B2.
    """
    B = 1.0 - 2.0 * kappa * D
    C = C2 - D * D
    sq = np.sqrt(1.0 - 4.0 * kappa * D + 4.0 * kappa * kappa * C2)
    pos = np.real(B) >= 0.0
    # the two algebraically equal forms of q; each avoids cancellation on its side of B = 0
    den = np.where(pos, 1.0, sq - B)
    q = np.where(pos, 0.5 * (B + sq), 2.0 * kappa * kappa * C / den)
    return q, -C / q


def _carlson_pair(kappa, C, Lx, Ly, span):
    """J0 and J1 from the factor values at the limits (DLMF 19.29.4, 19.29.7 with u = r^2)."""
    X = [np.sqrt(v) for v in Lx]
    Y = [np.sqrt(v) for v in Ly]
    U12 = (X[0] * X[1] * Y[2] + Y[0] * Y[1] * X[2]) / span
    U13 = (X[0] * X[2] * Y[1] + Y[0] * Y[2] * X[1]) / span
    U23 = (X[1] * X[2] * Y[0] + Y[1] * Y[2] * X[0]) / span
    s12, s13, s23 = U12 * U12, U13 * U13, U23 * U23
    j0 = elliprf(s12, s13, s23)
    # int u du / (2 sqrt(L1 L2 L3)) = C/3 R_D + sqrt(x y)/U12; sqrt(x y) = X3 Y3
    ju = C / 3.0 * elliprd(s13, s23, s12) + X[2] * Y[2] / U12
    return j0, ju


def free_membrane_integrals(kappa, D, C2, a, q_edge, through_root):
    """J0 and J1 over the free membrane, from the contact edge r = a to the clamp r = 1.

    Parameters
    ----------
    kappa, D, C2 : array_like
        Free-membrane constants (dimensionless, DESIGN.md B1).
    a : array_like
        Contact radius over b, 0 < a < 1.
    q_edge : array_like
        Q(a^2), known exactly as (a^2 + C2) cos^2(theta_a) (eq. 22); used instead of the factor that
        would be computed by subtracting near-equal numbers when the edge tangent is near vertical.
    through_root : array_like of bool
        True on the no-slip branch theta_a > pi/2 (eqs. 42, 47): the membrane first runs inward to
        r = eta, eta^2 = u_minus (the smaller root, eq. 44), then out to the clamp, and both integrals
        are the sums over [eta, a] and [eta, 1].

    Returns
    -------
    J0, J1 : ndarray
        J0 = ln(beta / rho_a) (eqs. 35, 41, 42, 57); J1 = -z(a), the rise from the contact edge to the
        clamp (eqs. 25, 46-48, 58).

    Notes
    -----
    Where the state is outside the model (Q < 0 somewhere on the path: Case II at the clamp, or an
    edge inside the forbidden band) the factors go negative and the result is NaN; callers check
    :func:`admissible` before trusting a value.
    """
    kappa, D, C2, a = np.broadcast_arrays(*(np.asarray(v) for v in (kappa, D, C2, a)))
    q, um = quadratic_roots(kappa, D, C2)
    k2 = kappa * kappa
    C = C2 - D * D
    ea = a * a
    # factors at the edge: L1 = q - k^2 a^2, L2 = a^2 - u_minus, L3 = a^2; the smaller of L1, L2 is
    # recomputed from the exact Q(a^2) = L1 L2
    L1e = q - k2 * ea
    L2e = ea - um
    small1 = np.abs(L1e) < np.abs(L2e)
    L1e, L2e = (np.where(small1, q_edge / np.where(small1, L2e, 1.0), L1e),
                np.where(small1, L2e, q_edge / np.where(small1, 1.0, L1e)))
    Lc = (q - k2, 1.0 - um, np.ones_like(ea))          # factors at the clamp u = 1
    Le = (L1e, L2e, ea)
    tr = np.asarray(through_root, dtype=bool)
    if not np.any(tr):
        j0, ju = _carlson_pair(kappa, C, Lc, Le, 1.0 - ea)
        return j0, kappa * ju + D * j0
    zero = np.zeros_like(L2e)
    Lr = (q - k2 * um, zero, um)                        # factors at the root u = u_minus
    j0o, juo = _carlson_pair(kappa, C, Lc, Le, 1.0 - ea)          # ordinary path a -> 1
    j0a, jua = _carlson_pair(kappa, C, Le, Lr, np.where(tr, L2e, 1.0))   # eta -> a
    j0b, jub = _carlson_pair(kappa, C, Lc, Lr, 1.0 - um)             # eta -> 1
    j0 = np.where(tr, j0a + j0b, j0o)
    ju = np.where(tr, jua + jub, juo)
    return j0, kappa * ju + D * j0


def admissible(kappa, D, C2, a, q_edge, through_root):
    """Whether the free membrane from the edge to the clamp has Q >= 0 everywhere (Case I).

    On the ordinary path the interval [a^2, 1] must lie inside [u_minus, u_plus]; on the
    theta_a > pi/2 path [u_minus, 1] must lie below u_plus and u_minus >= 0.
    """
    q, um = quadratic_roots(kappa, D, C2)
    k2 = kappa * kappa
    clamp_ok = np.real(q - k2) >= 0.0
    edge_ok = np.real(q_edge) >= 0.0
    tr = np.asarray(through_root, dtype=bool)
    root_ok = np.where(tr, np.real(um) >= 0.0, True)
    return clamp_ok & edge_ok & root_ok
