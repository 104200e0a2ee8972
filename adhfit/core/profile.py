"""The deformed membrane profile z(r) of one state, computed only on request.

Coordinates as the paper's Fig. 2: z = 0 at the clamp r = 1, z < 0 toward the substrate, whose apex
is at z = -d. The contacting membrane lies on the substrate, z = -d - sag(r) for r <= a. The free
membrane follows eqs. (46)-(47) without the spurious 1/b: z(r) = -int_r^1 tan(theta) dr, and on the
theta_a > pi/2 branch (no slip, eq. 47) the overhang between eta and a is
z(r) = -(int_eta^r + int_eta^1) tan(theta) dr, eta^2 the smaller root of Q. Lengths over b.
"""
from __future__ import annotations

import numpy as np

from .membrane import rise_many, roots

__all__ = ["profile", "constants_of_row"]


def _rise(kappa, D, C2, x, y, y_is_root: bool):
    """J1 from u = y to u = x, row by row (the compiled :func:`.membrane.rise`)."""
    x, y = np.broadcast_arrays(np.asarray(x, float), np.asarray(y, float))
    return rise_many(float(kappa), float(D), float(C2), np.ascontiguousarray(x),
                     np.ascontiguousarray(y), bool(y_is_root))


def sag(a, c):
    """Depth of the substrate at radius a below its apex, rs - sqrt(rs^2 - a^2), finite for rs = inf."""
    return a * a * c / (1.0 + np.sqrt(1.0 - (a * c) ** 2))


def edge_angles(a, c, alpha):
    """sin and cos of the membrane tangent at the contact edge, theta_a = alpha - asin(a/rs) (eq. 22)."""
    s, ac = np.sqrt(1.0 - (a * c) ** 2), a * c
    return s * np.sin(alpha) - ac * np.cos(alpha), s * np.cos(alpha) + ac * np.sin(alpha)


def constants_of_row(stage: str, slip: str, a: float, alpha: float, p: float, f: float, G: float,
                     c: float) -> tuple[float, float]:
    """(D, C2) of a history row, from its own columns.

    D = -f/pi (eqs. 26, 50, 59). C2: 0 while making contact, a^2 tan^2(alpha) when frictionless
    (eq. 55); for no slip C2 = a^2 (t^2 - 1) with t a root of eq. (52),
    t = cos(alpha) +/- sqrt(cos^2(alpha) - 1 + 2G), the one that reproduces D through eq. (39).
    """
    D = -f / np.pi
    if stage == "making_contact" or (alpha == 0.0 and G == 0.0):
        return D, 0.0
    if slip == "frictionless":
        return D, (a * np.tan(alpha)) ** 2
    ca = np.cos(alpha)
    disc = np.sqrt(max(ca * ca - 1.0 + 2.0 * G, 0.0))
    sin_ta, _ = edge_angles(a, c, alpha)
    cands = [ca + disc, ca - disc]
    t = min(cands, key=lambda tt: (abs(sin_ta * a * tt - p * a * a - D), abs(tt - 1.0)))
    return D, a * a * (t * t - 1.0)


def profile(stage: str, slip: str, *, a: float, alpha: float, p: float, d: float, f: float, G: float,
            rs: float, n: int = 200) -> tuple[np.ndarray, np.ndarray]:
    """z(r) over 0 <= r <= 1 for one history row (dimensionless, lengths over b).

    Parameters
    ----------
    stage, slip : str
        The row's stage and the interface condition.
    a, alpha, p, d, f, G : float
        The row's columns (docs/contracts.md A1).
    rs : float
        R_s / b (inf for flat).
    n : int
        Points on the free membrane (the contact region gets n // 4 more).

    Returns
    -------
    r, z : ndarray
        In history order along the membrane from the centre to the clamp (on the theta_a > pi/2
        branch r first decreases from a to eta, then increases to 1).
    """
    c = 0.0 if np.isinf(rs) else 1.0 / rs
    if a == 0.0:  # free inflation (eq. 14): the cap -int_r^1 p s / sqrt(1 - p^2 s^2) ds, no 1/p
        r = np.linspace(0.0, 1.0, n)
        return r, -p * (1.0 - r * r) / (np.sqrt(1.0 - (p * r) ** 2) + np.sqrt(1.0 - p * p))
    D, C2 = constants_of_row(stage, slip, a, alpha, p, f, G, c)
    rc = np.linspace(0.0, a, max(n // 4, 2))
    zc = -d - sag(rc, c)
    _, cos_ta = edge_angles(a, c, alpha)
    q, um = roots(float(p), float(D), float(C2))
    if cos_ta >= 0.0:
        r = a + (1.0 - a) * np.linspace(0.0, 1.0, n)
        z = -_rise(p, D, C2, np.ones(n), r * r, False)
        z[-1] = 0.0
        # the point r = a is the free membrane's own (its rise from the edge), not the substrate's
        return np.concatenate([rc[:-1], r]), np.concatenate([zc[:-1], z])
    eta = float(np.sqrt(um))
    # overhang a -> eta (r decreasing), then eta -> 1
    r1 = a - (a - eta) * np.linspace(0.0, 1.0, n // 2)
    tail = _rise(p, D, C2, np.ones(1), np.array([um]), True)[0]
    z1 = -(_rise(p, D, C2, r1 * r1, np.full(r1.size, um), True) + tail)
    r2 = eta + (1.0 - eta) * np.linspace(0.0, 1.0, n - n // 2)
    z2 = -_rise(p, D, C2, np.ones(r2.size), r2 * r2, False)
    z1[-1], z2[0], z2[-1] = -tail, -tail, 0.0
    return np.concatenate([rc[:-1], r1, r2[1:]]), np.concatenate([zc[:-1], z1, z2[1:]])
