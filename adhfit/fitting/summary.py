"""Turn one slip condition's least-squares optimum into a :class:`~.result.SlipFit`.

Standard errors come from lmfit's covariance of the internal parameters (ln W_ad, ln μh, scaled
offsets) by the delta method; with σ estimated, lmfit has scaled that covariance by the reduced χ².
95 % intervals of W_ad and μh come from the likelihood profile (:mod:`.profile`) when it converges —
they are then compared with the covariance intervals, which the infinite slope of the force at the
turning point can make too narrow (docs/numerics.md B4) — else from the covariance (normal in the internal
parameter, so log-normal for W_ad and μh).
"""
from __future__ import annotations

import dataclasses
import math

import numpy as np
from scipy import stats

from .lsq import RawFit, residual_function
from .model import ModelDomainError
from .profile import ProfileLimit, critical_value, one_side
from .residual_checks import correlation_factor, widen, zero_drift
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
#: standard error of ln W_ad or ln μh above which the covariance says nothing (a factor e^1.5·1.96 ≈ 20)
MAX_LOG_SE = 1.5


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
        back = (lambda t: math.exp(min(t, 700.0))) if log else (lambda t, f=factor: t * f)
        if log and se_int is not None and se_int > MAX_LOG_SE:  # a factor > 20 either way: not a number
            se_int = None
        cov_ci = (back(p.value - Z95 * se_int), back(p.value + Z95 * se_int)) if se_int else None
        ci, method = cov_ci, ("covariance" if cov_ci else None)
        status = "determined" if cov_ci else "undetermined"
        prof = profiles.get(name)
        if prof is not None:
            ci, method, status = _from_profile(prof, back, ci, method, status)
        out[name] = Estimate(name, value, se_int * factor if se_int else None, ci, method, cov_ci, status)
    return out


def _from_profile(prof, back, ci, method, status):
    """(ci95, method, status) from a profile's two sides (docs/contracts.md A5b)."""
    lo, hi = prof
    if lo.open and hi.open:
        return None, "profile", "undetermined"
    if hi.open:
        return ((back(lo.bound), None), "profile (one-sided 95 %)", "lower_bound") if lo.bound is not None \
            else (None, "profile", "undetermined")
    if lo.open:
        return ((None, back(hi.bound)), "profile (one-sided 95 %)", "upper_bound") if hi.bound is not None \
            else (None, "profile", "undetermined")
    if lo.bound is not None and hi.bound is not None:
        return (back(lo.bound), back(hi.bound)), "profile", "determined"
    return ci, method, status


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


_PLAIN = {"work_of_adhesion": "W_ad", "mu_h": "μh"}


def _diagnostics(raw: RawFit, est: dict, profiles: dict) -> list[str]:
    """Solver details (for the report's diagnostics part, not for the warnings)."""
    m, best, si = raw.model, raw.best, raw.par.si(raw.best.params)
    out = []
    if best.covar is None or any(e.stderr is None for e in est.values()):
        out.append("singular covariance: standard errors could not be estimated for every parameter")
    if m.near_turning_point(si["work_of_adhesion"], si["mu_h"], si["x_offset"]):
        out.append("optimum on the kink: a measured row sits at (or beyond) the model's turning point, "
                   "where dF/dx is infinite; covariance errors are fragile there (check the profile intervals)")
    for name, (lo, hi) in profiles.items():
        e = est[name]
        if lo.open or hi.open:
            out.append(f"the likelihood profile of {name} stays below the critical value on one side "
                       f"(to the parameter's bound or the model's domain): status {e.status}")
        elif not (lo.converged and hi.converged):
            out.append(f"the likelihood profile of {name} did not converge; its interval is from the covariance")
        elif e.ci95_covariance is not None and e.ci95 is not None and None not in e.ci95:
            w_p, w_c = math.log(e.ci95[1] / e.ci95[0]), math.log(e.ci95_covariance[1] / e.ci95_covariance[0])
            if w_p > 0 and abs(w_p / w_c - 1.0) > DISAGREE:
                out.append(f"{name}: the covariance interval is {w_c / w_p:.2g} times the likelihood-profile "
                           f"width; the profile interval is reported")
        if lo.better_optimum or hi.better_optimum:
            out.append(f"the profile of {name} found a lower χ² than the optimum: the fit may not have converged")
    out += [f"start {i}: χ² = {st['chisqr']:.6g}" for i, st in enumerate(raw.starts)]
    return out


def _warnings(raw: RawFit, est: dict, sigma: float, rho: float, factor: float, split) -> list[str]:
    """Plain sentences a lab user understands (docs/contracts.md A5b)."""
    m, best = raw.model, raw.best
    out = []
    for name, e in est.items():
        label = _PLAIN.get(name, name)
        if e.status == "lower_bound":
            why = (" (the unloading stops before the membrane starts to peel off, so the pull-off that "
                   "sets W_ad is never reached)" if name == "work_of_adhesion" else "")
            out.append(f"The data only bound {label} from below{why}: {label} ≥ {e.ci95[0]:.3g} {e.unit} "
                       f"(one-sided 95 %); no value is reported.")
        elif e.status == "upper_bound":
            out.append(f"The data only bound {label} from above: {label} ≤ {e.ci95[1]:.3g} {e.unit} "
                       f"(one-sided 95 %); no value is reported.")
        elif e.status == "undetermined" and name in _PLAIN:
            out.append(f"The data do not determine {label}: no value or interval is reported.")
    if factor > 1.0:
        out.append(f"The force noise is correlated from row to row (lag-1 autocorrelation {rho:.2f}): the rows "
                   f"are denser than the noise is independent, so the intervals were widened {factor:.2g}-fold "
                   f"(about {100 / factor ** 2:.0f} % of the rows count as independent).")
    noise = noise_estimate(m.force)
    if factor == 1.0 and noise > 0 and sigma > 2.0 * noise:
        out.append(f"The model does not follow the data to within the noise: the residuals ({sigma * 1e3:.3g} mN) "
                   f"are {sigma / noise:.2g} times the row-to-row scatter ({noise * 1e3:.3g} mN). Check the scene "
                   f"(geometry, pressure or gap), the units and the slip condition.")
    if raw.sigma_given and best.redchi > 1.0 + 4.0 * math.sqrt(2.0 / max(best.nfree, 1)):
        out.append(f"The model does not fit to the given noise level: reduced χ² = {best.redchi:.3g}.")
    if split is None and est["work_of_adhesion"].status == "determined":
        out.append("The data end before pull-off: W_ad rests on the unloading curve alone.")
    return out


def _split_hull(raw: RawFit, est: dict) -> dict:
    """Widen W_ad's and μh's intervals to cover the optima with the pull-off one row earlier or later
    when the data cannot reject them (Δχ² below the profile's critical value): at a few per cent noise
    the detachment row itself can be uncertain, and each row's fit alone knows only its own row."""
    best = raw.best
    n_free = int(best.ndata - best.nvarys)
    s2 = 1.0 if raw.sigma_given else best.chisqr / max(n_free, 1)
    crit = critical_value(n_free, raw.sigma_given)
    out = dict(est)
    for alt in raw.alternatives:
        if alt["dchisqr"] / s2 >= crit:
            continue
        for name in ("work_of_adhesion", "mu_h"):
            e = out[name]
            if e.status != "determined" or e.ci95 is None or not e.value:
                continue
            r = alt[name] / e.value
            lo, hi = min(e.ci95[0], e.ci95[0] * r), max(e.ci95[1], e.ci95[1] * r)
            if (lo, hi) != tuple(e.ci95):
                out[name] = dataclasses.replace(e, ci95=(lo, hi), ci_method=f"{e.ci_method} (hull over the "
                                                "pull-off rows the data allow)")
    return out


def _tail_onset(raw: RawFit) -> bool:
    """True when the optimum has no pull-off in the data: the test ended before the membrane came off.

    Then every W_ad above the largest G reached gives the same pinning-only curve (a flat profile), and
    a W_ad just below it moves only the last rows, by an amount the fit chooses: a change point at the
    end of the data, which fits the noise of those rows (one +3σ last row gave Δχ² = 8 against the
    plateau and a tight interval excluding the truth).  The χ²(1)/F limit does not hold for such a
    change point, and a test that simply ends is not evidence of delamination: W_ad's upper side is open.

    The recovery study also found optima that spread a false delamination over many rows of pure
    pinning data (W_ad half the largest G reached, a tight interval excluding the truth), so the rule is
    applied to every optimum without a pull-off in the data, however many rows its delamination covers:
    without the pull-off W_ad is reported as a one-sided lower bound (conservative when the data do
    reach some delamination, never a confident wrong value).
    """
    m, si = raw.model, raw.par.si(raw.best.params)
    w, mu, off = si["work_of_adhesion"], si["mu_h"], si["x_offset"]
    try:
        return m.split(w, mu, off) is None
    except ModelDomainError:
        return False


def _profile(residual, best, name: str, sigma_given: bool, upper_open: bool = False):
    """(lower, upper) profile limits; when one side is open, the other is the one-sided 95 % bound
    (the two-sided 90 % limit).  The upper side goes first: it is the one a test stopped before
    delamination leaves open for W_ad, so the lower side is then computed once, at the right level.
    ``upper_open``: the upper side is open without probing it (:func:`_tail_onset`)."""
    if upper_open:
        return (one_side(residual, best, name, -1.0, sigma_given=sigma_given, level=0.90),
                ProfileLimit(None, 0, False, False, 0, open=True))
    hi = one_side(residual, best, name, +1.0, sigma_given=sigma_given, level=0.95)
    lo = one_side(residual, best, name, -1.0, sigma_given=sigma_given, level=0.90 if hi.open else 0.95)
    if lo.open and not hi.open:
        side = one_side(residual, best, name, +1.0, sigma_given=sigma_given, level=0.90)
        hi = side if side.bound is not None else hi
    return lo, hi


def summarize(raw: RawFit, *, profile: bool = True) -> SlipFit:
    """The :class:`SlipFit` of one slip condition (estimates, criteria, curves, warnings)."""
    best, par, m = raw.best, raw.par, raw.model
    sigma = raw.scale if raw.sigma_given else raw.scale * math.sqrt(best.redchi)
    residual = residual_function(m, par, raw.scale, sigma)
    profiles = {}
    if profile:  # without a covariance the profile still works, from a 10 % first step
        tail = _tail_onset(raw)
        for name in ("work_of_adhesion", "mu_h"):
            profiles[name] = _profile(residual, best, INTERNAL[name], raw.sigma_given,
                                      upper_open=tail and name == "work_of_adhesion")
    est = _split_hull(raw, _estimates(raw, profiles))
    si = par.si(best.params)
    try:
        predicted = m.predict(si["work_of_adhesion"], si["mu_h"], si["x_offset"], si["force_offset"])
        split = m.split(si["work_of_adhesion"], si["mu_h"], si["x_offset"])
    except ModelDomainError:
        predicted, split = np.full(m.force.shape, np.nan), None
    rho, factor = correlation_factor(m.force - predicted)
    est = {k: widen(e, factor) for k, e in est.items()}
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
                     "converged": [lo.converged, hi.converged], "open": [lo.open, hi.open]}
                 for k, (lo, hi) in profiles.items()}
    warn = _warnings(raw, est, sigma, rho, factor, split)
    drift = _drift(raw, si, predicted, sigma, split)
    if drift:
        warn.append(drift)
    return SlipFit(slip=raw.slip, parameters=est, chisqr=chisqr, redchi=chisqr / max(best.nfree, 1),
                   aic=aic, bic=bic, ndata=int(best.ndata), nvarys=int(best.nvarys), sigma=float(sigma),
                   correlation=corr, predicted=predicted, model_curve=curve,
                   warnings=tuple(warn), starts=tuple(raw.starts),
                   profile=prof_info, n_evaluations=m.n_evaluations, n_histories=m.n_histories,
                   success=bool(best.success), message=str(best.message), raw=best,
                   diagnostics=tuple(_diagnostics(raw, est, profiles)), split=split,
                   autocorrelation=rho, widening=factor)


def _drift(raw: RawFit, si: dict, predicted: np.ndarray, sigma: float, split) -> str | None:
    """The zero-drift warning (:func:`.residual_checks.zero_drift`) from the rows at zero model force."""
    m = raw.model
    if split is None or not np.all(np.isfinite(predicted)):
        return None
    try:
        pcs = m.pieces(si["work_of_adhesion"], si["mu_h"], si["x_offset"])
    except ModelDomainError:
        return None
    xd = m.dimensionless_x(si["mu_h"], si["x_offset"])
    before = m.segments.loading & (xd < pcs.x_contact)
    after = np.arange(m.x.size) >= split
    return zero_drift(m.force - predicted, before, after, sigma, float(np.max(np.abs(m.force))))
