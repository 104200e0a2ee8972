"""The free (non-contacting) membrane between the contact edge and the clamp, shared by all stages.

Each stage only decides the two constants (D, C2) of eq. (38), sin(theta) = (kappa r^2 + D)/sqrt(r^2 + C2);
this module turns them into the observables: the material coordinate of the edge (J0), the gap d
(eqs. 25, 48, 58) and the force f = -pi D (eqs. 26, 50, 59). Dimensionless, lengths over b; c = 1/rs
is the substrate curvature (0 for a flat substrate). Complex inputs are allowed (complex-step
derivatives).
"""
from __future__ import annotations

import numpy as np

from .integrals import admissible, free_membrane_integrals

__all__ = ["substrate_cos", "sag", "edge_angles", "free_membrane"]


def substrate_cos(a, c):
    """cos of the substrate slope at radius a: sqrt(1 - (a/rs)^2)."""
    return np.sqrt(1.0 - (a * c) ** 2)


def sag(a, c):
    """Depth of the substrate at radius a below its apex, rs - sqrt(rs^2 - a^2), finite for rs = inf."""
    return a * a * c / (1.0 + substrate_cos(a, c))


def edge_angles(a, c, alpha):
    """sin and cos of the membrane tangent at the contact edge, theta_a = alpha - asin(a/rs) (eq. 22)."""
    s, ac = substrate_cos(a, c), a * c
    sa, ca = np.sin(alpha), np.cos(alpha)
    return s * sa - ac * ca, s * ca + ac * sa


def free_membrane(kappa, D, C2, a, c, cos_ta):
    """Observables of the free membrane for given constants.

    Parameters
    ----------
    kappa, D, C2 : array_like
        Pressure Pb/(2 mu h) and the constants of eq. (38) in the DESIGN.md B1 form.
    a : array_like
        Contact radius over b.
    c : float
        Substrate curvature b/R_s (0 when flat).
    cos_ta : array_like
        cos(theta_a) at the edge; its sign selects the theta_a > pi/2 branch (eqs. 42, 47).

    Returns
    -------
    J0 : ndarray
        ln(beta/rho_a), the material coordinate of the edge (lambda0-free).
    d : ndarray
        Gap between the clamp and the substrate apex over b: -z(a) - sag(a) (eqs. 25, 48, 58).
    ok : ndarray of bool
        The state is inside the model (Q >= 0 along the free membrane, Case I at the clamp).
    """
    q_edge = (a * a + C2) * cos_ta * cos_ta
    through = np.real(cos_ta) < 0.0
    with np.errstate(all="ignore"):
        j0, j1 = free_membrane_integrals(kappa, D, C2, a, q_edge, through)
        ok = admissible(kappa, D, C2, a, q_edge, through)
    return j0, j1 - sag(a, c), ok
