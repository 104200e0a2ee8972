"""The covariance of a global fit from a Jacobian taken at the scale of the data, not at a point.

Why: a measured row that sits next to a curve's turning point (the fold where the attached branch
ends and the membrane pulls off) has a model value that varies as the square root of its distance to
the fold, so its residual has an infinite slope in that curve's offset and in W_ad and μh (which move
the fold).  The optimiser's finite-difference Jacobian (steps of ~1e-6 of a parameter) sees that
slope, and the covariance inv(JᵀJ) then pins the offset ~100-fold too tightly and hands that curve
most of the W_ad precision: the shared intervals come out too narrow (the recovery study's z-scores of
contact-radius fits scattered with sd 1.3).  Which curve is hit depends only on where its rows fall
relative to its fold.

Here each column of J is a central secant over ±h_k, h_k the parameter's own conditional standard
deviation found from the residual itself: starting at the optimiser's value, h is rescaled until
χ²(θ ± h e_k) rises by ~1 on average (:data:`MAX_ROUNDS` rounds).  Where the model is smooth this
is the usual Gauss-Newton covariance; at a fold it averages the square-root cusp over the range the
data actually allow.
"""
from __future__ import annotations

import math

import numpy as np

from .lsq import PENALTY

__all__ = ["MAX_ROUNDS", "secant_covariance"]

MAX_ROUNDS = 5


def _chi2(residual, params, names, theta) -> float:
    p = params.copy()
    for n, t in zip(names, theta):
        p[n].value = float(np.clip(t, p[n].min, p[n].max))
    r = residual(p)
    return math.inf if np.any(r == PENALTY) else float(r @ r)


def _residual_at(residual, params, names, theta) -> np.ndarray:
    p = params.copy()
    for n, t in zip(names, theta):
        p[n].value = float(t)
    return np.asarray(residual(p), float)


def _scale(residual, params, names, theta0, k, h, chi0) -> float:
    """The step along coordinate k at which χ² rises by ~1 (a conditional standard deviation)."""
    for _ in range(MAX_ROUNDS):
        e = np.zeros(theta0.size)
        e[k] = h
        rise = 0.5 * (_chi2(residual, params, names, theta0 + e) + _chi2(residual, params, names, theta0 - e)) - chi0
        if not math.isfinite(rise):
            return h * 0.5
        new = h / math.sqrt(rise) if rise > 1e-6 else 10.0 * h
        new = float(np.clip(new, h / 30.0, 30.0 * h))
        if abs(math.log(new / h)) < math.log(1.3):
            return new
        h = new
    return h


def secant_covariance(residual, best) -> tuple[np.ndarray | None, np.ndarray | None]:
    """(covariance, steps) of the varying parameters of ``best`` (an lmfit result whose residual is in
    units of σ), in ``best.var_names`` order; ``(None, None)`` when it cannot be formed."""
    names = list(best.var_names)
    params = best.params
    theta0 = np.array([params[n].value for n in names])
    c0 = best.covar
    se0 = np.sqrt(np.clip(np.diag(c0), 1e-24, None)) if c0 is not None else np.full(theta0.size, 1e-3)
    chi0 = _chi2(residual, params, names, theta0)
    if not math.isfinite(chi0):
        return None, None
    steps = np.array([_scale(residual, params, names, theta0, k, float(se0[k]), chi0) for k in range(theta0.size)])
    cols = []
    for k, h in enumerate(steps):
        e = np.zeros(theta0.size)
        e[k] = h
        rp, rm = _residual_at(residual, params, names, theta0 + e), _residual_at(residual, params, names, theta0 - e)
        if np.any(rp == PENALTY) or np.any(rm == PENALTY):
            return None, None
        cols.append((rp - rm) / (2.0 * h))
    jac = np.column_stack(cols)
    return np.linalg.pinv(jac.T @ jac), steps


def apply_secant(sf) -> bool:
    """Replace the optimiser's covariance and standard errors of a :class:`~.global_stage.SeriesFit` by
    :func:`secant_covariance` (kept: ``sf.secant_steps``, the steps used); False when it cannot be formed."""
    cov, steps = secant_covariance(sf.residual, sf.best)
    sf.secant_steps = steps
    if cov is None or not np.all(np.isfinite(cov)) or np.any(np.diag(cov) <= 0):
        return False
    sf.best.covar = cov
    for k, n in enumerate(sf.best.var_names):
        sf.best.params[n].stderr = float(math.sqrt(cov[k, k]))
    return True
