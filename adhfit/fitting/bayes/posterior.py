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

from ...errors import InputError
from ..lsq import PENALTY, Parametrisation
from ..objective import Values

__all__ = ["LogPosterior", "Prior", "Target", "default_priors", "objective_priors", "checked_covariance",
           "DEFAULT_PRIOR_FACTOR", "INTERNAL_NAMES", "SCALE_CHECK", "SHARED"]

#: default log-uniform priors reach this factor below and above the least-squares estimates
DEFAULT_PRIOR_FACTOR = 100.0
#: SI name -> internal (θ) name, as in :meth:`.lsq.Parametrisation.params`
INTERNAL_NAMES = {"work_of_adhesion": "ln_work_of_adhesion", "mu_h": "ln_mu_h",
                  "displacement_offset": "x_offset", "pressure_offset": "x_offset",
                  "force_offset": "force_offset", "force_drift": "force_drift"}


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
        unit = {"work_of_adhesion": "J/m^2", "mu_h": "N/m", "force_offset": "N", "force_drift": "N"}.get(
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
        key, factor = (name, par.f_scale) if name.startswith("force_") else ("x_offset", par.x_scale)
        half = max(factor, *(2.0 * abs(v[key]) for v in lsq_values))
        out[name] = Prior(name, "uniform", -half, half, False, factor)
    return out


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


SHARED = ("work_of_adhesion", "mu_h")


class Target(LogPosterior):
    """Log prior, log likelihood and log posterior of one slip condition's objective, in θ.

    θ are the least-squares fit's internal coordinates: ln W_ad, ln μh, then per curve its scaled offsets.
    The likelihood is Gaussian per *block* (one curve's force rows with its pull-off term, each secondary
    observable of each curve), every block with its own σ: given, or integrated out under p(σ) ∝ 1/σ
    (module docstring), block by block.  One curve and its force alone is one block.

    Parameters
    ----------
    fit : ObjectiveFit
        The least-squares optimum (members with their settled σ's and row splits).
    names : list of str
        SI names of θ's coordinates (offsets suffixed with the curve's index in a series).
    priors : list of Prior
        One per coordinate.
    """

    def __init__(self, fit, names: list[str], priors: list[Prior]) -> None:
        self.internal = list(fit.best.var_names)
        if len(names) != len(self.internal) or len(priors) != len(names):
            raise ValueError(f"{len(names)} names and {len(priors)} priors for {len(self.internal)} parameters")
        self.names, self.priors, self.given = list(names), list(priors), dict(fit.given)
        self.fit = fit
        self._residual = fit.residual
        self.blocks = []  # (start, stop, residual unit, σ given)
        k = 0
        for m in fit.members:
            self.blocks.append((k, k + m.n_force, m.sigma_f, fit.given["force"]))
            k += m.n_force
            for b in m.blocks:
                self.blocks.append((k, k + b.data.rows.size, b.sigma, b.given))
                k += b.data.rows.size

    @property
    def noise_model(self) -> str:
        if len(self.blocks) == 1:
            if self.blocks[0][3]:
                return f"Gaussian, sigma known ({self.blocks[0][2]:.4g} N, given)"
            return ("Gaussian, sigma unknown: integrated out analytically under the prior p(sigma) ∝ 1/sigma "
                    "(Student-t-like marginal likelihood)")
        known = [k for k, v in self.given.items() if v]
        head = "Gaussian, one sigma per curve and observable"
        if len(known) == len(self.given):
            return head + ", all given"
        tail = "integrated out analytically under p(sigma) ∝ 1/sigma (block by block)"
        return head + (f"; {', '.join(known)} given, the others " if known else "; ") + tail

    def residual(self, theta: np.ndarray) -> np.ndarray:
        """The least-squares residual at θ (each block in units of its σ)."""
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

    def theta0(self) -> np.ndarray:
        """The least-squares optimum in θ."""
        return np.array([self.fit.best.params[n].value for n in self.internal])


def _scene_priors(scenes) -> dict:
    first = dict(scenes[0].priors)
    for sc in scenes[1:]:
        if dict(sc.priors) != first:
            raise InputError("[priors]", f"{sc.source}", "the same [priors] table in every curve's scene "
                             "(the shared W_ad and μh have one prior); remove it or make them agree")
    return first


def objective_priors(fits: dict, scenes) -> tuple[list[str], list[Prior]]:
    """Coordinate names and priors of the posterior (the same for every slip condition).

    Per curve :func:`default_priors` with that curve's least-squares offsets and the W_ad and μh of every
    slip condition; the shared values' priors are curve 0's (they use only the shared estimates, so every
    curve gives the same)."""
    scene_priors = _scene_priors(scenes)
    first = next(iter(fits.values()))
    si = [f.si() for f in fits.values()]
    names, priors = [], []
    for i, m in enumerate(first.members):
        pri = default_priors(m.par, [{**shared, **offs[i]} for shared, offs in si], scene_priors)
        for name in m.par.names:
            if name in SHARED and i > 0:
                continue
            names.append(name if name in SHARED or len(first.members) == 1 else f"{name}_{i}")
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
