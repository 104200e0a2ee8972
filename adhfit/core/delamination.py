"""Delamination (paper section 3.3): G = w while the edge recedes.

No slip (3.3.1): the contacting membrane is frozen in its making-contact state, so the material point
at radius a_d follows from eq. (61); the condition G = w (eq. 62) gives the contact angle explicitly
from the stretch jump t: cos(alpha) = 1 - (w - (t - 1)^2/2) / t. The unknown is t, inside
max(1 - sqrt(2w), sqrt(2w) - 1) <= t <= 1 + sqrt(2w) (where 0 <= alpha <= pi).

Frictionless (3.3.2): alpha = atan(sqrt(2w)) is constant (eq. 63), so the state is explicit in a.
Dimensionless, lengths over b, c = 1/rs.
"""
from __future__ import annotations

import numpy as np

from .membrane import substrate_cos

__all__ = ["noslip_angle", "noslip_stretch_bracket", "noslip_material", "frictionless_angle"]


def noslip_angle(t, w):
    """Contact angle alpha (rad) that makes G = w at stretch jump t (eq. 62 solved for alpha)."""
    return np.arccos(1.0 - (w - 0.5 * (t - 1.0) ** 2) / t)


def noslip_stretch_bracket(w, margin=1e-12):
    """The interval of t on which eq. (62) has a real contact angle in [0, pi] (w may be an array)."""
    s = np.sqrt(2.0 * np.asarray(w, dtype=float))
    return np.maximum(np.maximum(1.0 - s, s - 1.0), 0.0) + margin, 1.0 + s - margin


def noslip_material(a, a_m, c, L_m):
    """ln(beta/rho_ad) of the edge at radius a, from eq. (61) and L_m = ln(beta/rho_am)."""
    return L_m + np.log(a_m / a) + np.log((1.0 + substrate_cos(a, c)) / (1.0 + substrate_cos(a_m, c)))


def frictionless_angle(w):
    """Constant contact angle of frictionless delamination, eq. (63): atan(sqrt(2w))."""
    return np.arctan(np.sqrt(2.0 * w))
