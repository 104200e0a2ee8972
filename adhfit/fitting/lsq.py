"""Least-squares fit of one slip condition with lmfit (``least_squares``, trust-region reflective).

Fitted parameters (rows of :data:`adhfit.params.FITTED`): ``work_of_adhesion`` and ``mu_h``, plus the
nuisance ``displacement_offset`` (on by default under displacement control) or ``pressure_offset``
(off by default) and ``force_offset`` (the load-cell zero, on by default: the rows before contact
and after pull-off pin it).

* **Two stages**: the free-split model (:class:`~.model.CurveModel`) finds the detachment row by
  likelihood; then the split is fixed at that row and its neighbours, each refitted with the
  pull-off position term, and the lowest χ² wins (:func:`_refit_fixed`).

* **Parametrisation**: the optimiser sees ln W_ad, ln μh, the offset over the data's control range
  and the force offset over the largest force, so every internal parameter is O(1) and its
  finite-difference step (relative 1e-6) is meaningful; results are reported in SI.
* **Residual**: (F_measured - F_model) / s over every row (plus the pull-off position term of
  :func:`residual_function`), with s = σ when σ is given (covariance
  not rescaled) and s = the largest force otherwise; then lmfit scales the covariance by the
  reduced χ² (``scale_covar=True``), i.e. σ is estimated from the residuals.
* **Starts** (B4): the data-based start of :mod:`.starts`, then a few perturbed starts (W_ad × 1/2
  and × 2, μh × 0.8 and × 1.25, the offset ± 5 % of the control range); every start is scored by one
  evaluation and the best two (plus any caller-given start) are minimised — the first to full
  precision, the others coarsely and refined only if they beat it; the lowest χ² wins.  Outside the model's domain the residual is a large constant, which the
  trust-region method backs away from.
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import lmfit
import numpy as np
from scipy import special

from ..params import FITTED
from .model import OFFSET_NAME, CurveModel, ModelDomainError
from .starts import Start, data_start, hinge_contact, noise_estimate

__all__ = ["Parametrisation", "RawFit", "fit_slip", "residual_function", "minimise", "pull_off_term"]

#: relative finite-difference step of the Jacobian (the history's solver noise is ~1e-12)
DIFF_STEP = 1e-6
#: optimiser tolerances (scipy ftol = xtol = gtol) at an optimum, and for a start's first descent
FINE_TOL = 1e-8
COARSE_TOL = 1e-5
#: W_ad/μh range of the model (adhfit.params.DIMENSIONLESS["w"])
W_RANGE = (1e-6, 10.0)
#: residual of a parameter set outside the model's domain, per row, in units of s
PENALTY = 1e3


@dataclass(frozen=True)
class Parametrisation:
    """Internal (optimiser) <-> SI parameters.

    Attributes
    ----------
    x_scale : float
        Range of the measured control values (m or Pa); the offset is fitted over it.
    f_scale : float
        Largest measured force, N; the force offset is fitted over it.
    control : str
    fit_x_offset, fit_force_offset : bool
    fit_force_drift : bool
        Fit a linear drift of the load-cell zero over the rows (the force offset is then the zero at
        the first row), over the largest force.
    """

    x_scale: float
    f_scale: float
    control: str
    fit_x_offset: bool
    fit_force_offset: bool
    fit_force_drift: bool = False

    @property
    def names(self) -> list[str]:
        """SI names of the fitted parameters, in order."""
        out = ["work_of_adhesion", "mu_h"]
        if self.fit_x_offset:
            out.append(OFFSET_NAME[self.control])
        if self.fit_force_offset:
            out.append("force_offset")
        if self.fit_force_drift:
            out.append("force_drift")
        return out

    def params(self, start: Start) -> lmfit.Parameters:
        """lmfit Parameters at ``start`` with the bounds of the parameter table (SI -> internal)."""
        p = lmfit.Parameters()
        # box bounds inside the model's domain (w = W_ad/μh in [1e-6, 10]) around the start's μh, with a
        # margin: a flat W_ad (a test stopped before delamination) must not send the optimiser far away
        mu0 = float(start["mu_h"])
        box = {"work_of_adhesion": (math.log(W_RANGE[0] * mu0) - 1.5, math.log(W_RANGE[1] * mu0) + 1.5),
               "mu_h": (math.log(mu0) - 7.0, math.log(mu0) + 7.0)}
        for name in ("work_of_adhesion", "mu_h"):
            row = FITTED[name]
            lo = max(math.log(row.lower) if row.lower > 0 else -np.inf, box[name][0])
            hi = min(math.log(row.upper) if math.isfinite(row.upper) else np.inf, box[name][1])
            value = float(np.clip(math.log(start[name]), lo + 1e-9, hi - 1e-9))
            p.add(f"ln_{name}", value=value, min=lo, max=hi)
        if self.fit_x_offset:
            row = FITTED[OFFSET_NAME[self.control]]
            p.add("x_offset", value=start["x_offset"] / self.x_scale, min=row.lower / self.x_scale,
                  max=row.upper / self.x_scale)
        if self.fit_force_offset:
            row = FITTED["force_offset"]
            p.add("force_offset", value=start["force_offset"] / self.f_scale,
                  min=row.lower / self.f_scale, max=row.upper / self.f_scale)
        if self.fit_force_drift:
            p.add("force_drift", value=start.get("force_drift", 0.0) / self.f_scale)
        return p

    def si(self, values: dict) -> dict:
        """Internal values (a dict or lmfit Parameters) -> SI dict with all five model arguments."""
        v = {k: float(getattr(values[k], "value", values[k])) for k in values}
        return {"work_of_adhesion": math.exp(min(v["ln_work_of_adhesion"], 700.0)),
                "mu_h": math.exp(min(v["ln_mu_h"], 700.0)),
                "x_offset": v.get("x_offset", 0.0) * self.x_scale,
                "force_offset": v.get("force_offset", 0.0) * self.f_scale,
                "force_drift": v.get("force_drift", 0.0) * self.f_scale}


def pull_off_term(gap: tuple[float, float, float], x_tp: float) -> float:
    """sqrt(-2 ln P): P the probability that the model's turning point ``x_tp`` lies in the pull-off gap.

    The data place the pull-off anywhere between the last attached row and the first detached row
    (``gap`` = (x_attached, x_detached, soft), :attr:`~.model.CurveModel.jump`), so the likelihood of the
    jump is censored, not Gaussian: P = Φ((hi - x_tp)/s) - Φ((lo - x_tp)/s), nearly flat inside the gap
    and rising outside (the residual grows as the distance in units of s).
    A Gaussian term about the gap's midpoint (σ = spacing/√12) pulled the turning point to the middle
    of the row gap, so W_ad and the slip ΔBIC moved with where the rows happened to fall.
    """
    lo, hi = sorted(gap[:2])
    s = gap[2]
    a, b = (lo - x_tp) / s, (hi - x_tp) / s
    if b <= 0.0:  # x_tp above the gap
        lb, la = special.log_ndtr(b), special.log_ndtr(a)
        log_p = lb + math.log1p(-math.exp(min(la - lb, 0.0))) if la < lb else -np.inf
    elif a >= 0.0:  # below it
        la, lb = special.log_ndtr(-a), special.log_ndtr(-b)
        log_p = la + math.log1p(-math.exp(min(lb - la, 0.0))) if lb < la else -np.inf
    else:
        log_p = math.log1p(-(special.ndtr(a) + special.ndtr(-b)))
    return math.sqrt(max(-2.0 * log_p, 0.0)) if math.isfinite(log_p) else math.sqrt(PENALTY)


def residual_function(model: CurveModel, par: Parametrisation, scale: float, sigma: float | None = None):
    """The residual vector for lmfit (params -> array).

    (F_measured - F_model)/scale at every row.  With a free split the model itself decides which
    unloading rows are detached (:meth:`CurveModel.attached_weight`).  With a fixed split that shows
    the pull-off, one more term: :func:`pull_off_term` (the turning point must lie in the gap between
    the last attached and the first detached row) in units of the force noise σ (given, or the robust
    estimate), so that ``σ/scale`` of it enters a residual in units of ``scale``.
    """
    force = model.force
    jump = model.jump
    n = force.size + (jump is not None)
    if sigma is None:
        sigma = noise_estimate(force) or 1e-3 * float(np.max(np.abs(force)) or 1.0)

    def residual(params):
        si = par.si(params.valuesdict())
        w, mu, off = si["work_of_adhesion"], si["mu_h"], si["x_offset"]
        try:
            pred = model.predict(w, mu, off, si["force_offset"], si["force_drift"])
            r = (force - pred) / scale
            if jump is None:
                return r
            x_tp = model.turning_point(w, mu, off)[0]
        except ModelDomainError:
            return np.full(n, PENALTY)
        return np.append(r, pull_off_term(jump, x_tp) * sigma / scale)
    return residual


def minimise(residual, params: lmfit.Parameters, *, scale_covar: bool, max_nfev: int = 400,
             tol: float = FINE_TOL):
    """One lmfit ``least_squares`` run (TRF, 2-point Jacobian with step :data:`DIFF_STEP`).

    ``tol`` is scipy's ftol = xtol = gtol: :data:`FINE_TOL` for optima; the profile's sub-fits need only the
    χ² to ~1e-4 relative (a few hundredths of σ² on ~10² rows).
    """
    mini = lmfit.Minimizer(residual, params, scale_covar=scale_covar)
    with np.errstate(invalid="ignore"):  # a flat direction: lmfit's sqrt of a negative variance -> no stderr
        return mini.minimize(method="least_squares", max_nfev=max_nfev, diff_step=DIFF_STEP,
                             x_scale="jac", ftol=tol, xtol=tol, gtol=tol)


@dataclass(frozen=True)
class RawFit:
    """What :func:`fit_slip` found: the best lmfit result, its model and parametrisation, the starts.

    Attributes
    ----------
    slip : str
    best : lmfit.minimizer.MinimizerResult
    model : CurveModel
    par : Parametrisation
    scale : float
        Residual scale s (σ when given, else the largest force), N.
    sigma_given : bool
    starts : list of dict
        Each start (SI) with the χ² it reached.
    alternatives : tuple of dict
        The optima (SI) with the pull-off at a neighbouring row, and their χ² above the best
        (``dchisqr``, residual units): the ones the data cannot reject widen the intervals.
    won : str
        Which start (or row split) the optimum came from (for the diagnostics).
    free : tuple of (str, float)
        The free-split stage's optimum (before the row split was fixed): internal parameter names and values.
    """

    slip: str
    best: object
    model: CurveModel
    par: Parametrisation
    scale: float
    sigma_given: bool
    starts: list
    alternatives: tuple = ()
    won: str = ""
    free: tuple = ()


def _perturbed(start: Start, par: Parametrisation) -> list[tuple[Start, str]]:
    out = [(start, "data-based start")]
    for fw, fm in ((0.5, 1.0), (2.0, 1.0), (1.0, 0.8), (1.0, 1.25), (0.5, 0.8), (2.0, 1.25)):
        out.append((Start(start, work_of_adhesion=start["work_of_adhesion"] * fw, mu_h=start["mu_h"] * fm),
                    f"data-based start, W_ad x{fw:g}, μh x{fm:g}"))
    if par.fit_x_offset:
        for dx in (-0.05, 0.05):
            out.append((Start(start, x_offset=start["x_offset"] + dx * par.x_scale),
                        f"data-based start, offset {dx:+.0%} of the control range"))
    return out


def _run_starts(residual, par, runs, *, scale_covar, labels=None, optima: list | None = None):
    """Minimise from every start: the first to full precision, the others coarsely (tolerance
    :data:`COARSE_TOL`), refining one only if it beats the best so far — a start that ends in another
    basin shows it long before full convergence.  Returns (best, starts, label of the winning start);
    ``optima``, when given, receives every start's result."""
    best, starts, won = None, [], ""
    labels = labels or [f"start {i}" for i in range(len(runs))]
    for i, (s, label) in enumerate(zip(runs, labels)):
        res = minimise(residual, par.params(s), scale_covar=scale_covar, tol=FINE_TOL if i == 0 else COARSE_TOL)
        if i > 0 and res.chisqr < best.chisqr * (1.0 - 1e-6):
            res = minimise(residual, res.params, scale_covar=scale_covar, tol=FINE_TOL)
        if optima is not None:
            optima.append(res)
        starts.append({**{k: float(v) for k, v in s.items()}, "chisqr": float(res.chisqr), "start": label})
        if best is None or res.chisqr < best.chisqr:
            best, won = res, label
    if best.aborted or best.covar is None:
        # the optimiser can keep chasing ~1e-9 gains across the kink at the turning point until
        # max_nfev; a short coarse run from its best point ends cleanly and yields the covariance
        polish = minimise(residual, best.params, scale_covar=scale_covar, tol=COARSE_TOL, max_nfev=150)
        if polish.covar is not None and polish.chisqr <= best.chisqr * (1.0 + 1e-6):
            best = polish
    return best, starts, won


#: other starts' free-split optima within this factor of the best χ² lend their row splits to the fixed stage
CLOSE_OPTIMA = 1.5

#: rows at zero force needed at each end (before contact, after the detected jump) to fit a drift of the zero
DRIFT_ROWS = 5


def drift_supported(model: CurveModel) -> bool:
    """Whether the rows pin a linear drift of the load-cell zero: at least :data:`DRIFT_ROWS` rows before
    the contact point (the hinge fit of :mod:`.starts`) and after the detected jump."""
    seg = model.segments
    if seg.i_jump is None or model.x.size - seg.i_jump < DRIFT_ROWS:
        return False
    x_c = hinge_contact(model.x, model.force, seg.i_turn)[0]
    return int(np.count_nonzero(model.x[: seg.i_turn + 1] < x_c)) >= DRIFT_ROWS


def fit_slip(model: CurveModel, *, sigma: float | None = None, fit_x_offset: bool | None = None,
             fit_force_offset: bool = True, fit_force_drift: bool | None = None, extra_starts: list[dict] = (),
             n_runs: int = 2, known: RawFit | None = None) -> RawFit:
    """Fit W_ad, μh (and offsets) of one slip condition by least squares.

    Parameters
    ----------
    model : CurveModel
        The measured curve's model for this slip condition.
    sigma : float, optional
        Force noise σ (N); estimated from the residuals when not given.
    fit_x_offset : bool, optional
        Fit the control-variable offset; default: yes under displacement control, no under pressure
        control.
    fit_force_offset : bool
        Fit a load-cell offset.
    fit_force_drift : bool, optional
        Fit a linear drift of the load-cell zero over the test; default: with the offset, where the rows
        pin it (:func:`drift_supported`).
    extra_starts : list of dict
        More starts in SI (e.g. the other slip condition's optimum); always minimised.
    n_runs : int
        How many of the scored data-based starts are minimised.
    known : RawFit, optional
        An earlier fit of the same model (this is a restart from another start): when the free-split
        stage lands where ``known``'s did (every internal parameter within :data:`SAME_OPTIMUM`), the
        fixed stage would repeat ``known``'s from the same points, and ``known`` is returned.

    Returns
    -------
    RawFit
    """
    control = model.control
    fit_x_offset = (control == "displacement") if fit_x_offset is None else bool(fit_x_offset)
    x_scale = float(np.ptp(model.x)) or 1.0
    f_scale = float(np.max(np.abs(model.force))) or 1.0
    if fit_force_drift is None:
        fit_force_drift = fit_force_offset and drift_supported(model)
    par = Parametrisation(x_scale, f_scale, control, fit_x_offset, fit_force_offset, bool(fit_force_drift))
    scale = float(sigma) if sigma is not None else f_scale
    sigma_est = float(sigma) if sigma is not None else (noise_estimate(model.force) or 1e-3 * f_scale)
    residual = residual_function(model, par, scale, sigma_est)
    base = data_start(model, fit_offset=fit_x_offset, fit_force_offset=fit_force_offset)
    scored = []
    for s, label in _perturbed(base, par) if n_runs > 0 else ():
        r = residual(par.params(s))
        scored.append((float(r @ r), s, label))
    scored.sort(key=lambda t: t[0])
    runs = [s for _, s, _ in scored[:n_runs]] + [Start(base, **e) for e in extra_starts]
    labels = [lb for _, _, lb in scored[:n_runs]] + [e.get("label", "given start") if isinstance(e, dict) else
                                                    "given start" for e in extra_starts]
    runs = [Start({k: v for k, v in r.items() if k != "label"}) for r in runs]
    optima: list = []
    best, starts, won = _run_starts(residual, par, runs, scale_covar=sigma is None, labels=labels, optima=optima)
    others = [par.si(r.params) for r in optima if r is not best and r.chisqr <= CLOSE_OPTIMA * best.chisqr]
    if known is not None and not model.fixed_split and not others and _same_optimum(best, known):
        return known
    raw = RawFit(slip=model.slip, best=best, model=model, par=par, scale=scale, sigma_given=sigma is not None,
                 starts=starts, won=won, free=tuple((k, float(p.value)) for k, p in best.params.items()))
    if model.fixed_split:
        return raw
    # the row split of every start's optimum close to the best: the free split's χ² and the fixed split's
    # (with the pull-off term) need not rank two basins alike (a fit started from the other slip condition's
    # optimum detached 2 rows early, χ² 211 against 194 at the data's row)
    return _refit_fixed(raw, sigma, sigma_est, base, others)


#: a restart's free-split optimum within this of an earlier one in every internal parameter (O(1) units) is the same
SAME_OPTIMUM = 1e-3


def _same_optimum(best, known: RawFit) -> bool:
    """Whether the free-split optimum ``best`` is where ``known``'s free stage ended (its fixed stage,
    started from the same point, would only repeat ``known``'s)."""
    there = dict(known.free)
    return there.keys() == best.params.keys() and all(abs(p.value - there[k]) < SAME_OPTIMUM
                                                      for k, p in best.params.items())


def _refit_fixed(raw: RawFit, sigma: float | None, sigma_est: float, base: Start, others: list = ()) -> RawFit:
    """Second stage: fix the row split the free-split fit found and refit with the pull-off term.

    The free split finds the detachment row by likelihood (no threshold); but with it the pull-off
    position would be known to a fraction of a row (the ramp is steep when the jump is large against
    the noise), while the data only place it somewhere between two rows.  The fixed split with the
    pull-off term (σ_jump = spacing/√12) gives it its honest uncertainty.  Without a detached row
    (the data end before the model's pull-off) the free-split fit is kept: there the rows must all
    stay attached, which is what bounds W_ad from below.
    """
    m, par = raw.model, raw.par
    si = par.si(raw.best.params)
    try:
        j = m.split(si["work_of_adhesion"], si["mu_h"], si["x_offset"])
    except ModelDomainError:
        return raw
    ok = [k for k in (j, j - 1, j + 1) if k is not None and m.segments.i_turn + 1 < k < m.x.size] \
        if j is not None and j < m.x.size - 1 else []
    # a restart a wrong local optimum cannot survive: the row the jump detector finds, and its neighbours
    # (an optimum stuck with the model detaching rows early had a 1.5-12x higher χ² than the truth)
    d = m.segments.i_jump
    seen = set(ok)
    detected = [k for k in (d, d - 1, d + 1) if k not in seen and m.segments.i_turn + 1 < k < m.x.size] \
        if d is not None else []
    seen.update(detected)
    near = []  # (row, start) from the other starts' optima
    for o in others:
        try:
            jo = m.split(o["work_of_adhesion"], o["mu_h"], o["x_offset"])
        except ModelDomainError:
            continue
        for k in (jo, jo - 1, jo + 1) if jo is not None else ():
            if k not in seen and m.segments.i_turn + 1 < k < m.x.size:
                seen.add(k)
                near.append((k, o))
    if not ok and not detected and not near:
        return raw
    # every candidate split coarsely (a split in another basin shows it long before full convergence), the
    # least χ² then to full precision; each starts where its free split ended, sharing its histories
    fits = [_fixed_fit(raw, k, sigma, sigma_est, base, si, "row split of the free-split optimum") for k in ok]
    fits += [_fixed_fit(raw, k, sigma, sigma_est, base, si, "row split at the detected jump") for k in detected]
    fits += [_fixed_fit(raw, k, sigma, sigma_est, base, o, "row split of another start's optimum") for k, o in near]
    best = min(fits, key=lambda f: f.best.chisqr)
    refined = minimise(residual_function(best.model, par, raw.scale, sigma_est), best.best.params,
                       scale_covar=sigma is None, tol=FINE_TOL)
    if refined.chisqr <= best.best.chisqr:
        fits[fits.index(best)] = best = dataclasses.replace(best, best=refined)
    if not ok and best.best.chisqr >= raw.best.chisqr:  # the free fit (no pull-off in the data) stands
        return raw
    near = [f for f in fits if f is not best and abs(f.model.segments.i_jump - best.model.segments.i_jump) == 1]
    alts = tuple(dict(f.par.si(f.best.params), dchisqr=float(f.best.chisqr - best.best.chisqr),
                      split=f.model.segments.i_jump) for f in near)
    return dataclasses.replace(best, alternatives=alts, free=raw.free)


def _fixed_fit(raw: RawFit, j: int, sigma: float | None, sigma_est: float, base: Start, si: dict,
               why: str) -> RawFit:
    """The fit with the detachment fixed before row ``j`` (pull-off term included)."""
    m, par, f = raw.model, raw.par, raw.model.force
    fixed = m.split_before(j)  # its histories shared; the cost of stage 1 counted too
    residual = residual_function(fixed, par, raw.scale, sigma_est)
    label = f"{raw.won}; {why} (before row {j})"
    start = Start(base, **si)
    res = minimise(residual, par.params(start), scale_covar=sigma is None, tol=COARSE_TOL)
    starts = [{**{k: float(v) for k, v in start.items()}, "chisqr": float(res.chisqr), "start": label}]
    return RawFit(slip=m.slip, best=res, model=fixed, par=par, scale=raw.scale,
                  sigma_given=raw.sigma_given, starts=raw.starts + starts, won=label)
