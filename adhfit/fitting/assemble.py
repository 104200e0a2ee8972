"""The :class:`~.result.FitResult` of a least-squares stage: the reported values, warnings and provenance.

One place for every fit: the estimates of the selected slip condition (undecided: the favoured one's,
with 95 % intervals hulled over both conditions, and over both membrane models when the data cannot tell
those apart either), the plain warnings, the solver details, and for a series each curve's entry.
"""
from __future__ import annotations

import dataclasses
import platform
import time

from ..params import DIMENSIONLESS
from .checks import curve_entries, curve_warnings, plot_data
from .membrane import effect_warning
from .objective import ObjectiveFit
from .result import Estimate, FitResult, SlipFit
from .summary import MISFIT_HEAD, POSSIBLE_MISFIT_HEAD, summarize

__all__ = ["assemble", "hull", "reported", "provenance", "SIGMA_ESTIMATED"]

SIGMA_ESTIMATED = "estimated from the residuals (lmfit scales the covariance by the reduced chi-square)"
_MAIN = ("work_of_adhesion", "mu_h")
#: w = W_ad/μh within this fraction of the table's upper bound earns a warning
_W_EDGE = 0.98


def hull(ests: list[Estimate], chosen: Estimate, over: str) -> Estimate:
    """One estimate covering several fits' (an undecided slip or membrane): the widest status and interval."""
    if any(e.status == "undetermined" for e in ests):
        return dataclasses.replace(chosen, ci95=None, status="undetermined")
    los = [e.ci95[0] if e.ci95 is not None else None for e in ests]
    his = [e.ci95[1] if e.ci95 is not None else None for e in ests]
    lo = None if any(v is None for v in los) else min(los)
    hi = None if any(v is None for v in his) else max(his)
    status = {(False, False): "determined", (False, True): "lower_bound", (True, False): "upper_bound",
              (True, True): "undetermined"}[(lo is None, hi is None)]
    ses = [e.stderr for e in ests if e.stderr is not None]
    return dataclasses.replace(chosen, ci95=None if status == "undetermined" else (lo, hi), status=status,
                               stderr=max(ses) if ses else None, ci_method=f"{chosen.ci_method} (hull over {over})")


def reported(fits: dict[str, SlipFit], verdict: dict) -> dict[str, Estimate]:
    """Estimates of the selected fit; undecided: the favoured fit's, intervals hulled over both."""
    chosen = fits[verdict["parameters_from"]]
    if verdict["selected"] is not None or len(fits) == 1:
        return dict(chosen.parameters)
    return {name: hull([f.parameters[name] for f in fits.values() if name in f.parameters], e, "both slip conditions")
            for name, e in chosen.parameters.items()}


def _membrane_hull(stage, values: dict, profile: bool) -> dict:
    """Cover the large-stretch fits too (the data cannot tell the membrane models apart): the reported
    slip condition's, and every condition's when the slip is undecided (each enters the slip hull)."""
    v = stage.verdict
    slips = [v["parameters_from"]] if v["selected"] is not None or len(stage.large) == 1 else list(stage.large)
    others = [summarize(stage.large[s], profile=profile).parameters for s in slips]
    return {n: hull([e, *(o[n] for o in others)], e, "both membrane models") if n in _MAIN else e
            for n, e in values.items()}


def _warnings(problem, stage, rep: SlipFit) -> list[str]:
    """Plain sentences for a lab user (docs/contracts.md A5b)."""
    v, info = stage.verdict, stage.model
    out = list(problem.checks)
    if info["membrane"] == "large-stretch":
        notes = [effect_warning(eff, v["parameters_from"], sc.prestretch)
                 for eff, sc in zip(stage.effects, problem.scenes)]
        notes = [n for n in notes if n]
        out += notes[:1] if notes else ([] if any(stage.effects) else
                                        list(dict.fromkeys(w for sc in problem.scenes for w in sc.warnings())))
    if not rep.success:  # say so first: every number below is where the optimiser stopped
        out.insert(0, f"The fit did not converge ({rep.message.rstrip('.')}): the values are where the optimiser "
                      f"stopped; do not trust them, and refit (another start, --membrane large-stretch, or fewer "
                      f"rows).")
    out += list(rep.warnings)
    if v["selected"] is None and len(stage.summaries) > 1:
        why, fav = v["explanation"].rstrip("."), v["favoured"]
        out.append(f"The series cannot decide between no-slip and frictionless contact ({why}); the estimates are "
                   f"the {fav} fit's, and their 95 % intervals cover both conditions' intervals." if problem.series
                   else f"The slip condition is undecided: the data cannot tell no-slip from frictionless contact for "
                   f"sure ({why}). The estimates are the {fav} fit's, and their 95 % intervals cover both "
                   f"conditions' intervals.")
    first = (MISFIT_HEAD, POSSIBLE_MISFIT_HEAD)  # said first: every number below depends on it
    out = [w for w in out if any(h in w for h in first)] + [w for w in out if not any(h in w for h in first)]
    w_e, mu_e = rep.parameters["work_of_adhesion"], rep.parameters["mu_h"]
    if w_e.value and mu_e.value and w_e.value / mu_e.value > _W_EDGE * DIMENSIONLESS["w"].upper:
        out.append(f"W_ad/μh = {w_e.value / mu_e.value:.3g} is at the largest value the model covers "
                   f"({DIMENSIONLESS['w'].upper:g}): the estimate is unreliable.")
    return out


def provenance(problem, opts, method: str, options: dict) -> dict:
    """Where the numbers came from: adhfit and library versions, the inputs and their SHA-256, the
    scenes, the seed, the method and its options."""
    import lmfit  # noqa: PLC0415
    import numpy  # noqa: PLC0415
    import scipy  # noqa: PLC0415
    from .. import __version__  # noqa: PLC0415
    curves, scenes = problem.curves, problem.scenes
    fields = [{f.name: getattr(sc, f.name) for f in dataclasses.fields(sc) if f.name != "source"} for sc in scenes]
    one = not problem.series
    return {"adhfit_version": __version__, "input": curves[0].path if one else [c.path for c in curves],
            "input_sha256": curves[0].sha256 if one else [c.sha256 for c in curves],
            "scene_file": scenes[0].source if one else [sc.source for sc in scenes],
            "scene": fields[0] if one else None, "seed": opts.seed, "method": method, "options": options,
            "fit": "global" if problem.series else "single",
            "backend": "numba", "python": platform.python_version(), "numpy": numpy.__version__,
            "scipy": scipy.__version__, "lmfit": lmfit.__version__}


def _segments(stage, rep: SlipFit) -> dict:
    """Row-order segments of the report: the end of loading from the data, pull-off from the fit."""
    seg = stage.fits[stage.verdict["parameters_from"]].members[0].model.segments
    d = stage.segs[0].as_dict()
    j, n = rep.split, seg.n
    d.update({"i_jump": j, "n_attached": (n if j is None else j) - seg.i_turn - 1,
              "n_detached": 0 if j is None else n - j, "jump_from": "fitted model (its turning point)"})
    if j is not None and rep.predicted is not None:
        d["jump"] = float(abs(rep.predicted[j - 1] - rep.predicted[j]))
    return d


def options_dict(problem, opts, stage) -> dict:
    first = stage.singles[next(iter(stage.singles))][0]
    return {"slip": problem.slip, "sigma": opts.sigma, "sigma_contact_radius": opts.sigma_contact_radius,
            "contact_radius": opts.contact_radius, "fit_x_offset": first.par.fit_x_offset,
            "fit_force_offset": opts.fit_force_offset, "fit_force_drift": first.par.fit_force_drift,
            "points": opts.points, "profile": opts.profile,
            "membrane": problem.membrane}


def assemble(problem, stage, opts, t0: float, *, method: str = "lsq") -> FitResult:
    """The least-squares :class:`FitResult` of ``problem`` (module docstring)."""
    v = stage.verdict
    rep_slip = v["parameters_from"]
    rep, fit = stage.summaries[rep_slip], stage.fits[rep_slip]
    values = reported(stage.summaries, v)
    if stage.large:
        values = _membrane_hull(stage, values, opts.profile)
    warnings = _warnings(problem, stage, rep)
    diagnostics = [f"[{s}] {d}" for s, f in stage.summaries.items() for d in f.diagnostics]
    if any(not f.success for f in stage.summaries.values()):
        diagnostics.append("the optimiser did not report convergence for: "
                           + ", ".join(s for s, f in stage.summaries.items() if not f.success))
    curves = ()
    if problem.series:
        alone = [summarize(ObjectiveFit.from_single(r), profile=False) for r in stage.singles[rep_slip]]
        curves = tuple(curve_entries(fit, alone))
        warnings += curve_warnings(list(curves), fit)
    elif fit.joint:  # one curve with a secondary observable: its checks, without a curves table
        warnings += curve_warnings(curve_entries(fit, [rep]), fit)
    observables = ("force",) + tuple(dict.fromkeys(b.observable.name for m in fit.members for b in m.blocks))
    one = not problem.series
    sigma_source = "given" if opts.sigma is not None else SIGMA_ESTIMATED
    if not one:
        sigma_source = "per curve (curves[].sigma_force): " + ("given" if opts.sigma is not None else
                                                               "estimated from each curve's residuals")
    raw = {s: f.raw for s, f in stage.summaries.items()}
    if not one:
        raw = {**{s: f.best for s, f in stage.fits.items()}, "series_plot": plot_data(fit)}
    return FitResult(
        method=method, slip=v, parameters=values, fits=stage.summaries,
        n_points=sum(len(c.x) for c in problem.curves), n_excluded=sum(len(c.excluded) for c in problem.curves),
        sigma=rep.sigma if one else float("nan"), sigma_source=sigma_source,
        warnings=tuple(warnings), diagnostics=tuple(diagnostics),
        n_evaluations=sum(f.n_evaluations for f in stage.summaries.values()),
        n_histories=sum(f.n_histories for f in stage.summaries.values()), wall_time=time.perf_counter() - t0,
        provenance=provenance(problem, opts, method, options_dict(problem, opts, stage)),
        segments=_segments(stage, rep) if one else {}, excluded=tuple(problem.curves[0].excluded) if one else (),
        curve=problem.curves[0] if one else None, raw=raw, model=stage.model, observables=observables,
        curves=curves)
