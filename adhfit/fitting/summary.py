"""Turn one slip condition's optimum (:class:`~.objective.ObjectiveFit`) into a :class:`~.result.SlipFit`.

Intervals and their status come from :mod:`.intervals`; this module adds what a reader of one slip
condition's fit needs besides: the information criteria, χ² in units of the noise, the fitted curves,
the plain warnings (one-sided bounds, correlated noise, a misfit, a drifting zero) and the solver
details (covariance, kink, profiles, starts).  One curve or several: every per-curve sentence is built
per member; with several curves it names the curve.
"""
from __future__ import annotations

import math

import numpy as np

from .checks import DRIFT_FLOOR, curve_rows
from .intervals import estimates, profiles, split_hull
from .model import ModelDomainError
from .checks import correlation_factor, widen, zero_drift
from .result import SlipFit
from .starts import noise_estimate

__all__ = ["summarize", "DISAGREE", "model_curve", "status_warnings", "MISFIT_RATIO", "MISFIT_HEAD",
           "POSSIBLE_MISFIT_HEAD", "correlated_ratio", "implausible"]

#: profile and covariance half-widths differing by more than this fraction earn a note
DISAGREE = 0.25
_PLAIN = {"work_of_adhesion": "W_ad", "mu_h": "μh"}
#: RMS residual, as a fraction of the largest force, below which the residuals are the model's own
#: numerical error (3x its interpolation error at the default points), not noise
NUMERICAL = 3e-4
#: residual RMS over the row-to-row scatter above which the model does not describe a curve
MISFIT_RATIO = 2.0
#: how every misfit sentence begins (the result puts it first; the command line prints it)
MISFIT_HEAD = "The model does not describe these data to within their row-to-row scatter"
#: how a sentence begins when the residuals are as large as correlated noise could make them
POSSIBLE_MISFIT_HEAD = "The model may not describe these data"


def model_curve(model, si: dict) -> dict:
    """Dense model curve of one curve in measured units (control value, force in N) for plots."""
    try:
        pcs = model.pieces(si["work_of_adhesion"], si["mu_h"], si["x_offset"])
    except ModelDomainError:
        return {}
    sc = model.scene.scales(si["mu_h"])
    to_meas = (sc.from_delta if model.control == "displacement" else sc.from_p)
    xl = np.linspace(min(pcs.x_contact, float(np.min(model.dimensionless_x(si["mu_h"], si["x_offset"])))),
                     pcs.x_max, 200)
    xu = pcs.x_tp + (pcs.x_max - pcs.x_tp) * np.linspace(1.0, 0.0, 200) ** 2
    f0, x0 = si["force_offset"], si["x_offset"]
    return {"x_loading": to_meas(xl) - x0, "force_loading": sc.from_f(pcs.f_loading(xl)) + f0,
            "x_unloading": to_meas(xu) - x0, "force_unloading": sc.from_f(pcs.f_unloading(xu)) + f0,
            "x_contact": float(to_meas(pcs.x_contact)) - x0, "x_onset": float(to_meas(pcs.x_onset)) - x0,
            "x_turning_point": float(to_meas(pcs.x_tp)) - x0, "force_turning_point": float(sc.from_f(pcs.f_tp)) + f0}


def _diagnostics(fit, est: dict, limits: dict) -> list[str]:
    """Solver details (for the report's diagnostics part, not for the warnings)."""
    best = fit.best
    shared, offs = fit.si()
    out = []
    if best.covar is None or any(e.stderr is None for e in est.values()):
        out.append("singular covariance: standard errors could not be estimated for every parameter")
    for m, off in zip(fit.members, offs):
        if m.model.near_turning_point(shared["work_of_adhesion"], shared["mu_h"], off["x_offset"]):
            out.append("optimum on the kink: a measured row sits at (or beyond) the model's turning point, "
                       "where dF/dx is infinite; covariance errors are fragile there (check the profile intervals)")
            break
    for name, (lo, hi) in limits.items():
        e = est[name]
        if lo.open or hi.open:
            out.append(f"the likelihood profile of {name} stays below the critical value on one side "
                       f"(to the parameter's bound or the model's domain): status {e.status}")
        elif not (lo.converged and hi.converged):
            if lo.bound is not None and hi.bound is not None:
                out.append(f"the likelihood profile of {name} did not converge: its interval reaches out to the "
                           f"nearest sub-fits beyond the critical value (wider than the profile interval)")
            else:
                out.append(f"the likelihood profile of {name} did not converge; its interval is from the covariance")
        elif e.ci95_covariance is not None and e.ci95 is not None and None not in e.ci95:
            w_p, w_c = math.log(e.ci95[1] / e.ci95[0]), math.log(e.ci95_covariance[1] / e.ci95_covariance[0])
            if w_p > 0 and abs(w_p / w_c - 1.0) > DISAGREE:
                out.append(f"{name}: the covariance interval is {w_c / w_p:.2g} times the likelihood-profile "
                           f"width; the profile interval is reported")
        if lo.better_optimum or hi.better_optimum:
            out.append(f"the profile of {name} found a lower χ² than the optimum: the fit may not have converged")
    if fit.joint:
        out.append(f"joint fit: {best.message} ({'converged' if best.success else 'not converged'})")
    if getattr(fit, "restarts", 0):
        out.append(f"the optimiser had stopped short: {fit.restarts} restart(s) from a likelihood-profile sub-fit "
                   "below the optimum")
    won = [f"{m.label or 'curve'}: {m.single.won}" if len(fit.members) > 1 else m.single.won
           for m in fit.members if m.single is not None and m.single.won]
    if won:
        out.append("the optimum came from: " + "; ".join(won))
    starts = [st for m in fit.members if m.single is not None for st in m.single.starts]
    out += [f"start {i}: χ² = {st['chisqr']:.6g}" for i, st in enumerate(starts)]
    return out


def reached(fit) -> str | None:
    """Where a test without pull-off stops, in words: the stage of its last row at the fitted values
    (contact pinning, or so many rows into delamination); None when a curve shows its pull-off."""
    shared, offs = fit.si()
    for m, off in zip(fit.members, offs):
        model = m.model
        try:
            if model.split(shared["work_of_adhesion"], shared["mu_h"], off["x_offset"]) is not None:
                continue
            pcs = model.pieces(shared["work_of_adhesion"], shared["mu_h"], off["x_offset"])
        except ModelDomainError:
            return None
        xd = model.dimensionless_x(shared["mu_h"], off["x_offset"])[model.segments.i_turn + 1:]
        if xd.size == 0:
            return "the test stops at the end of loading, so the pull-off that sets W_ad is never reached"
        n_delam = int(np.count_nonzero(xd < pcs.x_onset))
        if n_delam == 0:
            return ("the unloading stops during contact pinning, before the membrane starts to peel off, so the "
                    "pull-off that sets W_ad is never reached")
        return (f"the unloading stops {n_delam} row{'s' if n_delam > 1 else ''} into delamination, while the "
                f"membrane peels off but before it comes off, so the pull-off that sets W_ad is never reached")
    return None


def status_warnings(est: dict, why_stopped: str | None = None) -> list[str]:
    """Plain sentences for parameters the data bound from one side only or do not determine."""
    out = []
    for name, e in est.items():
        label = _PLAIN.get(name, name)
        if e.status == "lower_bound":
            why = f" ({why_stopped})" if name == "work_of_adhesion" and why_stopped else ""
            out.append(f"The data only bound {label} from below{why}: {label} ≥ {e.ci95[0]:.3g} {e.unit} "
                       f"(one-sided 95 %); no value is reported.")
        elif e.status == "upper_bound":
            out.append(f"The data only bound {label} from above: {label} ≤ {e.ci95[1]:.3g} {e.unit} "
                       f"(one-sided 95 %); no value is reported.")
        elif e.status == "undetermined" and name in _PLAIN:
            out.append(f"The data do not determine {label}: no value or interval is reported.")
    return out


def _curve_warnings(fit, k: int, row: dict, split, factor: float, est: dict) -> list[str]:
    """Per curve: a misfit against the row-to-row noise, a given σ the fit does not reach, a test that
    ends before pull-off, a drifting zero."""
    m = fit.members[k]
    who = "" if len(fit.members) == 1 else f"Curve {m.label}: "
    out = []
    if row.get("misfit"):
        out.append(who + row["misfit"])
    if fit.given["force"] and row["redchi"] > 1.0 + 4.0 * math.sqrt(2.0 / max(m.n_force - len(m.par.names), 1)):
        out.append(f"{who}The model does not fit to the given noise level: reduced χ² = {row['redchi']:.3g}.")
    if split is None and est["work_of_adhesion"].status == "determined":
        out.append(f"{who}The data end before pull-off: W_ad rests on the unloading curve alone.")
    drift = _drift(fit, k, row, split, factor)
    if drift:
        out.append(who + drift)
    return out


def correlated_ratio(rho: float) -> float:
    """The residual RMS over the row-to-row scatter (second differences) that AR(1) noise of lag-1
    autocorrelation ρ gives: var(Δ²e) = 2σ²(3 - 4ρ + ρ²), against 6σ² for white noise."""
    rho = min(max(rho, 0.0), 0.99)
    return math.sqrt(3.0 / (3.0 - 4.0 * rho + rho * rho))


_CAUSES = ("a unit or scale on a column (a force in mN headed [N], a displacement in mm headed [um]), the "
           "scene's pressure or gap (a bare number is read in Pa or m) or a radius (a bare number is in metres), "
           "or the slip condition")


#: plausibility of a fitted test (:func:`implausible`): the fixed pressure's P b/(2μh) under displacement
#: control below this is a membrane hardly inflated; a substrate radius above this many membrane radii is
#: a flat plate; a W_ad above this (J/m²) is beyond near-equilibrium adhesion a membrane test measures
P_MIN, RS_MAX, W_MAX = 0.01, 100.0, 50.0


def implausible(member, shared: dict) -> list[str]:
    """What a fitted test cannot be, in words (each names the likely mistake): a membrane hardly inflated
    under displacement control, a 'sphere' far larger than the membrane, a W_ad beyond membrane tests."""
    sc = member.model.scene
    out = []
    mu, w = shared["mu_h"], shared["work_of_adhesion"]
    if sc.control == "displacement" and sc.pressure is not None:
        p = sc.pressure * sc.membrane_radius / (2.0 * mu)
        if abs(p) < P_MIN:
            out.append(f"at the fitted μh the scene's pressure gives P b/(2μh) = {p:.2g}, a membrane hardly "
                       f"inflated (a pressure in Pa meant as kPa, or a force in mN read as N, which makes μh "
                       f"1000x too large)")
    if math.isfinite(sc.substrate_radius) and sc.substrate_radius > RS_MAX * sc.membrane_radius:
        out.append(f"the substrate radius is {sc.substrate_radius / sc.membrane_radius:.3g} times the membrane's "
                   f"(a flat plate; a radius in mm meant, or 'inf' for a flat substrate?)")
    if w > W_MAX:
        out.append(f"W_ad = {w:.3g} J/m² is beyond what a membrane test measures (near-equilibrium adhesion, "
                   f"up to ~10 J/m²): a force or length column in the wrong unit?")
    return out


def _misfit(row: dict, member, factor: float, rho: float, shared: dict) -> tuple[str | None, bool]:
    """(sentence, certain) for a curve the model may not describe: residuals above :data:`MISFIT_RATIO`
    times the row-to-row scatter (second differences, which a smooth misfit leaves alone).  Correlated
    noise (an oversampled, filtered load cell) raises that ratio too, to :func:`correlated_ratio` of the
    residuals' own ρ; beyond :data:`MISFIT_RATIO` times that, or with a fitted test that cannot be
    (:func:`implausible`), no noise explains it (``certain``: the verdict is capped and the command line
    exits 5).  Otherwise both explanations are named, the misfit first."""
    sigma, noise = row["sigma_force"], noise_estimate(member.model.force)
    if not (noise > 0 and sigma > MISFIT_RATIO * noise):
        return None, False
    ratio = sigma / noise
    allowed = correlated_ratio(rho) if factor > 1.0 else 1.0
    odd = implausible(member, shared)
    if ratio > MISFIT_RATIO * allowed or odd:
        why = (f"; and {'; '.join(odd)}" if odd else ", more than any noise explains")
        return (f"{MISFIT_HEAD}: the residuals ({sigma * 1e3:.3g} mN) are {ratio:.2g} times the row-to-row scatter "
                f"({noise * 1e3:.3g} mN){why}. Likely causes: {_CAUSES}. The slip verdict is capped at "
                f"'positive'."), True
    return (f"{POSSIBLE_MISFIT_HEAD}: the residuals ({sigma * 1e3:.3g} mN) are {ratio:.2g} times the row-to-row "
            f"scatter ({noise * 1e3:.3g} mN) and are correlated from row to row (lag-1 autocorrelation "
            f"{rho:.2f}). Either the model does not describe these data (likely causes: {_CAUSES}), or the load "
            f"cell's noise is correlated (an oversampled, filtered signal): the intervals were widened "
            f"{factor:.2g}-fold and the slip evidence discounted alike."), False


def _fitted_drift(fit, k: int, factor: float = 1.0) -> str | None:
    """The sentence for a fitted drift of the zero that the data resolve (2 standard errors, widened like
    the intervals when the noise is correlated, and above the model's precision)."""
    m = fit.members[k]
    p = fit.best.params.get(fit.spar.name("force_drift", k))
    if p is None:
        return None
    drift = p.value * m.par.f_scale
    se = p.stderr * m.par.f_scale * factor if p.stderr is not None and np.isfinite(p.stderr) else None
    f_peak = float(np.max(np.abs(m.model.force)))
    if se is None or abs(drift) <= max(2.0 * se, DRIFT_FLOOR * f_peak):
        return None
    return (f"The load-cell zero drifted by {drift * 1e3:+.3g} mN ({100 * abs(drift) / f_peak:.2g} % of the peak "
            f"force) from the first row to the last; the fit removed it as a linear drift "
            f"(offsets.force_drift ± {se * 1e3:.2g} mN). Re-tare the load cell before the next test.")


def _drift(fit, k: int, row: dict, split, factor: float = 1.0) -> str | None:
    """The zero drift: fitted (:func:`_fitted_drift`), or else the warning of :func:`.checks.zero_drift`
    from the rows at zero model force."""
    if fit.members[k].par.fit_force_drift:
        return _fitted_drift(fit, k, factor)
    m = fit.members[k].model
    predicted = row["predicted"]
    if split is None or not np.all(np.isfinite(predicted)):
        return None
    shared, offs = fit.si()
    try:
        pcs = m.pieces(shared["work_of_adhesion"], shared["mu_h"], offs[k]["x_offset"])
    except ModelDomainError:
        return None
    xd = m.dimensionless_x(shared["mu_h"], offs[k]["x_offset"])
    before = m.segments.loading & (xd < pcs.x_contact)
    after = np.arange(m.x.size) >= split
    return zero_drift(m.force - predicted, before, after, row["sigma_force"], float(np.max(np.abs(m.force))))


def _splits(fit) -> list:
    shared, offs = fit.si()
    out = []
    for m, off in zip(fit.members, offs):
        try:
            out.append(m.model.split(shared["work_of_adhesion"], shared["mu_h"], off["x_offset"]))
        except ModelDomainError:
            out.append(None)
    return out


def summarize(fit, *, profile: bool = True) -> SlipFit:
    """The :class:`SlipFit` of one slip condition (estimates, criteria, curves, warnings)."""
    best = fit.best
    limits = profiles(fit) if profile else {}
    est = split_hull(fit, estimates(fit, limits))
    rows = curve_rows(fit)
    for row, k in zip(rows, range(len(rows))):
        pred = fit.predicted(k)
        row["predicted"], row["force_residual"] = pred, fit.members[k].model.force - pred
    # residuals below 3x the model's interpolation error (~1e-4 of the largest force at the default
    # points) are numerical, not noise: their smoothness is no correlated noise
    corr_rho = [correlation_factor(r["force_residual"], NUMERICAL * float(np.max(np.abs(m.model.force))))
                for r, m in zip(rows, fit.members)]
    rho = max(c[0] for c in corr_rho)
    factor = max(c[1] for c in corr_rho)
    est = {k: widen(e, factor) for k, e in est.items()}
    splits = _splits(fit)
    aic, bic = fit.criteria()
    chisqr = float(sum(r["chisqr"] for r in rows))
    ndata, nvarys = int(sum(r["n_residuals"] for r in rows)), int(best.nvarys)
    corr = None
    if best.covar is not None:
        c = best.covar
        corr = float(c[0, 1] / math.sqrt(c[0, 0] * c[1, 1])) if c[0, 0] > 0 and c[1, 1] > 0 else None
    prof_info = {k: {"subfits": lo.n_subfits + hi.n_subfits, "evaluations": lo.nfev + hi.nfev,
                     "converged": [lo.converged, hi.converged], "open": [lo.open, hi.open]}
                 for k, (lo, hi) in limits.items()}
    lower = est["work_of_adhesion"].status == "lower_bound"
    warn = status_warnings(est, reached(fit) if lower else None)
    shared_si = fit.si()[0]
    for row, m in zip(rows, fit.members):
        row["misfit"], row["certain"] = _misfit(row, m, factor, rho, shared_si)
    if factor > 1.0 and not any(r["misfit"] for r in rows):
        which = "" if len(rows) == 1 else " of at least one curve"
        warn.append(f"The force noise{which} is correlated from row to row (lag-1 autocorrelation {rho:.2f}): "
                    f"the rows are denser than the noise is independent, so the intervals were widened "
                    f"{factor:.2g}-fold (about {100 / factor ** 2:.0f} % of the rows count as independent).")
    for k, row in enumerate(rows):
        warn += _curve_warnings(fit, k, row, splits[k], factor, est)
    one = len(fit.members) == 1
    shared, offs = fit.si()
    models = [m.model for m in fit.members]
    return SlipFit(slip=fit.slip, parameters=est, chisqr=chisqr, redchi=chisqr / max(ndata - nvarys, 1),
                   aic=aic, bic=bic, ndata=ndata, nvarys=nvarys, sigma=rows[0]["sigma_force"] if one else float("nan"),
                   correlation=corr, predicted=np.concatenate([r["predicted"] for r in rows]),
                   model_curve=model_curve(models[0], {**shared, **offs[0]}) if one else {},
                   warnings=tuple(warn), starts=tuple(st for m in fit.members if m.single for st in m.single.starts),
                   profile=prof_info, n_evaluations=sum(m.n_evaluations for m in models),
                   n_histories=sum(m.n_histories for m in models), success=bool(best.success),
                   message=str(best.message), raw=best if not fit.joint else fit,
                   diagnostics=tuple(_diagnostics(fit, est, limits)), split=splits[0] if one else None,
                   autocorrelation=rho, widening=factor, misfit=any(r["certain"] for r in rows))
