"""Likelihood-profile intervals: the check of the covariance intervals that docs/numerics.md B4 asks for.

For a parameter θ (internally ln W_ad or ln μh) the profile fixes θ and refits every other parameter.
The 95 % limits are where the statistic

    D(θ) = (χ²(θ) - χ²_min) / s²

reaches its critical value: with σ given, s² = 1 and the critical value is the χ²(1) quantile 3.84;
with σ estimated from the residuals, s² = χ²_min/(n - k) and the critical value is the F(1, n - k)
quantile — the F-test that ``lmfit.conf_interval`` uses (``lmfit.confidence.f_compare``).

``lmfit.conf_interval`` itself brackets in steps of one standard error and refines to a relative
tolerance of 5e-5, about ten times the sub-fits needed here.  This module solves for the same limits
by secant steps in sqrt(D) (linear in θ near a regular optimum), warm-starting the other parameters at
their conditional means from the covariance, and stops at 3 % in sqrt(D): a precision far below the
interval's own statistical uncertainty.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy import stats

from .lsq import PENALTY, minimise

__all__ = ["ProfileLimit", "profile_interval", "one_side", "critical_value"]

#: stop when sqrt(D/critical) is within this of 1
TOL = 0.03
MAX_SUBFITS = 8
#: a side is open when two successive probes, the last beyond FLAT_STEPS first-step standard errors and
#: beyond FLAT_MIN (internal units: a factor e^0.5 in W_ad or μh), both stay below this fraction of the
#: critical sqrt(D).  FLAT_MIN: at the turning point's kink the covariance's standard error can be 100x too
#: small (0.0007 in ln μh under pressure control at 3 % noise), and "flat over five of them" then called a side
#: open after two probes 0.3 % out, whose hull became a 0.1 %-wide interval that missed the truth
FLAT_Q = 0.1
FLAT_STEPS = 5.0
FLAT_MIN = 0.5
#: a limit bracketed between probes this close (relative to the inner probe's offset) is found
BRACKET = 0.01
#: largest first step of a profile, internal units (a factor e in W_ad or μh)
MAX_FIRST_STEP = 1.0
#: tolerance of the sub-fits (see lsq.minimise)
SUBFIT_TOL = 1e-5


@dataclass(frozen=True)
class ProfileLimit:
    """One side of a profile interval (internal units).

    Attributes
    ----------
    value : float or None
        The limit, ``None`` if not found.
    n_subfits : int
    converged : bool
    better_optimum : bool
        A sub-fit found a lower χ² than the optimum (the fit had not converged).
    nfev : int
        Model evaluations spent.
    outer : float or None
        The probe nearest the optimum whose χ² exceeded the critical value (internal units).
    open : bool
        The data do not bound the parameter on this side: χ² stays below the critical value up to the
        parameter's bound or to the edge of the model's domain (a one-sided result, docs/contracts.md A5b).
    gain : float
        The largest drop of D below the optimum's that a sub-fit found (0 when none): a drop far below
        one unit of D is the χ² surface's numerical roughness, not a better optimum.
    better : dict or None
        The internal parameter values of that sub-fit (a start for a refit).
    """

    value: float | None
    n_subfits: int
    converged: bool
    better_optimum: bool
    nfev: int
    open: bool = False
    outer: float | None = None
    gain: float = 0.0
    better: dict | None = None

    @property
    def bound(self) -> float | None:
        """The limit if found, else the nearest probe known to lie beyond it (a conservative limit)."""
        return self.value if self.converged else self.outer


def critical_value(n_free: int, sigma_given: bool, level: float = 0.95) -> float:
    """Critical value of D: χ²(1) quantile (σ given) or F(1, n - k) quantile (σ estimated)."""
    if sigma_given:
        return float(stats.chi2.ppf(level, 1))
    return float(stats.f.ppf(level, 1, max(n_free, 1)))


def _subfit(residual, best, name, value, cov_shift, scale_covar, realign=None):
    params = best.params.copy()
    for other, shift in cov_shift.items():
        p = params[other]
        p.value = float(np.clip(best.params[other].value + shift, p.min, p.max))
    params[name].value = value
    params[name].vary = False
    if np.all(np.abs(residual(params)) >= PENALTY * 0.999):  # the warm start left the model's domain
        for other in cov_shift:
            params[other].value = best.params[other].value
    res = minimise(residual, params, scale_covar=scale_covar, max_nfev=200, tol=SUBFIT_TOL)
    other = realign(res.params) if realign is not None else None
    if other is not None:  # the sub-fit ended with the model's pull-off outside the data's gap: try it inside
        alt = minimise(residual, other, scale_covar=scale_covar, max_nfev=200, tol=SUBFIT_TOL)
        alt.nfev += res.nfev
        if alt.chisqr < res.chisqr:
            return alt
        res.nfev = alt.nfev
    return res


def _outside(res) -> bool:
    """True when a sub-fit ended outside the model's domain (the residual's penalty marker)."""
    r = getattr(res, "residual", None)
    return r is not None and np.size(r) > 0 and bool(np.all(np.abs(r) >= PENALTY * 0.999))


def _side(residual, best, name, direction, crit, s2, scale_covar, realign=None) -> ProfileLimit:
    names = list(best.var_names)
    i = names.index(name)
    theta0 = best.params[name].value
    cov = best.covar
    se = math.sqrt(cov[i, i]) if cov is not None and cov[i, i] > 0 else 0.1
    slopes = {o: (cov[names.index(o), i] / cov[i, i] if cov is not None and 0 < cov[i, i] < 1.0 else 0.0)
              for o in names if o != name}
    se = min(se, MAX_FIRST_STEP)  # a flat direction (huge se) is explored from a sane first step
    lo, hi = best.params[name].min, best.params[name].max
    t = direction * math.sqrt(crit) * se
    tried, nfev, better, hit_domain, gain, where = [], 0, False, False, 0.0, None
    for k in range(MAX_SUBFITS):
        value = float(np.clip(theta0 + t, lo, hi))
        res = _subfit(residual, best, name, value, {o: s * (value - theta0) for o, s in slopes.items()},
                      scale_covar, realign)
        nfev += res.nfev
        if _outside(res):  # beyond the model's domain: the limit, if any, lies closer
            hit_domain = True
            above = [p for p in tried if p[1] >= 1.0]
            t = 0.5 * (t + (min(above, key=lambda p: abs(p[0]))[0] if above else
                            (tried[-1][0] if tried else 0.0)))
            continue
        d = (res.chisqr - best.chisqr) / s2
        if d < -1e-6 * max(best.chisqr / s2, 1.0):
            better = True
            if -d > gain:
                gain, where = -d, {k: float(p.value) for k, p in res.params.items()}
        q = math.sqrt(max(d, 0.0) / crit)
        tried.append((value - theta0, q))
        if abs(q - 1.0) < TOL:
            return ProfileLimit(value, k + 1, True, better, nfev, gain=gain, better=where)
        bracket = _bracket(tried)
        if bracket is not None and abs(bracket[1][0] - bracket[0][0]) <= BRACKET * abs(bracket[0][0]):
            # χ² jumps across the critical value between two probes this close (the model's pull-off crossing
            # a row): the limit is the jump; the probe beyond it is the (conservative) limit
            return ProfileLimit(theta0 + bracket[1][0], k + 1, True, better, nfev, outer=theta0 + bracket[1][0],
                                gain=gain, better=where)
        if value in (lo, hi) and q < 1.0:
            return ProfileLimit(value, k + 1, False, better, nfev, open=True, gain=gain, better=where)
        if len(tried) >= 2 and all(p[1] < FLAT_Q for p in tried[-2:]) and abs(t) > max(FLAT_STEPS * se, FLAT_MIN):
            # χ² barely moves over many standard errors: the data do not bound this side
            return ProfileLimit(value, k + 1, False, better, nfev, open=True, gain=gain, better=where)
        t = _next_step(tried, direction, se)
    above = [t for t, q in tried if q >= 1.0]
    far = bool(tried) and max(abs(p[0]) for p in tried) > 10.0 * se
    outer = theta0 + min(above, key=abs) if above else None
    return ProfileLimit(theta0 + tried[-1][0] if tried else None, len(tried), False, better, nfev,
                        open=not above and (hit_domain or far or not tried), outer=outer, gain=gain, better=where)


def _bracket(tried):
    """The innermost probe above the critical value and the outermost below it, or ``None``."""
    below = [(t, q) for t, q in tried if q < 1.0]
    above = [(t, q) for t, q in tried if q >= 1.0]
    if not (below and above):
        return None
    return max(below, key=lambda p: abs(p[0])), min(above, key=lambda p: abs(p[0]))


def _next_step(tried, direction, se):
    """Next offset from the optimum.  Once the limit is bracketed: the secant through the two outermost
    probes below it, where that lands inside the bracket (sqrt(D) is near-linear on the optimum's side,
    and its chord's root lies just beyond the limit where it bends up), else regula falsi between the
    bracket's ends.  Regula falsi alone kept a far first probe as one end and crept toward the limit
    from the other (sqrt(D) rose from 0.9 to 74 across the bracket): eight sub-fits ended 10 % short and
    the far probe became the reported bound.  Before a bracket: the line through the origin and the last
    probe (growth at most 4x)."""
    bracket = _bracket(tried)
    if bracket is not None:
        (t0, q0), (t1, q1) = bracket
        lo, hi = sorted((t0, t1))
        below = sorted((p for p in tried if p[1] < 1.0), key=lambda p: abs(p[0]))[-2:]
        if len(below) == 2 and below[1][1] != below[0][1]:
            (ta, qa), (tb, qb) = below
            t = tb + (1.0 - qb) * (tb - ta) / (qb - qa)
            if lo < t < hi:
                return t
        return t0 + (1.0 - q0) * (t1 - t0) / (q1 - q0)
    t1, q1 = tried[-1]
    return t1 / q1 if q1 > 0.25 else 4.0 * t1


def profile_interval(residual, best, name: str, *, sigma_given: bool, level: float = 0.95,
                     s2_floor: float = 0.0, realign=None) -> tuple[ProfileLimit, ProfileLimit]:
    """Lower and upper 95 % profile limits of internal parameter ``name`` of an lmfit result.

    Parameters
    ----------
    residual : callable
        The residual function of the fit (:func:`.lsq.residual_function`).
    best : lmfit.minimizer.MinimizerResult
        The optimum (with ``covar`` when available: it places the first probes).
    name : str
        Internal parameter name (e.g. ``"ln_work_of_adhesion"``).
    sigma_given : bool
        Whether the residuals are in units of a known σ (χ² test) or σ is estimated (F-test).
    level : float
        Two-sided level (0.90 gives the one-sided 95 % bound of a side whose other side is open).
    s2_floor : float
        Least residual variance (residual units) D is measured in when σ is estimated: the model's own
        numerical precision, under which noise-free data's χ² is interpolation roughness.
    realign : callable, optional
        Sub-fit parameters -> a second start (lmfit Parameters), or ``None`` when none is needed: χ² jumps
        where the model's pull-off crosses a row, and a sub-fit started on the wrong side of such a jump
        stays there (:func:`.intervals.gap_start`).
    """
    n_free = int(best.ndata - best.nvarys)
    crit = critical_value(n_free, sigma_given, level)
    s2 = 1.0 if sigma_given else max(best.chisqr / max(n_free, 1), s2_floor)
    return (_side(residual, best, name, -1.0, crit, s2, not sigma_given, realign),
            _side(residual, best, name, +1.0, crit, s2, not sigma_given, realign))


def one_side(residual, best, name: str, direction: float, *, sigma_given: bool,
             level: float = 0.90, s2_floor: float = 0.0, realign=None) -> ProfileLimit:
    """One profile limit at a two-sided ``level`` (0.90: a one-sided 95 % bound); ``s2_floor`` and
    ``realign`` as for :func:`profile_interval`."""
    n_free = int(best.ndata - best.nvarys)
    crit = critical_value(n_free, sigma_given, level)
    s2 = 1.0 if sigma_given else max(best.chisqr / max(n_free, 1), s2_floor)
    return _side(residual, best, name, direction, crit, s2, not sigma_given, realign)
