"""Standard errors, 95 % intervals and their status (docs/contracts.md A5b) of an objective's optimum.

* **Covariance**: lmfit's, of the internal parameters (ln W_ad, ln μh, scaled offsets), by the delta
  method; with σ estimated lmfit has scaled it by the reduced χ².  A joint fit's covariance comes from a
  secant Jacobian at the scale of the data (:func:`secant_covariance`).
* **Profile** (:mod:`.profile`): the 95 % intervals of W_ad and μh where it converges.  They are compared
  with the covariance intervals, which the infinite slope of the force at the turning point can make
  too narrow (docs/numerics.md B4).  A joint fit reports the union of the two (a curve's last attached
  row meeting its fold stops a profile short: the recovery study's force-only profile intervals held the
  truth in 32/40, the covariance ones in 38/40).
* **Status**: a profile open on one side gives a one-sided bound; a fit whose data show no pull-off
  leaves W_ad's upper side open (:func:`no_pull_off`).
* **Row hull**: the optima with the pull-off one row earlier or later that the data cannot reject
  widen a one-curve fit's intervals (:func:`split_hull`).
"""
from __future__ import annotations

import dataclasses
import math

import numpy as np
from scipy import stats

from .lsq import PENALTY, minimise
from .model import ModelDomainError
from .objective import SIGMA_FLOOR
from .profile import ProfileLimit, critical_value, one_side
from .result import Estimate

__all__ = ["INTERNAL", "Z95", "MAX_LOG_SE", "MAX_ROUNDS", "estimates", "secant_covariance", "apply_secant",
           "no_pull_off", "split_hull", "from_profile", "honest", "ROUGH"]

#: SI name -> internal lmfit name
INTERNAL = {"work_of_adhesion": "ln_work_of_adhesion", "mu_h": "ln_mu_h", "displacement_offset": "x_offset",
            "pressure_offset": "x_offset", "force_offset": "force_offset", "force_drift": "force_drift"}
Z95 = float(stats.norm.ppf(0.975))
#: standard error of ln W_ad or ln μh above which the covariance says nothing (a factor e^1.5·1.96 ≈ 20)
MAX_LOG_SE = 1.5
#: a profile sub-fit that lowers D by less than this is the χ² surface's numerical roughness (noise-free data:
#: the interpolation error moves χ² at the 1e-5 level), not a better optimum: the covariance interval stands
ROUGH = 0.1
#: rounds of the secant step search (:func:`secant_covariance`)
MAX_ROUNDS = 5
_SHARED = ("work_of_adhesion", "mu_h")


# --- the secant covariance of a joint fit ---------------------------------------------------------------
# Why: a measured row next to a curve's fold has a model value that varies as the square root of its
# distance to the fold, so its residual has an infinite slope in that curve's offset and in W_ad and μh.
# The optimiser's finite-difference Jacobian sees that slope, and inv(JᵀJ) then pins the offset ~100-fold
# too tightly and hands that curve most of the W_ad precision.  Here each column of J is a central secant
# over ±h_k, h_k the parameter's own conditional standard deviation found from the residual itself (χ²
# rises by ~1): the usual Gauss-Newton covariance where the model is smooth, the cusp averaged over the
# range the data allow at a fold.

def _residual_at(residual, params, names, theta, clip: bool) -> np.ndarray:
    p = params.copy()
    for n, t in zip(names, theta):
        p[n].value = float(np.clip(t, p[n].min, p[n].max)) if clip else float(t)
    return np.asarray(residual(p), float)


def _chi2(residual, params, names, theta) -> float:
    r = _residual_at(residual, params, names, theta, clip=True)
    return math.inf if np.any(r == PENALTY) else float(r @ r)


def _scale(residual, params, names, theta0, k, h, chi0) -> float:
    """The step along coordinate k at which χ² rises by ~1 (a conditional standard deviation)."""
    for _ in range(MAX_ROUNDS):
        e = np.zeros(theta0.size)
        e[k] = h
        rise = 0.5 * (_chi2(residual, params, names, theta0 + e) + _chi2(residual, params, names, theta0 - e)) - chi0
        if not math.isfinite(rise):
            return h * 0.5
        new = float(np.clip(h / math.sqrt(rise) if rise > 1e-6 else 10.0 * h, h / 30.0, 30.0 * h))
        if abs(math.log(new / h)) < math.log(1.3):
            return new
        h = new
    return h


def secant_covariance(residual, best) -> tuple[np.ndarray | None, np.ndarray | None]:
    """(covariance, steps) of the varying parameters of ``best`` (an lmfit result whose residual is in
    units of σ), in ``best.var_names`` order; ``(None, None)`` when it cannot be formed."""
    names = list(best.var_names)
    params = best.params
    theta0 = np.array([params[n].value for n in names])
    c0 = best.covar
    se0 = np.sqrt(np.clip(np.diag(c0), 1e-24, None)) if c0 is not None else np.full(theta0.size, 1e-3)
    chi0 = _chi2(residual, params, names, theta0)
    if not math.isfinite(chi0):
        return None, None
    steps = np.array([_scale(residual, params, names, theta0, k, float(se0[k]), chi0) for k in range(theta0.size)])
    cols = []
    for k, h in enumerate(steps):
        e = np.zeros(theta0.size)
        e[k] = h
        rp = _residual_at(residual, params, names, theta0 + e, clip=False)
        rm = _residual_at(residual, params, names, theta0 - e, clip=False)
        if np.any(rp == PENALTY) or np.any(rm == PENALTY):
            return None, None
        cols.append((rp - rm) / (2.0 * h))
    jac = np.column_stack(cols)
    return np.linalg.pinv(jac.T @ jac), steps


def apply_secant(fit) -> bool:
    """Replace a joint fit's covariance and standard errors by :func:`secant_covariance` (the steps are
    kept in ``fit.secant_steps``); False when it cannot be formed."""
    cov, steps = secant_covariance(fit.residual, fit.best)
    fit.secant_steps = steps
    if cov is None or not np.all(np.isfinite(cov)) or np.any(np.diag(cov) <= 0):
        return False
    fit.best.covar = cov
    for k, n in enumerate(fit.best.var_names):
        fit.best.params[n].stderr = float(math.sqrt(cov[k, k]))
    return True


# --- profiles and status ---------------------------------------------------------------------------------

def from_profile(prof, back, ci, method, status):
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


def no_pull_off(fit) -> bool:
    """True when no member's data show the pull-off at the optimum: the test ended before the membrane
    came off.

    Then every W_ad above the largest G reached gives the same pinning-only curve (a flat profile), and
    a W_ad just below it moves only the last rows, by an amount the fit chooses: a change point at the
    end of the data, which fits the noise of those rows (one +3σ last row gave Δχ² = 8 against the
    plateau and a tight interval excluding the truth).  The χ²(1)/F limit does not hold for such a
    change point, and a test that simply ends is not evidence of delamination: W_ad's upper side is open.
    The recovery study also found optima that spread a false delamination over many rows of pure
    pinning data, so the rule holds for every optimum without a pull-off in the data.
    """
    shared, offs = fit.si()
    for m, off in zip(fit.members, offs):
        try:
            if m.model.split(shared["work_of_adhesion"], shared["mu_h"], off["x_offset"]) is not None:
                return False
        except ModelDomainError:
            return False
    return True


GAP_FRACTION = 0.05


def gap_start(fit):
    """The second start of the profile sub-fits (:func:`.profile.profile_interval`), or ``None``.

    χ² jumps where the model's pull-off crosses a row: a sub-fit with W_ad fixed whose start puts the
    pull-off on the wrong side of the last attached row stays in that valley, several units of χ² above the
    profile (shallow displacement-control tests at 3 % noise: D = 10.4 at the true W_ad against 1.9 from a
    start at the truth; the 95 % intervals then missed the truth in 16 of 80 replicates).  The start moves
    each curve's control offset so that its model's pull-off sits in the middle of the gap the data leave
    between the last attached and the first detached row; it is tried only when a sub-fit ended with the
    pull-off outside that gap.
    """
    spar = fit.spar
    movable = [(i, m) for i, m in enumerate(fit.members)
               if m.par.fit_x_offset and m.model.fixed_split and m.model.jump is not None]
    if not movable:
        return None

    def realign(params):
        v = {k: float(p.value) for k, p in params.items()}
        out, moved = params.copy(), False
        for i, m in movable:
            si = m.par.si(spar.member_values(v, i))
            x_a, x_d, _ = m.model.jump
            lo, hi, target = min(x_a, x_d), max(x_a, x_d), None
            off = si["x_offset"]
            for k in range(4):  # the pull-off moves with the offset's loading end too: a few fixed-point steps
                try:
                    tp = m.model.turning_point(si["work_of_adhesion"], si["mu_h"], off)[0]
                except ModelDomainError:
                    break
                if k == 0 and lo <= tp <= hi:
                    break
                if target is None:  # just inside the gap, at the edge the pull-off is outside of
                    near_a = abs(tp - x_a) <= abs(tp - x_d)
                    target = x_a + GAP_FRACTION * (x_d - x_a) if near_a else x_d - GAP_FRACTION * (x_d - x_a)
                off += tp - target
            else:
                p = out[spar.name("x_offset", i)]
                p.value = float(np.clip(off / m.par.x_scale, p.min, p.max))
                moved = True
        return out if moved else None
    return realign


def _profile(residual, best, name: str, sigma_given: bool, upper_open: bool = False, floor: float = 0.0,
             realign=None):
    """(lower, upper) profile limits; when one side is open, the other is the one-sided 95 % bound
    (the two-sided 90 % limit).  The upper side goes first: it is the one a test stopped before
    delamination leaves open for W_ad, so the lower side is then computed once, at the right level.
    ``upper_open``: the upper side is open without probing it (:func:`no_pull_off`)."""
    kw = {"sigma_given": sigma_given, "s2_floor": floor, "realign": realign}
    if upper_open:
        return (one_side(residual, best, name, -1.0, level=0.90, **kw),
                ProfileLimit(None, 0, False, False, 0, open=True))
    hi = one_side(residual, best, name, +1.0, level=0.95, **kw)
    lo = one_side(residual, best, name, -1.0, level=0.90 if hi.open else 0.95, **kw)
    if lo.open and not hi.open:
        side = one_side(residual, best, name, +1.0, level=0.90, **kw)
        hi = side if side.bound is not None else hi
    return lo, hi


#: refits from a better point a profile found, before its limits are accepted
PROFILE_RESTARTS = 2


def _limits(fit) -> dict:
    tail = no_pull_off(fit)
    residual = fit.residual
    # σ estimated, one block: the residual is in units of the largest force, and the model's precision
    # (the history's interpolation, ~1e-5 of it) floors the noise the profile steps are judged by
    floor = 0.0 if fit.sigma_given else (SIGMA_FLOOR * fit.members[0].par.f_scale / fit.members[0].sigma_f) ** 2
    realign = gap_start(fit)
    return {name: _profile(residual, fit.best, INTERNAL[name], fit.sigma_given,
                           upper_open=tail and name == "work_of_adhesion", floor=floor, realign=realign)
            for name in _SHARED}


def profiles(fit) -> dict:
    """Profile limits of W_ad and μh of an objective's optimum.

    A profile sub-fit that ends below the optimum's χ² (by :data:`ROUGH` units of D or more) shows that
    the optimiser had stopped short (at the kink of the turning point, typically): the fit is restarted
    from that point, all parameters free, and the profiles are computed again (at most
    :data:`PROFILE_RESTARTS` times).  The restart replaces the fit's optimum (``fit.restarts`` counts them).
    """
    fit.restarts = getattr(fit, "restarts", 0)
    for _ in range(PROFILE_RESTARTS + 1):
        limits = _limits(fit)
        sides = [side for pair in limits.values() for side in pair if side.better and side.gain >= ROUGH]
        if not sides or fit.restarts >= PROFILE_RESTARTS:
            return limits
        start = max(sides, key=lambda side: side.gain).better
        params = fit.best.params.copy()
        for k, v in start.items():
            params[k].value = v
        res = minimise(fit.residual, params, scale_covar=not fit.sigma_given)
        if not res.chisqr < fit.best.chisqr:
            return limits
        fit.replace_best(res)
        fit.restarts += 1
    return limits


def _names(fit) -> list[str]:
    """The estimates a fit reports: W_ad and μh, and a one-curve fit's offsets (a series reports each
    curve's offsets in its curves' entries)."""
    return list(fit.members[0].par.names) if len(fit.members) == 1 else list(_SHARED)


def estimates(fit, profile_limits: dict) -> dict[str, Estimate]:
    """Value, standard error, 95 % interval and status of every reported parameter (module docstring)."""
    best = fit.best
    par = fit.members[0].par
    shared, offs = fit.si()
    si = {**shared, **offs[0]}
    out = {}
    for name in _names(fit):
        p = best.params[INTERNAL[name]]
        log = name in _SHARED
        value = si[name] if name in si else si["x_offset"]  # displacement_offset, pressure_offset
        factor = value if log else (par.f_scale if name.startswith("force_") else par.x_scale)
        se_int = p.stderr if (p.stderr is not None and np.isfinite(p.stderr) and p.stderr > 0) else None
        back = (lambda t: math.exp(min(t, 700.0))) if log else (lambda t, f=factor: t * f)
        if log and se_int is not None and se_int > MAX_LOG_SE:  # a factor > 20 either way: not a number
            se_int = None
        cov_ci = (back(p.value - Z95 * se_int), back(p.value + Z95 * se_int)) if se_int else None
        ci, method = cov_ci, ("covariance" if cov_ci else None)
        status = "determined" if cov_ci else "undetermined"
        prof = profile_limits.get(name)
        if prof is not None and cov_ci and any(side.better_optimum and side.gain < ROUGH for side in prof):
            # sub-fits below the optimum by less than the χ² surface's roughness: the covariance stands, widened
            # to a two-sided profile interval that reaches further (at the turning point's kink the covariance
            # can be 100x too narrow: μh 1.9253-1.9276 N/m against a profile 1.857-2.009 at 3 % noise)
            method = "covariance (the likelihood profile is below the χ² surface's numerical roughness)"
            p_ci, _, p_status = from_profile(prof, back, ci, method, status)
            if p_status == "determined" and p_ci and None not in p_ci and (p_ci[0] < ci[0] or p_ci[1] > ci[1]):
                ci = (min(ci[0], p_ci[0]), max(ci[1], p_ci[1]))
                method = "covariance ∪ profile (sub-fits below the optimum within the χ² surface's roughness)"
        elif prof is not None:
            ci, method, status = from_profile(prof, back, ci, method, status)
            if fit.joint and status == "determined" and cov_ci and ci and None not in ci:
                ci, method = (min(ci[0], cov_ci[0]), max(ci[1], cov_ci[1])), f"{method} ∪ covariance"
        out[name] = honest(Estimate(name, value, se_int * factor if se_int else None, ci, method, cov_ci, status))
    return out


def _usable(ci, value: float) -> bool:
    """A two-sided interval with finite ends that is wider than the numbers' own precision."""
    if ci is None or None in ci or not all(math.isfinite(v) for v in ci):
        return False
    return ci[1] - ci[0] > 1e-9 * max(abs(value), abs(ci[0]), abs(ci[1]), 1e-300)


def honest(e: Estimate) -> Estimate:
    """Never a zero-width or non-finite interval called ``determined``: the covariance interval where it is
    usable, else ``undetermined``; a one-sided bound must be finite."""
    if e.status == "determined" and not _usable(e.ci95, e.value):
        if _usable(e.ci95_covariance, e.value):
            return dataclasses.replace(e, ci95=e.ci95_covariance,
                                       ci_method=f"covariance (the {e.ci_method} interval had no width)")
        return dataclasses.replace(e, ci95=None, status="undetermined", ci_method=f"{e.ci_method} (no usable interval)")
    if e.status in ("lower_bound", "upper_bound"):
        bound = e.ci95[0] if e.status == "lower_bound" else e.ci95[1]
        if bound is None or not math.isfinite(bound):
            return dataclasses.replace(e, ci95=None, status="undetermined")
    return e


def split_hull(fit, est: dict) -> dict:
    """Widen W_ad's and μh's intervals to cover the optima with the pull-off one row earlier or later
    when the data cannot reject them (Δχ² below the profile's critical value): at a few per cent noise
    the detachment row itself can be uncertain, and each row's fit alone knows only its own row."""
    raw = fit.single
    if raw is None or not raw.alternatives:
        return est
    best = raw.best
    n_free = int(best.ndata - best.nvarys)
    s2 = 1.0 if raw.sigma_given else best.chisqr / max(n_free, 1)
    crit = critical_value(n_free, raw.sigma_given)
    out = dict(est)
    for alt in raw.alternatives:
        if alt["dchisqr"] / s2 >= crit:
            continue
        for name in _SHARED:
            e = out[name]
            if e.status != "determined" or e.ci95 is None or not e.value:
                continue
            r = alt[name] / e.value
            lo, hi = min(e.ci95[0], e.ci95[0] * r), max(e.ci95[1], e.ci95[1] * r)
            if (lo, hi) != tuple(e.ci95):
                out[name] = dataclasses.replace(e, ci95=(lo, hi), ci_method=f"{e.ci_method} (hull over the "
                                                "pull-off rows the data allow)")
    return out
