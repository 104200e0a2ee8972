"""Turn one slip condition's least-squares optimum into a :class:`~.result.SlipFit`.

Standard errors come from lmfit's covariance of the internal parameters (ln W_ad, ln μh, scaled
offsets) by the delta method; with σ estimated, lmfit has scaled that covariance by the reduced χ².
95 % intervals of W_ad and μh come from the likelihood profile (:mod:`.profile`) when it converges —
they are then compared with the covariance intervals, which the infinite slope of the force at the
turning point can make too narrow (DESIGN.md B4) — else from the covariance (normal in the internal
parameter, so log-normal for W_ad and μh).
"""
from __future__ import annotations

import math

import numpy as np
from scipy import stats

from .lsq import RawFit, residual_function
from .model import ModelDomainError
from .profile import profile_interval
from .result import Estimate, SlipFit
from .selection import information_criteria
from .starts import noise_estimate

__all__ = ["summarize", "INTERNAL", "DISAGREE"]

#: SI name -> internal lmfit name
INTERNAL = {"work_of_adhesion": "ln_work_of_adhesion", "mu_h": "ln_mu_h", "displacement_offset": "x_offset",
            "pressure_offset": "x_offset", "force_offset": "force_offset"}
#: profile and covariance half-widths differing by more than this fraction earn a warning
DISAGREE = 0.25
Z95 = float(stats.norm.ppf(0.975))


def _estimates(raw: RawFit, profiles: dict) -> dict[str, Estimate]:
    best, par = raw.best, raw.par
    si = par.si(best.params)
    out = {}
    for name in par.names:
        p = best.params[INTERNAL[name]]
        log = name in ("work_of_adhesion", "mu_h")
        value = si[name] if name in si else si["x_offset"]  # displacement_offset, pressure_offset
        factor = value if log else (par.x_scale if name != "force_offset" else par.f_scale)
        se_int = p.stderr if (p.stderr is not None and np.isfinite(p.stderr) and p.stderr > 0) else None
        back = (lambda t: math.exp(t)) if log else (lambda t, f=factor: t * f)
        cov_ci = (back(p.value - Z95 * se_int), back(p.value + Z95 * se_int)) if se_int else None
        ci, method = cov_ci, ("covariance" if cov_ci else None)
        prof = profiles.get(name)
        if prof is not None and prof[0].converged and prof[1].converged:
            ci, method = (back(prof[0].value), back(prof[1].value)), "profile"
        out[name] = Estimate(name, value, se_int * factor if se_int else None, ci, method, cov_ci)
    return out


def _model_curve(raw: RawFit) -> dict:
    """Dense model curve in measured units (control value, force in N) for plots."""
    m, si = raw.model, raw.par.si(raw.best.params)
    try:
        pcs = m.pieces(si["work_of_adhesion"], si["mu_h"], si["x_offset"])
    except ModelDomainError:
        return {}
    sc = m.scene.scales(si["mu_h"])
    to_meas = (sc.from_delta if m.control == "displacement" else sc.from_p)
    xl = np.linspace(min(pcs.x_contact, float(np.min(m.dimensionless_x(si["mu_h"], si["x_offset"])))),
                     pcs.x_max, 200)
    xu = pcs.x_tp + (pcs.x_max - pcs.x_tp) * np.linspace(1.0, 0.0, 200) ** 2
    f0 = si["force_offset"]
    return {"x_loading": to_meas(xl) - si["x_offset"], "force_loading": sc.from_f(pcs.f_loading(xl)) + f0,
            "x_unloading": to_meas(xu) - si["x_offset"], "force_unloading": sc.from_f(pcs.f_unloading(xu)) + f0,
            "x_contact": float(to_meas(pcs.x_contact)) - si["x_offset"],
            "x_onset": float(to_meas(pcs.x_onset)) - si["x_offset"],
            "x_turning_point": float(to_meas(pcs.x_tp)) - si["x_offset"],
            "force_turning_point": float(sc.from_f(pcs.f_tp)) + f0}


def _warnings(raw: RawFit, est: dict, profiles: dict, curve: dict, sigma: float) -> list[str]:
    m, best, si = raw.model, raw.best, raw.par.si(raw.best.params)
    out = []
    if best.covar is None or any(e.stderr is None for e in est.values()):
        out.append("standard errors could not be estimated (singular covariance): a parameter is not "
                   "determined by these data")
    if m.near_turning_point(si["work_of_adhesion"], si["mu_h"], si["x_offset"]):
        out.append("optimum on the kink: a measured row sits at (or beyond) the model's turning point, "
                   "where dF/dx is infinite; covariance errors are fragile there (check the profile intervals)")
    for name, (lo, hi) in profiles.items():
        e = est[name]
        if not (lo.converged and hi.converged):
            out.append(f"the likelihood profile of {name} did not converge; its interval is from the covariance")
        elif e.ci95_covariance is not None:
            w_p, w_c = math.log(e.ci95[1] / e.ci95[0]), math.log(e.ci95_covariance[1] / e.ci95_covariance[0])
            if abs(w_p / w_c - 1.0) > DISAGREE:
                out.append(f"{name}: the covariance interval is {w_c / w_p:.2g} times the likelihood-profile "
                           f"width; the profile interval is reported")
        if lo.better_optimum or hi.better_optimum:
            out.append(f"the profile of {name} found a lower χ² than the optimum: the fit may not have converged")
    noise = noise_estimate(m.force)
    if noise > 0 and sigma > 2.0 * noise:
        out.append(f"poor fit: the residuals (σ = {sigma:.3g} N) are {sigma / noise:.2g} times the "
                   f"row-to-row noise ({noise:.3g} N): the model misses systematic features of the data")
    if raw.sigma_given and best.redchi > 1.0 + 4.0 * math.sqrt(2.0 / max(best.nfree, 1)):
        out.append(f"poor fit: reduced χ² = {best.redchi:.3g} with the given σ")
    if m.segments.i_jump is None:
        out.append("the data end before pull-off (no detachment jump found): W_ad rests on the unloading "
                   "curve alone")
    att = m.segments.attached
    if curve and att.any() and m.segments.i_jump is None:
        x_last = float(np.min(m.x[att]))
        if x_last > curve["x_onset"]:
            out.append("the data never reach delamination (the unloading stops before the model's onset): "
                       "W_ad is only bounded from below")
    return out


def summarize(raw: RawFit, *, profile: bool = True) -> SlipFit:
    """The :class:`SlipFit` of one slip condition (estimates, criteria, curves, warnings)."""
    best, par, m = raw.best, raw.par, raw.model
    sigma = raw.scale if raw.sigma_given else raw.scale * math.sqrt(best.redchi)
    residual = residual_function(m, par, raw.scale, sigma)
    profiles = {}
    if profile:  # without a covariance the profile still works, from a 10 % first step
        for name in ("work_of_adhesion", "mu_h"):
            profiles[name] = profile_interval(residual, best, INTERNAL[name], sigma_given=raw.sigma_given)
    est = _estimates(raw, profiles)
    si = par.si(best.params)
    try:
        predicted = m.predict(si["work_of_adhesion"], si["mu_h"], si["x_offset"], si["force_offset"])
    except ModelDomainError:
        predicted = np.full(m.force.shape, np.nan)
    curve = _model_curve(raw)
    aic, bic = information_criteria(best.chisqr, best.ndata, best.nvarys, sigma_given=raw.sigma_given)
    # χ² in units of σ²: the given σ, or the robust row-to-row noise (σ estimated)
    unit = 1.0 if raw.sigma_given else (raw.scale / (noise_estimate(m.force) or raw.scale)) ** 2
    chisqr = float(best.chisqr) * unit
    corr = None
    if best.covar is not None:
        c = best.covar
        corr = float(c[0, 1] / math.sqrt(c[0, 0] * c[1, 1])) if c[0, 0] > 0 and c[1, 1] > 0 else None
    prof_info = {k: {"subfits": lo.n_subfits + hi.n_subfits, "evaluations": lo.nfev + hi.nfev,
                     "converged": [lo.converged, hi.converged]} for k, (lo, hi) in profiles.items()}
    return SlipFit(slip=raw.slip, parameters=est, chisqr=chisqr, redchi=chisqr / max(best.nfree, 1),
                   aic=aic, bic=bic, ndata=int(best.ndata), nvarys=int(best.nvarys), sigma=float(sigma),
                   correlation=corr, predicted=predicted, model_curve=curve,
                   warnings=tuple(_warnings(raw, est, profiles, curve, sigma)), starts=tuple(raw.starts),
                   profile=prof_info, n_evaluations=m.n_evaluations, n_histories=m.n_histories,
                   success=bool(best.success), message=str(best.message), raw=best)

