"""Making contact (paper section 3.1): adhesionless, frictionless, alpha = 0.

Eq. (19) in the DESIGN.md B1 form: C2 = 0 and D = kappa C1 = -(kappa + 1/rs) a^2; force eq. (26)
f = -pi D = pi (kappa + 1/rs) a^2. Dimensionless, lengths over b, c = 1/rs.
"""
from __future__ import annotations

import numpy as np

__all__ = ["constants"]


def constants(kappa, a, c):
    """(D, C2) of the free membrane while making contact, eq. (19)."""
    D = -(kappa + c) * a * a
    return D, np.zeros_like(D)
