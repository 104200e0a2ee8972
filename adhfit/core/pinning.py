"""Contact pinning (paper section 3.2): the contact edge keeps its material point rho_am.

No slip (3.2.1): the contact radius stays a_m. The unknown is t = lambda1+/lambda2 = T1+/(mu h) =
sqrt(1 + C2/a^2), the jump of the meridional stretch across the edge (eqs. 32, 51-52): C2 = a^2 (t^2 - 1)
and eq. (39) times kappa gives D = sin(theta_a) a t - kappa a^2. Working in t rather than C2 keeps the
unknown O(1); the pinning states are located by G itself (see ``branches``).

Frictionless (3.2.2): the edge slides; C2 = a^2 tan^2 alpha (eq. 55), D from eq. (56) times kappa, and
G = tan^2(alpha)/2 (eq. 60). The unknown is the contact radius a (eq. 57).
Dimensionless, lengths over b, c = 1/rs.
"""
from __future__ import annotations

import numpy as np

from .membrane import edge_angles, substrate_cos

__all__ = ["noslip_constants", "noslip_release_rate", "frictionless_constants",
           "frictionless_release_rate"]


def noslip_constants(kappa, a, c, alpha, t):
    """(D, C2) for no slip at contact angle alpha and stretch jump t (eqs. 38-39)."""
    sin_ta, _ = edge_angles(a, c, alpha)
    return sin_ta * a * t - kappa * a * a, a * a * (t * t - 1.0)


def noslip_release_rate(alpha, t):
    """G/(mu h) for no slip, eq. (52): t (1 - cos alpha) + (t - 1)^2 / 2."""
    return t * (1.0 - np.cos(alpha)) + 0.5 * (t - 1.0) ** 2


def frictionless_constants(kappa, a, c, alpha):
    """(D, C2) for frictionless contact at contact radius a and angle alpha (eqs. 55-56)."""
    ta = np.tan(alpha)
    return a * substrate_cos(a, c) * ta - (kappa + c) * a * a, (a * ta) ** 2


def frictionless_release_rate(alpha):
    """G/(mu h) for frictionless contact, eq. (60): tan^2(alpha) / 2."""
    return 0.5 * np.tan(alpha) ** 2
