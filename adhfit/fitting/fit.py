"""``fit_curve``: fit a measured curve under both slip conditions and compare them (docs/contracts.md A5).

One call reads the data and the scene (or takes them as objects), fits each slip condition by least
squares (:mod:`.lsq`), computes intervals (:mod:`.summary`), compares the conditions
(:mod:`.selection`) and returns a frozen :class:`~.result.FitResult`.  The second condition is also
started from the first one's optimum (the two optima are usually close).  The membrane model
(docs/contracts.md A6) is decided after the large-stretch fits, and the exact membrane refines them
(:mod:`.membrane_choice`, :mod:`.membrane_fit`).
"""
from __future__ import annotations

import dataclasses
import time

from ..errors import InputError
from .model import CurveModel, segment
from .options import DEFAULT_POINTS, METHODS
from .lsq import fit_slip
from .prepare import check_options as _check_options
from .prepare import provenance as _provenance
from .prepare import read_inputs as _inputs
from .prepare import segments_report as _segments
from .result import Estimate, FitResult, SlipFit
from .selection import compare
from .summary import summarize

__all__ = ["fit_curve", "METHODS", "SIGMA_ESTIMATED"]

SIGMA_ESTIMATED = "estimated from the residuals (lmfit scales the covariance by the reduced chi-square)"
_MAIN = ("work_of_adhesion", "mu_h")
#: w = W_ad/μh within this fraction of the table's upper bound earns a warning
_W_EDGE = 0.98


def _membrane_verdict(large: dict, exact: dict, info: dict) -> tuple[dict, dict, bool]:
    """Under ``auto``, after the exact refit: keep it when the data prefer it (ΔBIC above
    :data:`~.membrane_fit.MEMBRANE_DBIC`), go back to the large-stretch fit when they prefer that, and
    otherwise keep the exact fit's values with intervals that also cover the large-stretch fit's."""
    from .membrane_fit import MEMBRANE_DBIC, membrane_evidence  # noqa: PLC0415
    dbic = membrane_evidence(large, exact)
    why = info["why"].rstrip(".")
    if dbic > MEMBRANE_DBIC:
        return exact, {**info, "why": f"{why}; the data prefer the exact membrane (ΔBIC = {dbic:.3g}).",
                       "delta_bic": dbic}, False
    if dbic < -MEMBRANE_DBIC:
        return large, {"membrane": "large-stretch", "delta_bic": dbic,
                       "why": f"{why}; but the data prefer the large-stretch model (ΔBIC = {-dbic:.3g})."}, False
    return exact, {**info, "delta_bic": dbic,
                   "why": f"{why}; the data cannot tell the two membrane models apart (|ΔBIC| = {abs(dbic):.2g} < "
                          f"{MEMBRANE_DBIC:g}): the values are the exact membrane's, the 95 % intervals cover both "
                          f"models' intervals."}, True


def _hull(name: str, ests: list[Estimate], chosen: Estimate, over: str = "both slip conditions") -> Estimate:
    """One estimate covering both slip conditions' (undecided slip): the widest status and interval."""
    los = [e.ci95[0] if e.ci95 is not None else None for e in ests]
    his = [e.ci95[1] if e.ci95 is not None else None for e in ests]
    if any(e.status == "undetermined" for e in ests):
        return dataclasses.replace(chosen, ci95=None, status="undetermined")
    lo = None if any(v is None for v in los) else min(los)
    hi = None if any(v is None for v in his) else max(his)
    status = {(False, False): "determined", (False, True): "lower_bound", (True, False): "upper_bound",
              (True, True): "undetermined"}[(lo is None, hi is None)]
    ses = [e.stderr for e in ests if e.stderr is not None]
    return dataclasses.replace(chosen, ci95=None if status == "undetermined" else (lo, hi), status=status,
                               stderr=max(ses) if ses else None,
                               ci_method=f"{chosen.ci_method} (hull over {over})")


def _reported(fits: dict[str, SlipFit], verdict: dict) -> dict[str, Estimate]:
    """Estimates of the selected fit; undecided: the favoured fit's, intervals hulled over both."""
    chosen = fits[verdict["parameters_from"]]
    if verdict["selected"] is not None or len(fits) == 1:
        return dict(chosen.parameters)
    return {name: _hull(name, [f.parameters[name] for f in fits.values() if name in f.parameters], e)
            for name, e in chosen.parameters.items()}


def _warnings(scene, fits, verdict, curve, reported, model_info, effects) -> tuple[list[str], list[str]]:
    """(warnings, diagnostics): plain sentences for a lab user, and solver details."""
    from .membrane_fit import effect_warning  # noqa: PLC0415
    note = effect_warning(effects, verdict["parameters_from"], scene.prestretch)
    out = [] if model_info["membrane"] == "exact" else [note] if note else [] if effects else list(scene.warnings())
    rep = fits[verdict["parameters_from"]]
    out += list(rep.warnings)
    diag = [f"[{s}] {d}" for s, f in fits.items() for d in f.diagnostics]
    if verdict["selected"] is None and len(fits) > 1:
        out.append(f"The slip condition is undecided: the data cannot tell no-slip from frictionless contact "
                   f"for sure ({verdict['explanation'].rstrip('.')}). The estimates are the {verdict['favoured']} "
                   f"fit's, and their 95 % intervals cover both conditions' intervals.")
    w_e, mu_e = rep.parameters["work_of_adhesion"], rep.parameters["mu_h"]
    from ..params import DIMENSIONLESS  # noqa: PLC0415
    if w_e.value and mu_e.value and w_e.value / mu_e.value > _W_EDGE * DIMENSIONLESS["w"].upper:
        out.append(f"W_ad/μh = {w_e.value / mu_e.value:.3g} is at the largest value the model covers "
                   f"({DIMENSIONLESS['w'].upper:g}): the estimate is unreliable.")
    if any(not f.success for f in fits.values()):
        diag.append("the optimiser did not report convergence for: "
                    + ", ".join(s for s, f in fits.items() if not f.success))
    return out, diag


def _decide(fits: dict[str, SlipFit]) -> dict:
    """The slip verdict; ΔBIC is divided by the widening² of the better fit when its noise is correlated."""
    bic = {s: f.bic for s, f in fits.items()}
    aic = {s: f.aic for s, f in fits.items()}
    if len(fits) > 1:
        best = min(bic, key=bic.get)
        f2 = fits[best].widening ** 2
        bic = {s: bic[best] + (v - bic[best]) / f2 for s, v in bic.items()}
        aic = {s: aic[best] + (v - aic[best]) / f2 for s, v in aic.items()}
    return compare(bic, aic)


def fit_curve(data, scene, *, method: str = "lsq", slip: str | None = None, sigma: float | None = None,
              fit_x_offset: bool | None = None, fit_force_offset: bool = True, seed: int | None = None,
              points: int = DEFAULT_POINTS, profile: bool = True, membrane: str | None = None,
              read_options: dict | None = None, **mcmc_options) -> FitResult:
    """Fit W_ad, μh and the slip condition to a measured curve.

    Parameters
    ----------
    data : path or adhfit.data.Curve
        The measured curve (CSV, docs/contracts.md A4) or a Curve.
    scene : path or adhfit.scene.Scene
        The scene (TOML, A3): geometry and the fixed pressure or gap.
    method : {"lsq", "mcmc"}
        Least squares (lmfit), or posterior sampling (emcee, :func:`.mcmc_fit.fit_curve_mcmc`, which
        starts from the least-squares fits).  Both return a :class:`~.result.FitResult`.
    slip : {"auto", "no-slip", "frictionless"}, optional
        Default: the scene's ``[interface] slip``.  ``"auto"`` fits both and compares them.
    sigma : float, optional
        Force noise σ, N.  Default: estimated from the residuals.
    fit_x_offset : bool, optional
        Fit a displacement offset (default under displacement control) or a pressure offset.
    fit_force_offset : bool
        Fit the load-cell zero (default; the rows before contact and after pull-off pin it).
        ``False`` fixes it at zero.
    seed : int, optional
        Recorded in the provenance (least squares draws no random numbers).
    points : int
        Rows per computed history.
    profile : bool
        Compute likelihood-profile intervals of W_ad and μh of the reported fit; the other fit's
        intervals are from its covariance (an undecided verdict reports the hull of both).  An exact
        fit profiles only when its optimum sits on the kink at the turning point (elsewhere its
        covariance is trustworthy, and a profile costs ~30 exact histories).
    membrane : {"auto", "large-stretch", "exact"}, optional
        Default: the scene's ``[membrane] model``.  The large-stretch fit always runs first; ``exact``
        refines it with the exact membrane, ``auto`` does so when the data resolve the approximation's
        error (:mod:`.membrane_choice`).  ``report.json`` ``model`` says which ran and why.
    read_options : dict, optional
        Keywords for :func:`adhfit.data.read_curve` when ``data`` is a path: ``columns``, ``units``,
        ``force_sign``, ``displacement_sign``.
    **mcmc_options
        ``method="mcmc"`` only: ``outdir``, ``workers``, ``progress`` and the sampler settings of
        :func:`.mcmc_fit.fit_curve_mcmc` (``n_walkers``, ``max_steps``, ...).

    Returns
    -------
    FitResult
    """
    if method == "mcmc":
        from .mcmc_fit import fit_curve_mcmc  # noqa: PLC0415 - emcee loads only for MCMC
        return fit_curve_mcmc(data, scene, slip=slip, sigma=sigma, fit_x_offset=fit_x_offset,
                              fit_force_offset=fit_force_offset, seed=seed, points=points, membrane=membrane,
                              read_options=read_options, **mcmc_options)
    if mcmc_options:
        name = sorted(mcmc_options)[0]
        raise InputError(name, mcmc_options[name], "absent with method='lsq' (an MCMC option)")
    t0 = time.perf_counter()
    curve, scene = _inputs(data, scene, read_options)
    from .plausibility import check_curve  # noqa: PLC0415
    curve, checks = check_curve(curve, scene)  # repeated rows left out; absurd data raise here
    slip = scene.slip if slip is None else slip
    membrane = scene.membrane_model if membrane is None else membrane
    _check_options(method, slip, sigma, points, membrane)
    slips = ("no-slip", "frictionless") if slip == "auto" else (slip,)
    seg = segment(curve)
    raws = {}
    for s in slips:
        model = CurveModel(curve, scene, s, points=points, segments=seg)
        extra = [r.par.si(r.best.params) for r in raws.values()]
        raws[s] = fit_slip(model, sigma=sigma, fit_x_offset=fit_x_offset, fit_force_offset=fit_force_offset,
                           extra_starts=extra)
    from .membrane_fit import choose_and_refit, wants_profile  # noqa: PLC0415
    large = raws
    raws, model_info, effects = choose_and_refit(raws, scene, membrane)
    hull_large = False
    if membrane == "auto" and model_info["membrane"] == "exact":  # do the data prefer it?
        raws, model_info, hull_large = _membrane_verdict(large, raws, model_info)
    # profiles cost ~2/3 of a fit: compute them only for the fit whose estimates are reported
    fits = {s: summarize(r, profile=False) for s, r in raws.items()}
    verdict = _decide(fits)
    # the reported fit only; an undecided verdict hulls with the other's covariance interval
    if profile and wants_profile(raws[verdict["parameters_from"]], model_info):
        wanted = verdict["parameters_from"]
        fits[wanted] = summarize(raws[wanted], profile=True)
        if len(fits) > 1 and verdict["selected"] is None and \
                any(not e.determined for k, e in fits[wanted].parameters.items() if k in _MAIN):
            # an undecided slip hulls both fits: a one-sided result needs the other's profile too
            for other in (s for s in fits if s != wanted):
                fits[other] = summarize(raws[other], profile=True)
        verdict = _decide(fits)
        if verdict["parameters_from"] != wanted:
            verdict = dict(verdict, parameters_from=wanted)
    rep = fits[verdict["parameters_from"]]
    options = {"slip": slip, "sigma": sigma, "fit_x_offset": raws[slips[0]].par.fit_x_offset,
               "fit_force_offset": fit_force_offset, "points": points, "profile": profile, "membrane": membrane}
    reported = _reported(fits, verdict)
    if hull_large:  # the data cannot tell the membrane models apart: cover the large-stretch fit's too
        other = summarize(large[verdict["parameters_from"]], profile=profile)
        reported = {n: _hull(n, [e, other.parameters[n]], e, over="both membrane models") if n in _MAIN else e
                    for n, e in reported.items()}
    warnings, diagnostics = _warnings(scene, fits, verdict, curve, reported, model_info, effects)
    return FitResult(
        method=method, slip=verdict, parameters=reported, fits=fits,
        n_points=len(curve.x), n_excluded=len(curve.excluded), sigma=rep.sigma,
        sigma_source="given" if sigma is not None else SIGMA_ESTIMATED,
        warnings=tuple(checks + warnings), diagnostics=tuple(diagnostics),
        n_evaluations=sum(f.n_evaluations for f in fits.values()),
        n_histories=sum(f.n_histories for f in fits.values()), wall_time=time.perf_counter() - t0,
        provenance=_provenance(curve, scene, seed, method, options), segments=_segments(seg, rep),
        excluded=tuple(curve.excluded), curve=curve, raw={s: f.raw for s, f in fits.items()}, model=model_info)
