"""Free inflation (paper section 2.3): the Case I spherical cap. Dimensionless, lengths over b."""
from __future__ import annotations

import numpy as np

__all__ = ["apex_deflection", "critical_pressure"]


def apex_deflection(p):
    """Apex deflection d0/b of the freely inflated membrane at pressure p = Pb/(2 mu h), |p| <= 1.

    Eq. (15) rewritten without cancellation, d0 = p / (1 + sqrt(1 - p^2)): finite at p = 0 and the
    correct (Case I) cap for p < 0 (docs/numerics.md C). NaN for |p| > 1, where no Case I cap exists.
    """
    p = np.asarray(p)
    with np.errstate(invalid="ignore"):
        return p / (1.0 + np.sqrt(1.0 - p * p))


def critical_pressure(d):
    """Pressure at which the free cap's apex reaches a substrate at gap d (eq. 64): 2d/(1+d^2)."""
    d = np.asarray(d)
    return 2.0 * d / (1.0 + d * d)
