"""Fit results: frozen, complete, the same fields whatever the method (STYLE habit 5).

A :class:`FitResult` never re-runs a fit: it holds the estimates, both slip conditions' fits with their
predictions and model curves, the slip verdict, warnings and provenance; the optimiser's own objects
are kept in ``raw``.  :meth:`FitResult.as_dict` gives the report.json content (docs/contracts.md A5) with
``None`` wherever a number is not finite.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any, Mapping

import numpy as np

from ..params import FITTED

__all__ = ["Estimate", "SlipFit", "FitResult", "clean", "MODEL"]

#: the membrane model of every fit in this version, and why (docs/contracts.md A5b)
MODEL = {"membrane": "large-stretch",
         "why": "The large-stretch membrane of the paper is the model fitted; it is accurate when the "
                "pre-stretch λ0 is large (its error grows as λ0 approaches 1)."}


def clean(x: Any) -> Any:
    """JSON-safe copy: numpy scalars and arrays to Python, non-finite floats to ``None``."""
    if isinstance(x, Mapping):
        return {str(k): clean(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [clean(v) for v in x]
    if isinstance(x, np.ndarray):
        return [clean(v) for v in x.tolist()]
    if isinstance(x, (bool, np.bool_)):
        return bool(x)
    if isinstance(x, (int, np.integer)):
        return int(x)
    if isinstance(x, (float, np.floating)):
        return float(x) if math.isfinite(float(x)) else None
    return x


def _readonly(a) -> np.ndarray:
    arr = np.array(a, dtype=float, copy=True)
    arr.setflags(write=False)
    return arr


def _per_curve_offsets(curves) -> dict:
    """``offsets`` of a global fit: each offset's values per curve (in ``curves`` order), SI."""
    out: dict = {}
    for i, c in enumerate(curves):
        for short, o in c["offsets"].items():
            e = out.setdefault(short, {"status": "per_curve", "unit": o.get("unit"), "values": [None] * len(curves),
                                       "stderr": [None] * len(curves), "fitted": "note" not in o})
            e["values"][i], e["stderr"][i] = o.get("value"), o.get("stderr")
    return out


@dataclass(frozen=True)
class Estimate:
    """One fitted parameter in SI.

    Attributes
    ----------
    name : str
        Row of :data:`adhfit.params.FITTED`.
    value : float
    stderr : float or None
        Standard error from the covariance (delta method from the internal parametrisation).
    ci95 : (float, float) or None
        95 % interval.
    ci_method : {"profile", "covariance", "covariance (two slips)", None}
        Where ``ci95`` comes from.
    ci95_covariance : (float, float) or None
        The covariance interval, kept for comparison with the profile.
    status : {"determined", "lower_bound", "upper_bound", "undetermined"}
        What the data say (docs/contracts.md A5b): a value and a two-sided ``ci95``; a one-sided 95 % bound
        (``ci95`` = ``(low, None)`` or ``(None, high)``); or nothing.  ``value`` keeps the optimum
        (for plots); the report gives ``value: null`` unless the status is ``determined``.
    """

    name: str
    value: float
    stderr: float | None = None
    ci95: tuple[float | None, float | None] | None = None
    ci_method: str | None = None
    ci95_covariance: tuple[float, float] | None = None
    status: str = "determined"

    @property
    def unit(self) -> str:
        return FITTED[self.name].unit

    @property
    def symbol(self) -> str:
        return FITTED[self.name].symbol

    @property
    def determined(self) -> bool:
        return self.status == "determined"

    def as_dict(self) -> dict:
        det = self.determined
        return clean({"value": self.value if det else None, "stderr": self.stderr if det else None,
                      "ci95": None if self.status == "undetermined" else self.ci95, "unit": self.unit,
                      "status": self.status, "optimum": self.value, "ci_method": self.ci_method,
                      "ci95_covariance": self.ci95_covariance})


@dataclass(frozen=True)
class SlipFit:
    """The fit of one slip condition.

    Attributes
    ----------
    slip : str
    parameters : mapping name -> Estimate
        ``work_of_adhesion``, ``mu_h`` and the fitted offsets.
    chisqr, redchi : float
        χ² and reduced χ² in units of σ²: the given σ, or, when σ is estimated, the robust
        row-to-row noise of the data (second differences, :func:`.starts.noise_estimate`), so that
        a reduced χ² near 1 means the model fits to the noise.
    aic, bic : float
        As defined in :mod:`.selection` (differences between slip conditions are what matter).
    ndata, nvarys : int
        Residuals (rows, plus one for the pull-off position) and fitted parameters.
    sigma : float
        Force noise σ, N: given, or estimated from the residuals, sqrt(RSS/(n - k)).
    correlation : float or None
        Correlation of W_ad and μh (of their logarithms, which is the same to first order).
    predicted : ndarray
        Model force at every row, N.
    model_curve : mapping
        Dense model curve in measured units for plots (``x_loading, force_loading, x_unloading,
        force_unloading, x_onset, x_turning_point, force_turning_point``).
    warnings : tuple of str
        Plain sentences for a lab user.
    starts : tuple of dict
        Every start (SI) and the χ² it reached.
    profile : mapping
        Per parameter: sub-fits spent and whether each limit converged.
    n_evaluations, n_histories : int
        Model predictions and computed histories spent on this slip condition.
    success : bool
    message : str
    raw : object
        The optimiser's result (lmfit ``MinimizerResult``); not compared, not serialised.
    diagnostics : tuple of str
        Solver details (kink, profiles, starts): not for the warnings.
    split : int or None
        First row the fitted model puts after pull-off (``None``: the data end before it).
    autocorrelation, widening : float
        Lag-1 autocorrelation of the residuals and the factor the intervals were widened by
        (:mod:`.checks`).
    misfit : bool
        The model does not describe the data to within their row-to-row scatter (a unit, a scene
        setting or the slip condition wrong, or correlated noise): the slip verdict is capped.
    """

    slip: str
    parameters: Mapping[str, Estimate]
    chisqr: float
    redchi: float
    aic: float
    bic: float
    ndata: int
    nvarys: int
    sigma: float
    correlation: float | None
    predicted: np.ndarray
    model_curve: Mapping[str, Any]
    warnings: tuple[str, ...] = ()
    starts: tuple = ()
    profile: Mapping[str, Any] = field(default_factory=dict)
    n_evaluations: int = 0
    n_histories: int = 0
    success: bool = True
    message: str = ""
    raw: Any = field(default=None, compare=False, repr=False)
    diagnostics: tuple[str, ...] = ()
    split: int | None = None
    autocorrelation: float = 0.0
    widening: float = 1.0
    misfit: bool = False

    def __post_init__(self) -> None:
        object.__setattr__(self, "predicted", _readonly(self.predicted))
        object.__setattr__(self, "parameters", MappingProxyType(dict(self.parameters)))
        object.__setattr__(self, "model_curve", MappingProxyType(dict(self.model_curve)))

    def as_dict(self) -> dict:
        return clean({"parameters": {k: e.as_dict() for k, e in self.parameters.items()},
                      "chisqr": self.chisqr, "redchi": self.redchi, "aic": self.aic, "bic": self.bic,
                      "ndata": self.ndata, "nvarys": self.nvarys, "sigma": self.sigma,
                      "correlation_work_of_adhesion_mu_h": self.correlation, "success": self.success,
                      "message": self.message, "warnings": list(self.warnings),
                      "diagnostics": list(self.diagnostics), "first_detached_row": self.split,
                      "residual_autocorrelation": self.autocorrelation, "interval_widening": self.widening,
                      "misfit": self.misfit,
                      "starts": list(self.starts),
                      "profile": dict(self.profile), "model_evaluations": self.n_evaluations,
                      "histories": self.n_histories})


@dataclass(frozen=True)
class FitResult:
    """The result of ``adhfit fit`` (docs/contracts.md A5), whatever the method.

    Attributes
    ----------
    method : str
        ``"lsq"`` (or ``"mcmc"``).
    slip : mapping
        ``selected`` (None when undecided), ``verdict``, ``delta_aic``, ``delta_bic`` and the
        evidence scale used (:mod:`.selection`).
    parameters : mapping name -> Estimate
        The reported estimates: of the selected slip condition; when undecided, of the one with the
        lower BIC, with 95 % intervals widened to cover both conditions' intervals.
    fits : mapping slip -> SlipFit
    n_points, n_excluded : int
        Rows used, and lines left out of the file (blank or comment lines, listed in ``excluded``).
    sigma : float
        Force noise σ of the reported fit, N.
    sigma_source : str
        ``"given"`` or ``"estimated from the residuals (covariance scaled by the reduced chi-square)"``.
    warnings : tuple of str
        What to distrust, in plain words.
    n_evaluations, n_histories : int
        Model predictions and computed histories, all slip conditions together.
    wall_time : float
        Seconds.
    provenance : mapping
        adhfit version, input file and sha256, scene, seed, method, options.
    segments : mapping
        Row-order segmentation of the data (end of loading, detachment jump).
    curve : object
        The measured curve (``adhfit.data.Curve``), for plots.
    raw : mapping
        The optimiser's results per slip condition; not compared, not serialised.
    diagnostics : tuple of str
        Solver details (kink, profiles, starts), apart from the plain ``warnings``.
    model : mapping
        ``membrane`` and ``why`` (one sentence).
    observables : tuple of str
        The columns the fit used.
    curves : tuple of dict
        A global fit's curves (docs/contracts.md A7: ``file``, ``offsets``, ``redchi``, ``n_points`` and the
        per-curve checks); empty for a single curve.
    sampling : mapping, optional
        An MCMC fit's run (``None`` for least squares): ``summary`` (JSON-ready: seed, noise model,
        priors, per slip condition its diagnostics and evidence, the model probabilities, cost; also
        :attr:`mcmc`), ``samples`` (slip -> kept posterior samples in SI, an (n, k) array whose
        columns are ``summary["slips"][slip]["parameters"]``; also :attr:`samples`) and
        ``predictive`` (the posterior-predictive band at the data rows of the reported fit: ``slip``,
        ``median``, ``lo``/``hi`` for the model curve, ``lo_obs``/``hi_obs`` with the noise; also
        :attr:`predictive`).
    """

    method: str
    slip: Mapping[str, Any]
    parameters: Mapping[str, Estimate]
    fits: Mapping[str, SlipFit]
    n_points: int
    n_excluded: int
    sigma: float
    sigma_source: str
    warnings: tuple[str, ...]
    n_evaluations: int
    n_histories: int
    wall_time: float
    provenance: Mapping[str, Any]
    segments: Mapping[str, Any]
    excluded: tuple = ()
    curve: Any = field(default=None, compare=False, repr=False)
    raw: Mapping[str, Any] = field(default_factory=dict, compare=False, repr=False)
    diagnostics: tuple[str, ...] = ()
    model: Mapping[str, Any] = field(default_factory=lambda: dict(MODEL))
    observables: tuple[str, ...] = ("force",)
    curves: tuple = ()
    sampling: Mapping[str, Any] | None = field(default=None, compare=False, repr=False)

    def __post_init__(self) -> None:
        for key in ("slip", "parameters", "fits", "provenance", "segments", "raw", "model"):
            object.__setattr__(self, key, MappingProxyType(dict(getattr(self, key))))
        if self.sampling is not None:
            object.__setattr__(self, "sampling", MappingProxyType(dict(self.sampling)))

    @property
    def mcmc(self) -> Mapping[str, Any]:
        """The MCMC run's JSON-ready summary (empty for least squares)."""
        return self.sampling["summary"] if self.sampling else {}

    @property
    def samples(self) -> Mapping[str, Any]:
        """Kept posterior samples per slip condition, SI (empty for least squares)."""
        return self.sampling["samples"] if self.sampling else {}

    @property
    def predictive(self) -> Mapping[str, Any]:
        """The posterior-predictive band of the reported fit (empty for least squares)."""
        return self.sampling["predictive"] if self.sampling else {}

    @property
    def converged(self) -> bool | None:
        """Whether every MCMC run met its stopping rule and R-hat bound (``None`` for least squares)."""
        return bool(self.mcmc.get("converged")) if self.sampling else None

    @property
    def reported_slip(self) -> str:
        """The slip condition whose fit gives :attr:`parameters`."""
        return self.slip.get("parameters_from") or self.slip.get("selected") or next(iter(self.fits))

    @property
    def correlation(self) -> float | None:
        """Correlation of W_ad and μh in the reported fit."""
        return self.fits[self.reported_slip].correlation

    @property
    def offsets(self) -> dict:
        """The fitted nuisance parameters of the reported fit (SI)."""
        return {k: e for k, e in self.parameters.items() if k not in ("work_of_adhesion", "mu_h")}

    def offsets_report(self) -> dict:
        """``offsets`` of report.json (docs/contracts.md A5b): every fitted offset in SI under its short name
        (``force``, ``displacement``, ``pressure``), ``force`` always present (0.0 with a note when fixed)."""
        if self.curves:  # a global fit: offsets per curve
            return _per_curve_offsets(self.curves)
        out = {}
        for k, e in self.offsets.items():
            out[k.removesuffix("_offset")] = e.as_dict() | {"fitted": True}
        if "force" not in out:
            out["force"] = {"value": 0.0, "stderr": None, "ci95": None, "unit": "N", "status": "fixed",
                            "fitted": False, "note": "load-cell zero fixed at 0 (fit_force_offset=False)"}
        return out

    def as_dict(self) -> dict:
        """The report.json content: the A5 keys and more, no NaN (``None`` instead)."""
        return clean({
            "method": self.method, "slip": dict(self.slip),
            "parameters": {k: e.as_dict() for k, e in self.parameters.items()
                           if k in ("work_of_adhesion", "mu_h")},
            "offsets": self.offsets_report(),
            "model": dict(self.model), "observables": list(self.observables),
            "diagnostics": list(self.diagnostics),
            "fits": {k: f.as_dict() for k, f in self.fits.items()},
            "correlation_work_of_adhesion_mu_h": self.correlation,
            "n_points": self.n_points, "n_excluded": self.n_excluded, "excluded": list(self.excluded),
            "sigma": self.sigma, "sigma_source": self.sigma_source, "segments": dict(self.segments),
            "warnings": list(self.warnings), "model_evaluations": self.n_evaluations,
            "histories": self.n_histories, "wall_time_s": self.wall_time,
            "provenance": dict(self.provenance)} | ({"curves": list(self.curves)} if self.curves else {})
            | (self._sampling_dict() if self.sampling else {}))

    def _sampling_dict(self) -> dict:
        """report.json keys of an MCMC fit (docs/contracts.md A5): seed, convergence, model probabilities,
        the sampler's diagnostics per slip condition (with the solver notes) and the run's summary."""
        m = self.mcmc
        return {"seed": m.get("seed"), "converged": self.converged,
                "model_probabilities": m.get("model_probabilities", {}).get("probabilities"),
                "diagnostics": {s: v["diagnostics"] for s, v in m.get("slips", {}).items()}
                | {"notes": list(self.diagnostics)},
                "mcmc": dict(m)}

    def plot(self, ax=None, **kwargs):
        """Data, the fitted curves and residuals, for one curve or every curve of a series (see
        :func:`adhfit.report.fit_plot.plot_fit`).

        Returns the main (force) axes.  Draws from stored predictions: never re-runs a fit.
        """
        from ..report.fit_plot import plot_fit  # noqa: PLC0415 - matplotlib lives in adhfit.report
        return plot_fit(self, ax=ax, **kwargs)

    def _repr_html_(self) -> str:  # notebooks
        from ..report.html import fit_summary_html  # noqa: PLC0415 - reports import matplotlib lazily
        d = self.as_dict()
        if d.get("curves"):  # a series: per-curve offsets are in the curves table, not here
            d = {**d, "offsets": {}}
        return fit_summary_html(d)
