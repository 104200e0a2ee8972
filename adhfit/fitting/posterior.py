"""The posterior of one slip condition: priors and the Gaussian likelihood of the least-squares residual.

Parameters are sampled in the least-squares fit's internal coordinates (:class:`.lsq.Parametrisation`):
θ = (ln W_ad, ln μh[, offset / control range][, force offset / largest force]).

Likelihood
----------
The residual is the one the least-squares fit minimises (:func:`.lsq.residual_function`: every row,
plus the pull-off position term), so there is one model and one residual for both methods.
The noise is Gaussian, independent, with one σ for all residuals:

* σ **given** (``--sigma``): ln L = -χ²/2 - (n/2) ln(2πσ²), χ² = Σ r²/σ²;
* σ **not given**: σ is a nuisance parameter with the scale-invariant prior p(σ) ∝ 1/σ, integrated
  out analytically: L(θ) = ½ Γ(n/2) (π RSS(θ))^(-n/2).  This is exact; the prior is improper, but it
  is the same for both slip conditions (same data, same n), so its constant cancels from their
  Bayes factor.

Priors
------
Independent, on W_ad and μh as set in the scene's ``[priors]`` table (:func:`adhfit.scene.normalize_priors`:
``loguniform``, ``uniform``, ``normal`` truncated to positive values).  **Default**: log-uniform
on [v_min/100, 100 v_max], v_min and v_max the least and largest least-squares estimate over the slip
conditions (the same prior for both, so that their evidences are comparable).  The offsets get a
uniform prior over ± the measured range of the control variable (the force offset: ± the largest
measured force), widened to contain twice any least-squares offset.  Densities are expressed in θ
(with the Jacobian), so they integrate to one there and the evidence is correct.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy import special, stats

from .lsq import PENALTY, Parametrisation, residual_function
from .model import CurveModel
from .starts import noise_estimate

__all__ = ["LogPosterior", "Prior", "Target", "default_priors", "DEFAULT_PRIOR_FACTOR", "INTERNAL_NAMES"]

#: default log-uniform priors reach this factor below and above the least-squares estimates
DEFAULT_PRIOR_FACTOR = 100.0
#: SI name -> internal (θ) name, as in :meth:`.lsq.Parametrisation.params`
INTERNAL_NAMES = {"work_of_adhesion": "ln_work_of_adhesion", "mu_h": "ln_mu_h",
                  "displacement_offset": "x_offset", "pressure_offset": "x_offset",
                  "force_offset": "force_offset"}


@dataclass(frozen=True)
class Prior:
    """The prior of one parameter (SI description; density evaluated in θ).

    Attributes
    ----------
    name : str
        Row of :data:`adhfit.params.FITTED`.
    dist : {"loguniform", "uniform", "normal"}
    a, b : float
        (min, max) for the uniform families, (mean, sd) for the normal; SI.
    log : bool
        θ is ln(value) (W_ad, μh) rather than value / ``factor`` (offsets).
    factor : float
        SI value = θ · factor for the offsets.
    source : str
        ``"scene"`` or ``"default"``.
    """

    name: str
    dist: str
    a: float
    b: float
    log: bool
    factor: float = 1.0
    source: str = "default"

    def to_si(self, t: float) -> float:
        return math.exp(t) if self.log else t * self.factor

    def logpdf(self, t: float) -> float:
        """ln of the prior density in θ (-inf outside the support)."""
        v = self.to_si(t)
        jac = t if self.log else math.log(self.factor)  # ln |d value / d θ|
        if self.dist == "loguniform":
            return -math.log(math.log(self.b / self.a)) - math.log(v) + jac if self.a <= v <= self.b else -math.inf
        if self.dist == "uniform":
            return -math.log(self.b - self.a) + jac if self.a <= v <= self.b else -math.inf
        if self.log and v <= 0:
            return -math.inf
        trunc = stats.norm.logcdf(self.a / self.b) if self.log else 0.0  # normal truncated to v > 0
        return float(stats.norm.logpdf(v, self.a, self.b)) - trunc + jac

    def describe(self) -> str:
        unit = {"work_of_adhesion": "J/m^2", "mu_h": "N/m", "force_offset": "N"}.get(
            self.name, "m" if self.name == "displacement_offset" else "Pa")
        if self.dist == "normal":
            return f"normal(mean={self.a:.4g}, sd={self.b:.4g}) {unit}" + (", truncated to > 0" if self.log else "")
        return f"{self.dist} on [{self.a:.4g}, {self.b:.4g}] {unit} ({self.source})"

    def as_dict(self) -> dict:
        keys = ("mean", "sd") if self.dist == "normal" else ("min", "max")
        return {"dist": self.dist, keys[0]: self.a, keys[1]: self.b, "source": self.source,
                "description": self.describe()}


def default_priors(par: Parametrisation, lsq_values: list[dict], scene_priors: dict) -> dict[str, Prior]:
    """Priors of every fitted parameter (module docstring), in the order of ``par.names``.

    Parameters
    ----------
    par : Parametrisation
    lsq_values : list of dict
        SI least-squares estimates of each slip condition (:meth:`Parametrisation.si`).
    scene_priors : dict
        :attr:`adhfit.scene.Scene.priors` (validated, SI).
    """
    out = {}
    for name in par.names:
        if name in ("work_of_adhesion", "mu_h"):
            if name in scene_priors:
                s = scene_priors[name]
                a, b = (s["mean"], s["sd"]) if s["dist"] == "normal" else (s["min"], s["max"])
                out[name] = Prior(name, s["dist"], float(a), float(b), True, source="scene")
                continue
            vals = [v[name] for v in lsq_values]
            out[name] = Prior(name, "loguniform", min(vals) / DEFAULT_PRIOR_FACTOR,
                              max(vals) * DEFAULT_PRIOR_FACTOR, True)
            continue
        key, factor = ("force_offset", par.f_scale) if name == "force_offset" else ("x_offset", par.x_scale)
        half = max(factor, *(2.0 * abs(v[key]) for v in lsq_values))
        out[name] = Prior(name, "uniform", -half, half, False, factor)
    return out


class _Values(dict):
    """A dict that answers ``valuesdict()`` like lmfit Parameters (what the shared residual reads)."""

    def valuesdict(self) -> dict:
        return self


class LogPosterior:
    """What a target needs besides its likelihood: ``ndim``, the prior, the posterior emcee samples and
    the map from θ back to SI values (subclasses set ``names`` and ``priors`` and define
    ``log_likelihood``)."""

    names: list[str]
    priors: list[Prior]

    @property
    def ndim(self) -> int:
        return len(self.names)

    def log_prior(self, theta: np.ndarray) -> float:
        total = 0.0
        for prior, t in zip(self.priors, theta):
            total += prior.logpdf(float(t))
            if total == -math.inf:
                break
        return total

    def log_likelihood(self, theta: np.ndarray) -> float:  # pragma: no cover - defined by subclasses
        raise NotImplementedError

    def __call__(self, theta: np.ndarray) -> float:
        """ln posterior (unnormalised): what emcee samples."""
        lp = self.log_prior(theta)
        if lp == -math.inf:
            return -math.inf
        ll = self.log_likelihood(theta)
        return lp + ll if math.isfinite(ll) else -math.inf

    def to_si(self, theta: np.ndarray) -> np.ndarray:
        """θ samples (..., ndim) -> SI values of ``self.names``."""
        theta = np.asarray(theta, float)
        out = np.empty_like(theta)
        for k, prior in enumerate(self.priors):
            out[..., k] = np.exp(theta[..., k]) if prior.log else theta[..., k] * prior.factor
        return out


class Target(LogPosterior):
    """Log prior, log likelihood and log posterior of one slip condition in θ.

    Parameters
    ----------
    model : CurveModel
    par : Parametrisation
        The least-squares fit's parametrisation of this slip condition.
    priors : dict name -> Prior
        One per ``par.names`` entry, in that order.
    sigma : float, optional
        Known force noise σ (N); ``None``: σ integrated out (module docstring).
    """

    def __init__(self, model: CurveModel, par: Parametrisation, priors: dict[str, Prior],
                 sigma: float | None) -> None:
        self.model, self.par, self.sigma = model, par, sigma
        self.names = list(par.names)
        self.priors = [priors[n] for n in self.names]
        self.internal = [INTERNAL_NAMES[n] for n in self.names]
        self.scale = float(sigma) if sigma is not None else par.f_scale
        sigma_jump = float(sigma) if sigma is not None else (noise_estimate(model.force) or 1e-3 * par.f_scale)
        self._residual = residual_function(model, par, self.scale, sigma_jump)
        self.n = model.force.size + (model.jump is not None)

    @property
    def noise_model(self) -> str:
        if self.sigma is not None:
            return f"Gaussian, sigma known ({self.sigma:.4g} N, given)"
        return ("Gaussian, sigma unknown: integrated out analytically under the prior p(sigma) ∝ 1/sigma "
                "(Student-t-like marginal likelihood)")

    def residual(self, theta: np.ndarray) -> np.ndarray:
        """The shared least-squares residual at θ (units of ``self.scale``)."""
        return self._residual(_Values(zip(self.internal, map(float, theta))))

    def log_likelihood(self, theta: np.ndarray) -> float:
        r = self.residual(theta)
        if np.all(r == PENALTY):  # outside the model's domain (the residual's marker)
            return -math.inf
        ss = float(r @ r)
        if self.sigma is not None:
            return -0.5 * ss - 0.5 * self.n * math.log(2.0 * math.pi * self.sigma**2)
        rss = ss * self.scale**2
        return math.log(0.5) + special.gammaln(0.5 * self.n) - 0.5 * self.n * math.log(math.pi * rss)

    def from_si(self, values: dict) -> np.ndarray:
        """SI dict (as :meth:`Parametrisation.si` gives) -> θ."""
        out = []
        for name, prior in zip(self.names, self.priors):
            key = name if name in values else ("force_offset" if name == "force_offset" else "x_offset")
            out.append(math.log(values[key]) if prior.log else values[key] / prior.factor)
        return np.array(out)
