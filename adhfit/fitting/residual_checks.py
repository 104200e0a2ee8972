"""Checks on the residuals of a fit that the χ² alone cannot make (issue 9).

* **Serially correlated noise** (rows far denser than the noise correlation, e.g. an oversampled
  load cell with a low-pass filter): the lag-1 autocorrelation ρ of the residuals in row order.  For
  white noise ρ̂ ~ N(-1/n, 1/n), so ρ̂ > max(0.2, 3/√n) happens by chance with probability < 0.2 %.
  When it fires, the rows carry fewer independent observations: for AR(1) noise the effective
  number is n (1 - ρ)/(1 + ρ), so standard errors and interval half-widths grow by
  sqrt((1 + ρ)/(1 - ρ)) and ΔBIC shrinks by that factor squared.
* **Load-cell zero drift**: the rows the model predicts at zero force (before contact and after
  detachment) pin the load-cell zero; if the two groups disagree by more than 4 standard errors,
  the zero has drifted during the test.
"""
from __future__ import annotations

import dataclasses
import math

import numpy as np

from .result import Estimate

__all__ = ["lag1_autocorrelation", "correlation_factor", "widen", "zero_drift", "RHO_MIN"]

#: smallest lag-1 autocorrelation that counts as correlated noise (with 3/sqrt(n))
RHO_MIN = 0.2
#: ρ used at most in the widening (the AR(1) factor diverges at 1)
RHO_CAP = 0.95
#: rows per group needed before the zero-drift check speaks
MIN_ZERO_ROWS = 4


def lag1_autocorrelation(r: np.ndarray) -> float:
    """Lag-1 autocorrelation of a residual vector in row order (0 for fewer than 3 rows)."""
    r = np.asarray(r, float)
    r = r[np.isfinite(r)]
    if r.size < 3:
        return 0.0
    d = r - r.mean()
    den = float(d @ d)
    return float(d[1:] @ d[:-1]) / den if den > 0 else 0.0


def correlation_factor(r: np.ndarray) -> tuple[float, float]:
    """(ρ, factor): the lag-1 autocorrelation and the interval widening sqrt((1 + ρ)/(1 - ρ));
    factor is 1 unless ρ exceeds max(:data:`RHO_MIN`, 3/√n)."""
    rho = lag1_autocorrelation(r)
    n = max(int(np.size(r)), 1)
    if rho <= max(RHO_MIN, 3.0 / math.sqrt(n)):
        return rho, 1.0
    rc = min(rho, RHO_CAP)
    return rho, math.sqrt((1.0 + rc) / (1.0 - rc))


def _stretch(value: float, bound: float | None, factor: float, log: bool) -> float | None:
    if bound is None:
        return None
    if log and value > 0 and bound > 0:
        return math.exp(math.log(value) + factor * (math.log(bound) - math.log(value)))
    return value + factor * (bound - value)


def widen(e: Estimate, factor: float) -> Estimate:
    """The estimate with its standard error and interval widened by ``factor`` about its value
    (in ln for W_ad and μh, where the intervals are computed)."""
    if factor == 1.0:
        return e
    log = e.name in ("work_of_adhesion", "mu_h")
    ci = None if e.ci95 is None else tuple(_stretch(e.value, b, factor, log) for b in e.ci95)
    cov = None if e.ci95_covariance is None else tuple(_stretch(e.value, b, factor, log)
                                                       for b in e.ci95_covariance)
    return dataclasses.replace(e, stderr=None if e.stderr is None else e.stderr * factor, ci95=ci,
                               ci95_covariance=cov,
                               ci_method=f"{e.ci_method} (widened x{factor:.2g} for correlated noise)")


def zero_drift(resid: np.ndarray, before: np.ndarray, after: np.ndarray, sigma: float,
               f_peak: float) -> str | None:
    """A plain warning when the force before contact and after detachment disagree.

    Parameters
    ----------
    resid : ndarray
        Measured minus fitted force at every row, N.
    before, after : ndarray of bool
        Rows the model puts at zero force before contact and after detachment.
    sigma : float
        Force noise, N.
    f_peak : float
        Largest measured force, N (for the percentage).
    """
    if before.sum() < MIN_ZERO_ROWS or after.sum() < MIN_ZERO_ROWS or not sigma > 0:
        return None
    m1, m2 = float(np.mean(resid[before])), float(np.mean(resid[after]))
    se = sigma * math.sqrt(1.0 / before.sum() + 1.0 / after.sum())
    d = m2 - m1
    if abs(d) <= 4.0 * se:
        return None
    return (f"The load-cell zero drifted during the test: the force after detachment differs from the force "
            f"before contact by {d * 1e3:.3g} mN ({100 * abs(d) / f_peak:.2g} % of the peak force). The fit uses "
            f"one zero for the whole test; re-tare the load cell or remove the drift before fitting.")
