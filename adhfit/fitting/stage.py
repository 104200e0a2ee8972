"""The least-squares stage of every fit: what ``method="lsq"`` reports and where MCMC starts.

Per slip condition:

1. **each curve alone** (:func:`~.lsq.fit_slip`): data-based starts, the free then fixed row split
   (the pull-off row found by likelihood), the other condition's optimum as one more start;
2. **the membrane model** (docs/contracts.md A6, :func:`~.membrane.choose_members`): the exact
   membrane refines the large-stretch fits when asked, or under ``auto`` when the data resolve the
   approximation's error;
3. **the objective** (:func:`~.joint.objective_fit`): one curve and its force alone is its own fit;
   several curves, or a secondary observable, are fitted jointly with a noise level per block;
4. **summaries** (:func:`~.summary.summarize`), the slip verdict (:mod:`.selection`), and the
   likelihood profiles of the fit whose values are reported.
5. **the result** (:func:`assemble`): the reported values of the selected slip condition (undecided:
   the favoured one's, with 95 % intervals hulled over both conditions, and over both membrane models
   when the data cannot tell those apart either), the plain warnings, the solver details, and for a
   series each curve's entry.  MCMC (:mod:`.bayes.sampling`) assembles its result here too.
"""
from __future__ import annotations

import dataclasses
import platform
import time
from dataclasses import dataclass, field

from ..params import DIMENSIONLESS, SLIP_CONDITIONS
from .checks import curve_entries, curve_warnings, plot_data
from .joint import objective_fit
from .lsq import fit_slip
from .membrane import MEMBRANE_DBIC, choose_members, effect_warning, membrane_evidence, wants_profile
from .model import CurveModel, segment
from .objective import ObjectiveFit
from .result import Estimate, FitResult, SlipFit
from .selection import compare
from .summary import MISFIT_HEAD, POSSIBLE_MISFIT_HEAD, summarize

__all__ = ["Stage", "least_squares", "decide", "assemble", "hull", "reported", "provenance", "SIGMA_ESTIMATED"]

_MAIN = ("work_of_adhesion", "mu_h")


@dataclass
class Stage:
    """What the least-squares stage found.

    Attributes
    ----------
    fits : dict slip -> ObjectiveFit
        The optima of the membrane model used.
    summaries : dict slip -> SlipFit
    verdict : dict
        The slip verdict (:func:`decide`); ``parameters_from`` names the reported condition.
    model : dict
        report.json ``model``.
    effects : list of dict
        Per curve, per slip condition: the approximation's :class:`~.membrane.Effect`.
    singles : dict slip -> list of RawFit
        Each curve's own fit (of the membrane model used).
    large : dict slip -> ObjectiveFit
        The large-stretch optima when the data cannot tell the membranes apart (their intervals are
        hulled with the exact ones); else empty.
    segs : list of Segments
    """

    fits: dict
    summaries: dict
    verdict: dict
    model: dict
    effects: list
    singles: dict
    segs: list
    large: dict = field(default_factory=dict)


def decide(summaries: dict) -> dict:
    """The slip verdict; ΔBIC is divided by the widening² of the better fit when its noise is correlated."""
    bic = {s: f.bic for s, f in summaries.items()}
    aic = {s: f.aic for s, f in summaries.items()}
    if len(summaries) > 1:
        best = min(bic, key=bic.get)
        f2 = summaries[best].widening ** 2
        bic = {s: bic[best] + (v - bic[best]) / f2 for s, v in bic.items()}
        aic = {s: aic[best] + (v - aic[best]) / f2 for s, v in aic.items()}
        if summaries[best].misfit:  # a model that does not describe the data earns no strong verdict
            return cap(compare(bic, aic))
    return compare(bic, aic)


def cap(verdict: dict) -> dict:
    """The verdict of a fit the model does not describe: at most 'positive' evidence, nothing selected."""
    if verdict["evidence"] not in ("strong", "very strong"):
        return verdict
    fav, d = verdict["favoured"], verdict["delta_bic"]
    return dict(verdict, selected=None, evidence="positive", capped=verdict["evidence"],
                verdict=f"{fav}: positive evidence at most, not selected (ΔBIC = {d:.2g}; the model does not "
                        f"describe these data)",
                explanation=f"ΔBIC = {d:.1f} would be {verdict['evidence']} evidence for {fav}, but the model does "
                            f"not describe these data to within their scatter, so the verdict is capped at 'positive'.")


def _singles(problem, opts, segs, slips) -> dict:
    """Each curve's own large-stretch fit, per slip condition.  Each condition is also started from the
    other's optimum (the two optima are usually close, and a condition stuck in a wrong basin, e.g.
    with the model detaching rows early, is not left there by the other's better start)."""
    singles: dict = {s: [] for s in slips}
    for i, (curve, scene) in enumerate(zip(problem.curves, problem.scenes)):
        done, models = {}, {}
        for s in slips:
            model = models[s] = CurveModel(curve, scene, s, points=opts.points, segments=segs[i])
            extra = [dict(r.par.si(r.best.params), label=f"the {o} optimum") for o, r in done.items()]
            done[s] = fit_slip(model, sigma=opts.sigma, fit_x_offset=opts.fit_x_offset,
                               fit_force_offset=opts.fit_force_offset, fit_force_drift=opts.fit_force_drift,
                               extra_starts=extra)
        first = slips[0]
        if len(slips) > 1:  # the first condition from the second's optimum
            other = done[slips[1]]
            # the same model: its histories and its data-based start are kept
            again = fit_slip(models[first], sigma=opts.sigma, fit_x_offset=opts.fit_x_offset,
                             fit_force_offset=opts.fit_force_offset, fit_force_drift=opts.fit_force_drift, n_runs=0,
                             extra_starts=[dict(other.par.si(other.best.params), label=f"the {slips[1]} optimum")],
                             known=done[first])
            if again.best.chisqr < done[first].best.chisqr * (1.0 - 1e-9):
                done[first] = again
        for s in slips:
            singles[s].append(done[s])
    return singles


def _objectives(problem, singles: dict, segs: list) -> dict:
    return {s: objective_fit(s, raws, problem.curves, segs, problem.sigmas, problem.observables, problem.labels)
            for s, raws in singles.items()}


def _membrane_verdict(large: dict, exact: dict, info: dict) -> tuple[dict, dict, bool]:
    """Under ``auto``, after the exact refit: keep it when the data prefer it (ΔBIC above
    :data:`~.membrane.MEMBRANE_DBIC`), go back to the large-stretch fit when they prefer that, and
    otherwise keep the exact fit's values with intervals that also cover the large-stretch fit's."""
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


def least_squares(problem, opts, *, profile: bool) -> Stage:
    """Steps 1–4 of the module docstring for every slip condition of ``problem``."""
    slips = SLIP_CONDITIONS if problem.slip == "auto" else (problem.slip,)
    segs = [segment(c) for c in problem.curves]
    large_singles = _singles(problem, opts, segs, slips)
    singles, model_info, effects = choose_members(large_singles, problem.scenes, problem.membrane)
    fits = _objectives(problem, singles, segs)
    large = {}
    if model_info["membrane"] == "exact" and problem.membrane == "auto":  # do the data prefer it?
        large_fits = _objectives(problem, large_singles, segs)
        fits, model_info, hull = _membrane_verdict(large_fits, fits, model_info)
        if fits is large_fits:
            singles = large_singles
        large = large_fits if hull else {}
    # profiles cost ~2/3 of a fit: compute them only for the fit whose estimates are reported
    summaries = {s: summarize(f, profile=False) for s, f in fits.items()}
    verdict = decide(summaries)
    if profile and wants_profile(fits[verdict["parameters_from"]], model_info):
        wanted = verdict["parameters_from"]
        summaries[wanted] = summarize(fits[wanted], profile=True)
        if len(summaries) > 1 and verdict["selected"] is None:
            # an undecided slip hulls both fits: the other's covariance interval is fragile at the pull-off's
            # kink (a frictionless pressure-control test at 5 % noise: no-slip's W_ad interval [0.08, 0.98]
            # from the covariance, [0.29, 0.31] from its profile), so its profile is computed too
            for other in (s for s in summaries if s != wanted):
                summaries[other] = summarize(fits[other], profile=True)
        verdict = dict(decide(summaries), parameters_from=wanted)
    return Stage(fits=fits, summaries=summaries, verdict=verdict, model=model_info, effects=effects,
                 singles=singles, segs=segs, large=large)

# --- the result of the stage ---------------------------------------------------------------

SIGMA_ESTIMATED = "estimated from the residuals (lmfit scales the covariance by the reduced chi-square)"
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
