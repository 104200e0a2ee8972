"""The joint posterior of a test series (:mod:`.global_mcmc`): its target, its priors, a checked start.

:class:`SeriesTarget` has the interface of :class:`.posterior.Target`, so :func:`.mcmc.sample_posterior`
and :func:`.evidence.importance_evidence` take it unchanged.
"""
from __future__ import annotations

import math

import numpy as np
from scipy import special

from ..errors import InputError
from .lsq import PENALTY
from .posterior import LogPosterior, Prior, default_priors
from .series import Values, block_sizes, series_residual

__all__ = ["SCALE_CHECK", "SHARED", "SeriesTarget", "checked_covariance", "series_priors"]

SHARED = ("work_of_adhesion", "mu_h")


class SeriesTarget(LogPosterior):
    """Log prior, log likelihood and log posterior of one slip condition's joint fit, in θ.

    The same interface as :class:`.posterior.Target` (``names``, ``ndim``, ``priors``, ``log_prior``,
    ``log_likelihood``, ``__call__``, ``to_si``), so the sampler and the evidence take either.

    Parameters
    ----------
    sf : SeriesFit
        The least-squares joint fit (members with their settled σ's, row splits, parametrisation).
    names : list of str
        SI names of θ's coordinates (offsets suffixed with the curve's index).
    priors : list of Prior
        One per coordinate.
    """

    def __init__(self, sf, names: list[str], priors: list[Prior]) -> None:
        self.internal = list(sf.best.var_names)
        if len(names) != len(self.internal) or len(priors) != len(names):
            raise ValueError(f"{len(names)} names and {len(priors)} priors for {len(self.internal)} parameters")
        self.names, self.priors, self.given = list(names), list(priors), dict(sf.given)
        self._residual = series_residual(sf.members, sf.spar)
        self.blocks = []  # (start, stop, σ, σ given)
        k = 0
        for m, (nf, na) in zip(sf.members, block_sizes(sf.members)):
            self.blocks.append((k, k + nf, m.sigma_f, sf.given["force"]))
            if na:
                self.blocks.append((k + nf, k + nf + na, m.sigma_a, sf.given["contact_radius"]))
            k += nf + na

    @property
    def noise_model(self) -> str:
        known = [k for k, v in self.given.items() if v]
        head = "Gaussian, one sigma per curve and observable"
        if len(known) == len(self.given):
            return head + ", all given"
        tail = "integrated out analytically under p(sigma) ∝ 1/sigma (block by block)"
        return head + (f"; {', '.join(known)} given, the others " if known else "; ") + tail

    def residual(self, theta: np.ndarray) -> np.ndarray:
        """The joint least-squares residual at θ (each block in units of its σ)."""
        return self._residual(Values(zip(self.internal, map(float, theta))))

    def log_likelihood(self, theta: np.ndarray) -> float:
        r = self.residual(theta)
        if np.any(r == PENALTY):  # a curve outside the model's domain (the residual's marker)
            return -math.inf
        total = 0.0
        for lo, hi, sigma, given in self.blocks:
            ss, n = float(r[lo:hi] @ r[lo:hi]), hi - lo
            if given:
                total += -0.5 * ss - 0.5 * n * math.log(2.0 * math.pi * sigma**2)
            else:
                total += math.log(0.5) + special.gammaln(0.5 * n) - 0.5 * n * math.log(math.pi * ss * sigma**2)
        return total


def _scene_priors(scenes) -> dict:
    first = dict(scenes[0].priors)
    for sc in scenes[1:]:
        if dict(sc.priors) != first:
            raise InputError("[priors]", f"{sc.source}", "the same [priors] table in every curve's scene "
                             "(the shared W_ad and μh have one prior); remove it or make them agree")
    return first


def series_priors(joint: dict, scenes) -> tuple[list[str], list[Prior]]:
    """Coordinate names and priors of the joint posterior (the same for every slip condition).

    Per curve :func:`.posterior.default_priors` with that curve's least-squares offsets and the joint
    W_ad and μh of every slip condition; the shared values' priors are curve 0's (they use only the
    shared estimates, so every curve gives the same)."""
    scene_priors = _scene_priors(scenes)
    first = next(iter(joint.values()))
    si = [sf.spar.si(sf.best.params) for sf in joint.values()]
    names, priors = [], []
    for i, m in enumerate(first.members):
        pri = default_priors(m.par, [{**shared, **offs[i]} for shared, offs in si], scene_priors)
        for name in m.par.names:
            if name in SHARED and i > 0:
                continue
            names.append(name if name in SHARED else f"{name}_{i}")
            priors.append(pri[name])
    return names, priors


#: the start covariance's scale along a coordinate is widened when the posterior's own scale there
#: exceeds it by more than this factor (never narrowed: :func:`checked_covariance`)
SCALE_CHECK = 2.0


def checked_covariance(target, theta0: np.ndarray, cov0: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The start covariance with every coordinate's scale checked against the log posterior itself.

    Least squares gives the covariance from a finite-difference Jacobian; a kink in the contact-radius
    model or a rugged objective can make one standard error far too small or too large, and the
    sampler's start ball and first proposal would inherit it.  Along each coordinate k the drop of the
    log posterior d(h) = ln π(θ0) - ½[ln π(θ0 + h e_k) + ln π(θ0 - h e_k)] is evaluated at h = the
    conditional standard deviation s_k = 1/sqrt((C⁻¹)_kk) (and once more at the new estimate);
    a Gaussian gives d = h²/(2 s²).  Where the estimate exceeds s_k by more than the factor
    :data:`SCALE_CHECK`, that row and column of C are widened (correlations kept).  A scale is never
    narrowed: next to a curve's fold the log posterior has a square-root cusp, so its drop over one
    step overstates the curvature (on three-curve series with the contact radius the check halved
    scales that were already 2-7 times too small), and a too-wide start only costs the tuning some
    acceptance while a too-narrow one slows it down.  Costs 2–4 evaluations per coordinate.

    Returns
    -------
    (covariance, ratios) : the corrected covariance and the per-coordinate scale factors applied.
    """
    cov0 = np.atleast_2d(np.asarray(cov0, float))
    lp0 = target(theta0)
    ratio = np.ones(theta0.size)
    if not math.isfinite(lp0):
        return cov0, ratio
    cond = 1.0 / np.sqrt(np.clip(np.diag(np.linalg.pinv(cov0)), 1e-300, None))
    for k in range(theta0.size):
        h, r, d = cond[k], 1.0, float("nan")
        for _ in range(2):
            e = np.zeros(theta0.size)
            e[k] = h
            d = lp0 - 0.5 * (target(theta0 + e) + target(theta0 - e))
            if not math.isfinite(d):
                break
            est = h / math.sqrt(2.0 * d) if d > 1e-3 else 10.0 * h  # flat: look further out
            r = float(np.clip(est / cond[k], 0.1, 30.0))
            if abs(math.log(est / h)) < math.log(1.3):
                break
            h = r * cond[k]
        ratio[k] = r if math.isfinite(d) and r > SCALE_CHECK else 1.0  # widen only (see docstring)
    return cov0 * np.outer(ratio, ratio), ratio
