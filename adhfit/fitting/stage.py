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
"""
from __future__ import annotations

from dataclasses import dataclass, field

from ..params import SLIP_CONDITIONS
from .joint import objective_fit
from .lsq import fit_slip
from .membrane import MEMBRANE_DBIC, choose_members, membrane_evidence, wants_profile
from .model import CurveModel, segment
from .selection import compare
from .summary import summarize

__all__ = ["Stage", "least_squares", "decide"]

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
        done: dict = {}
        for s in slips:
            model = CurveModel(curve, scene, s, points=opts.points, segments=segs[i])
            extra = [dict(r.par.si(r.best.params), label=f"the {o} optimum") for o, r in done.items()]
            done[s] = fit_slip(model, sigma=opts.sigma, fit_x_offset=opts.fit_x_offset,
                               fit_force_offset=opts.fit_force_offset, fit_force_drift=opts.fit_force_drift,
                               extra_starts=extra)
        first = slips[0]
        if len(slips) > 1:  # the first condition from the second's optimum
            other = done[slips[1]]
            model = CurveModel(curve, scene, first, points=opts.points, segments=segs[i])
            again = fit_slip(model, sigma=opts.sigma, fit_x_offset=opts.fit_x_offset,
                             fit_force_offset=opts.fit_force_offset, fit_force_drift=opts.fit_force_drift, n_runs=0,
                             extra_starts=[dict(other.par.si(other.best.params), label=f"the {slips[1]} optimum")])
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
        if len(summaries) > 1 and verdict["selected"] is None and \
                any(not e.determined for k, e in summaries[wanted].parameters.items() if k in _MAIN):
            # an undecided slip hulls both fits: a one-sided result needs the other's profile too
            for other in (s for s in summaries if s != wanted):
                summaries[other] = summarize(fits[other], profile=True)
        verdict = dict(decide(summaries), parameters_from=wanted)
    return Stage(fits=fits, summaries=summaries, verdict=verdict, model=model_info, effects=effects,
                 singles=singles, segs=segs, large=large)
