"""The membrane model of a fit (docs/contracts.md A6): which one the data need, and the exact refit.

**Which model.** After a least-squares fit with the large-stretch membrane (fast), the exact neo-Hookean membrane is
computed once at the fitted values, on the measured rows:

* **force error**: the largest |F_exact - F_large-stretch| over the rows, against the noise σ;
* **effect on the estimates**: the large-stretch model is refitted (from the same optimum) to the
  noise-free exact prediction; the shift of W_ad and μh is what the approximation does to the
  estimates at these values (an estimate of the bias, first order in the model error).

``auto`` switches to the exact membrane when the force error exceeds :data:`FORCE_THRESHOLD` σ at
some row, or when the estimated shift of W_ad or μh exceeds :data:`SHIFT_THRESHOLD` of its standard
error.  Why these numbers: a bias of half a standard error lowers the coverage of a 95 % interval to
about 92 %, a whole one to 83 %; and a systematic force error of half the noise at the rows where it
is largest is about the smallest that a few hundred rows show in χ² (Δχ² of a few units).

**The exact fit.** An exact history costs ~10²–10³ times a large-stretch one, so the exact fit does not search: every
slip condition is first fitted with the large-stretch membrane (starts, the free then fixed row
split), then :func:`approximation_effect` computes the exact force at that optimum
and the shift the approximation causes, and the exact fit starts from the large-stretch optimum
corrected by that shift — usually within a fraction of a standard error of the exact optimum, so a
few trust-region steps finish it.  It keeps the large-stretch fit's row split (the detachment row),
and reuses the last histories (the force offset needs no new history).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from ..errors import AdhfitError, ConvergenceError
from .lsq import COARSE_TOL, RawFit, minimise, residual_function
from .model import CurveModel, ModelDomainError
from .stand_in import minimise_exact
from .starts import Start, noise_estimate

__all__ = ["Effect", "approximation_effect", "decide", "FORCE_THRESHOLD", "SHIFT_THRESHOLD", "EXACT_POINTS",
           "choose_and_refit", "choose_members", "exact_refit", "refit", "wants_profile", "effect_warning",
           "membrane_evidence", "MEMBRANE_DBIC", "shift_text"]

#: largest force error, in units of the noise σ, that ``auto`` accepts from the approximation
FORCE_THRESHOLD = 0.5
#: largest estimated shift of W_ad or μh, in standard errors, that ``auto`` accepts
SHIFT_THRESHOLD = 0.5
#: rows per exact history: its interpolation error is ~1e-4 of the largest force (measured against
#: 400 rows at λ0 = 1.2), and the exact solver's cost hardly depends on the row count
EXACT_POINTS = 80


@dataclass(frozen=True)
class Effect:
    """The large-stretch approximation's error at one fit's optimum.

    Attributes
    ----------
    slip : str
    force_error : float
        Largest |F_exact - F_large-stretch| over the rows, N.
    sigma : float
        Force noise σ of the fit, N.
    shift : dict
        Relative shift of ``work_of_adhesion`` and ``mu_h`` that the approximation causes (the
        large-stretch estimate on exact-membrane data, minus the truth, over the truth).
    se : dict
        Relative standard errors of W_ad and μh of the large-stretch fit (None when unknown).
    start : dict
        The large-stretch optimum corrected by the shift (SI): a start for the exact fit.
    """

    slip: str
    force_error: float
    sigma: float
    shift: dict
    se: dict
    start: dict

    def resolved(self) -> bool:
        """True when the data resolve the approximation's error (see the module's thresholds)."""
        if self.force_error > FORCE_THRESHOLD * self.sigma:
            return True
        return any(self.se[k] is not None and abs(self.shift[k]) > SHIFT_THRESHOLD * self.se[k] for k in self.shift)


def _rel_se(raw: RawFit, name: str) -> float | None:
    p = raw.best.params[f"ln_{name}"]
    return float(p.stderr) if p.stderr is not None and np.isfinite(p.stderr) and p.stderr > 0 else None


def approximation_effect(raw: RawFit, sigma: float) -> Effect:
    """The approximation's force error and estimated effect on W_ad and μh at a large-stretch optimum.

    Parameters
    ----------
    raw : RawFit
        A large-stretch least-squares fit.
    sigma : float
        Its force noise σ, N.

    Raises
    ------
    ModelDomainError
        The exact membrane has no history at these values.
    """
    m, par = raw.model, raw.par
    si = par.si(raw.best.params)
    args = (si["work_of_adhesion"], si["mu_h"], si["x_offset"], si["force_offset"], si["force_drift"])
    exact = CurveModel(m.curve, m.scene, m.slip, points=EXACT_POINTS, segments=m.segments, membrane="exact")
    free = CurveModel(m.curve, m.scene, m.slip, points=m.points, segments=m.segments)
    try:
        f_ex = exact.predict(*args)
    except AdhfitError as err:
        raise ModelDomainError(f"no exact history: {err}", {"work_of_adhesion": args[0], "mu_h": args[1]}) from None
    err = float(np.max(np.abs(f_ex - free.predict(*args))))
    twin = CurveModel(replace(m.curve, force=f_ex), m.scene, m.slip, points=m.points, segments=m.segments)
    res = minimise(residual_function(twin, par, raw.scale, sigma), raw.best.params, scale_covar=False,
                   tol=COARSE_TOL)
    si2 = par.si(res.params)
    shift = {k: si2[k] / si[k] - 1.0 for k in ("work_of_adhesion", "mu_h")}
    start = {k: si[k] / (1.0 + shift[k]) for k in shift}
    start.update({k: 2 * si[k] - si2[k] for k in ("x_offset", "force_offset", "force_drift")})
    return Effect(slip=m.slip, force_error=err, sigma=float(sigma), shift=shift,
                  se={k: _rel_se(raw, k) for k in shift}, start=start)


def decide(effects: dict[str, Effect], lambda0: float, requested: str, outside: tuple = ()) -> dict:
    """The report's ``model`` entry: which membrane and why (one sentence with the numbers).

    Parameters
    ----------
    effects : dict slip -> Effect
        Empty when the exact membrane could not be computed at the fitted values.
    lambda0 : float
        The scene's pre-stretch.
    requested : {"auto", "large-stretch", "exact"}
    outside : tuple of str
        Slip conditions whose large-stretch optimum lies outside the exact membrane's domain (no Case I
        history there): the approximation is off by more than any data resolve.
    """
    if requested not in ("auto", "large-stretch", "exact"):  # another registry model: fitted as asked
        return {"membrane": requested, "why": f"{requested} requested (λ0 = {lambda0:g})."}
    if outside and requested != "exact":
        where = (f"at λ0 = {lambda0:g} the exact membrane has no history at the large-stretch optimum "
                 f"({', '.join(outside)}): the approximation is far off there, beyond what any data resolve")
        if requested == "auto":
            return {"membrane": "exact", "why": f"auto: {where}."}
        return {"membrane": "large-stretch", "why": f"large-stretch requested: {where}; --membrane exact "
                "fits the exact membrane."}
    if not effects:
        membrane = "exact" if requested == "exact" else "large-stretch"
        return {"membrane": membrane, "why": f"{requested} requested at λ0 = {lambda0:g}; the exact membrane "
                f"could not be computed at the large-stretch optimum, so its effect is unknown."}
    e = max(effects.values(), key=lambda x: x.force_error / x.sigma)
    worst = max(effects.values(), key=lambda x: max(abs(v) / (x.se[k] or math.inf) for k, v in x.shift.items()))
    numbers = (f"at λ0 = {lambda0:g} the large-stretch force is off by up to {e.force_error / e.sigma:.2g} σ "
               f"(σ = {e.sigma:.3g} N) and shifts W_ad by {shift_text(worst.shift['work_of_adhesion'])} and μh by "
               f"{shift_text(worst.shift['mu_h'])} ({_in_se(worst)})")
    resolved = any(x.resolved() for x in effects.values())
    if requested == "auto":
        membrane = "exact" if resolved else "large-stretch"
        rule = (f"the data resolve that (thresholds {FORCE_THRESHOLD:g} σ, {SHIFT_THRESHOLD:g} standard error)"
                if resolved else f"below what the data resolve ({FORCE_THRESHOLD:g} σ, {SHIFT_THRESHOLD:g} "
                f"standard error)")
        return {"membrane": membrane, "why": f"auto: {numbers}, {rule}."}
    verdict = "the data resolve that" if resolved else "below what the data resolve"
    return {"membrane": requested, "why": f"{requested} requested: {numbers}, {verdict}."}


#: a relative shift beyond this is past what the first-order estimate (one refit) can tell
SHIFT_TEXT_MAX = 0.5


def shift_text(x: float) -> str:
    """A relative shift in words: ``+1.2 %``; beyond ±50 % (a refit far from its start, e.g. of a W_ad the
    data bound from one side only) the first-order number means nothing and is not printed."""
    if not math.isfinite(x) or abs(x) > SHIFT_TEXT_MAX:
        return f"more than {100 * SHIFT_TEXT_MAX:.0f} % (beyond a first-order estimate)"
    return f"{100 * x:+.2g} %"


def _in_se(e: Effect) -> str:
    parts = [f"{abs(e.shift[k]) / e.se[k]:.2g}" for k in ("work_of_adhesion", "mu_h") if e.se[k]]
    return f"{' and '.join(parts)} standard errors" if parts else "standard errors unknown"


#: trust-region evaluations allowed to an exact refinement (each new parameter set is one history)
MAX_NFEV = 60
#: optimiser tolerance (scipy ftol = xtol = gtol) of the exact refinement: 1e-5 of ln W_ad, ln μh is
#: ~1e-2 of their standard errors at 0.5 % noise, and 1e-5 of χ² is ~1e-3 on a few hundred rows, far
#: below what the slip comparison (ΔBIC of units) needs; FINE_TOL (1e-8) cost ~4x the histories
EXACT_TOL = 1e-5
#: standard error of ln W_ad or ln μh above which an exact fit's covariance interval is not trusted
#: (the log-normal interval is then far from the likelihood's shape): profile instead
MAX_COVARIANCE_SE = 0.2
#: factors on W_ad and μh together (W_ad/μh kept) tried in turn, when the exact membrane has no history at
#: the large-stretch optimum, for the first start where it has one: at small λ0 the approximation
#: underestimates μh (by 33 % at λ0 = 1.1 on an F–P curve to P b/2μh = 0.75), and the dimensionless
#: pressure of its optimum, P b/2μh, lies beyond what the exact membrane reaches in Case I
DOMAIN_STEPS = (1.25, 1.6, 2.0, 2.5, 3.2, 4.0)
#: rounds of refits at the pull-off row the exact model puts at the last optimum and its neighbours
#: (``_follow_split``)
SPLIT_ROUNDS = 4


def exact_refit(raw: RawFit, effect: Effect | None, membrane: str = "exact") -> RawFit:
    """The exact-membrane (or another registry model's) least-squares fit of one slip condition, started
    from ``raw`` (large-stretch).

    Parameters
    ----------
    raw : RawFit
        The large-stretch fit of this slip condition.
    effect : Effect, optional
        Its approximation effect; its corrected start is used when given.
    membrane : str
        The model to fit (:data:`adhfit.membranes.MEMBRANES`).
    """
    m, par = raw.model, raw.par
    exact = CurveModel(m.curve, m.scene, m.slip, points=EXACT_POINTS, segments=m.segments,
                       fixed_split=m.fixed_split, membrane=membrane)
    exact.n_histories, exact.n_evaluations = m.n_histories, m.n_evaluations
    sigma_est = raw.scale if raw.sigma_given else (noise_estimate(m.force) or 1e-3 * par.f_scale)
    residual = residual_function(exact, par, raw.scale, sigma_est)
    si = par.si(raw.best.params)
    starts = [Start(effect.start)] if effect is not None else []
    if effect is None and not _computable(exact, si):
        stiffer = _domain_start(exact, si)
        starts += [Start(stiffer)] if stiffer is not None else []
    starts.append(Start(si))
    best, tried = None, []
    stderr = _stderr(raw)
    polish = not exact.fixed_split  # a fixed split is followed first (_follow_split), then polished once
    for s in starts:
        res, at = minimise_exact(exact, par, raw.scale, sigma_est, par.params(s), scale_covar=not raw.sigma_given,
                                 stderr=stderr, max_nfev=MAX_NFEV, tol=EXACT_TOL, polish=polish)
        tried.append({**{k: float(v) for k, v in s.items()}, "chisqr": float(res.chisqr), "membrane": "exact"})
        if best is None or res.chisqr < best.chisqr:
            best = res
        if best.covar is not None and best.success:
            break  # the corrected start converged: the plain one would cost as much again
    if not _computable(exact, par.si(best.params)):  # every step was outside the exact model's domain
        raise ConvergenceError(
            f"the exact-membrane fit ({m.slip}, λ0 = {m.scene.prestretch:g}) from the large-stretch optimum "
            f"(W_ad = {si['work_of_adhesion']:.4g} J/m^2, μh = {si['mu_h']:.4g} N/m)",
            {"hint": "no exact history there (Case I only: the membrane must not turn past vertical at the "
                     "clamp); --membrane large-stretch fits the approximation"})
    if exact.fixed_split:
        exact, best = _follow_split(exact, best, residual_args=(par, raw.scale, sigma_est), sigma_given=raw.sigma_given,
                                    tried=tried, stderr=stderr, at=at)
        if at is not None:  # the stand-in's optimum, polished on the exact model itself
            best = minimise(residual, best.params, scale_covar=not raw.sigma_given, max_nfev=MAX_NFEV, tol=EXACT_TOL)
    return RawFit(slip=raw.slip, best=best, model=exact, par=par, scale=raw.scale, sigma_given=raw.sigma_given,
                  starts=list(raw.starts) + tried, alternatives=_alternatives(raw, par.si(best.params)))


def _follow_split(exact: CurveModel, best, *, residual_args: tuple, sigma_given: bool, tried: list, stderr: dict,
                  at: dict | None = None):
    """Refit at the detachment row the exact model itself puts pull-off at, while that differs from the
    row kept from the large-stretch fit, and then at the rows either side too, keeping the least χ² (the
    pull-off term included), for at most :data:`SPLIT_ROUNDS` rounds. Where the approximation is far off
    (λ0 = 1.1) its pull-off row was 4 rows early: the exact fit held to it stopped at χ² 6x the truth's
    (W_ad 9 % low); following the exact row alone settled one row early (W_ad 2.6 % low at 1 % noise)."""
    par = residual_args[0]
    free = CurveModel(exact.curve, exact.scene, exact.slip, points=exact.points, segments=exact.segments,
                      membrane=exact.membrane)
    seen, moved = {exact.segments.i_jump}, False
    for _ in range(SPLIT_ROUNDS):
        si, cur = par.si(best.params), exact.segments.i_jump
        try:
            j = free.split(si["work_of_adhesion"], si["mu_h"], si["x_offset"])
        except ModelDomainError:
            break
        rows = [j] if j is not None and j != cur else []
        if rows or moved:  # the large-stretch row was wrong: the exact χ² weighs the neighbours too
            rows += [cur - 1, cur + 1]
        rows = [k for k in dict.fromkeys(rows) if k not in seen and exact.segments.i_turn + 1 < k < exact.x.size]
        if not rows:
            break
        seen.update(rows)
        fits = [_split_fit(exact, k, best, residual_args, sigma_given, tried, stderr, at) for k in rows]
        model, res = min(fits, key=lambda mf: mf[1].chisqr)
        if not res.chisqr < best.chisqr:
            break
        exact, best, moved = model, res, True
    return exact, best


def _split_fit(exact: CurveModel, j: int, best, residual_args: tuple, sigma_given: bool, tried: list, stderr: dict,
               at: dict | None):
    """The exact fit with the detachment fixed before row ``j``, from ``best``'s parameters."""
    par = residual_args[0]
    model = exact.split_before(j)
    res, _ = minimise_exact(model, *residual_args, best.params, scale_covar=not sigma_given, stderr=stderr,
                            max_nfev=MAX_NFEV, tol=EXACT_TOL, at=at, polish=at is None,
                            rounds=1)  # only compared here; the winner is polished on the exact model
    tried.append({**{k: float(v) for k, v in par.si(res.params).items()}, "chisqr": float(res.chisqr),
                  "membrane": "exact", "split": j})
    return model, res


def _alternatives(raw: RawFit, exact_si: dict) -> tuple:
    """The large-stretch fit's optima with pull-off one row earlier/later, carried over to the exact fit
    as relative shifts (the Δχ² between rows is set by the data's rows near the jump, not by the
    membrane model; refitting them exactly would cost two more exact fits)."""
    ls = raw.par.si(raw.best.params)
    return tuple(dict(alt, **{k: exact_si[k] * alt[k] / ls[k] for k in ("work_of_adhesion", "mu_h")})
                 for alt in raw.alternatives)


def _stderr(raw: RawFit) -> dict:
    """Internal name -> standard error of the large-stretch fit (None where it has none)."""
    return {n: p.stderr for n, p in raw.best.params.items()}


def _domain_start(model: CurveModel, si: dict) -> dict | None:
    """The first of W_ad and μh scaled by :data:`DOMAIN_STEPS` (offsets kept) at which ``model`` (exact)
    has a history; None if none has."""
    for k in DOMAIN_STEPS:
        s = dict(si, work_of_adhesion=si["work_of_adhesion"] * k, mu_h=si["mu_h"] * k)
        if _computable(model, s):
            return s
    return None


def _computable(model: CurveModel, s: dict) -> bool:
    try:
        model.pieces(s["work_of_adhesion"], s["mu_h"], s["x_offset"])
    except ModelDomainError:
        return False
    return True


def _sigma(raw: RawFit) -> float:
    return raw.scale if raw.sigma_given else raw.scale * float(raw.best.redchi) ** 0.5


def choose_and_refit(raws: dict[str, RawFit], scene, membrane: str) -> tuple[dict[str, RawFit], dict, dict]:
    """Decide the membrane model and, for the exact one, refit every slip condition with it.

    Parameters
    ----------
    raws : dict slip -> RawFit
        The large-stretch fits.
    scene : adhfit.scene.Scene
    membrane : {"auto", "large-stretch", "exact"}

    Returns
    -------
    (raws, model, effects)
        The fits to report (exact or the given ones), the report's ``model`` entry, and the
        :class:`~.membrane.Effect` per slip condition (empty when the exact membrane failed).
    """
    effects, outside = {}, []
    for s, raw in raws.items():
        try:
            effects[s] = approximation_effect(raw, _sigma(raw))
        except ModelDomainError:
            outside.append(s)
        except (AdhfitError, ValueError):
            continue
    model = decide(effects, scene.prestretch, membrane, tuple(outside))
    if model["membrane"] == "large-stretch":
        return raws, model, effects
    out = {s: refit(raw, effects.get(s), model["membrane"]) for s, raw in raws.items()}
    return out, model, effects


def refit(raw: RawFit, effect: Effect | None, membrane: str) -> RawFit:
    """The fit of one slip condition with ``membrane`` (a registry entry), refined from the large-stretch
    fit ``raw``: the exact membrane from the start its approximation effect predicts, another model from
    the large-stretch optimum."""
    return exact_refit(raw, effect if membrane == "exact" else None, membrane=membrane)


def effect_warning(effects: dict[str, Effect], slip: str, lambda0: float) -> str | None:
    """The warning a large-stretch fit adds when the data resolve the approximation's error: its estimated
    effect at the user's λ0 (``None`` otherwise; the ``model`` entry always gives the numbers)."""
    e = effects.get(slip)
    if e is None or not e.resolved():  # below what the data resolve: report.json ``model`` says so
        return None
    return (f"The large-stretch approximation (paper eq. 10) at λ0 = {lambda0:g}: fitting it to the exact "
            f"membrane's curve at these values shifts W_ad by {shift_text(e.shift['work_of_adhesion'])} and μh by "
            f"{shift_text(e.shift['mu_h'])} (largest force error {e.force_error / e.sigma:.2g} σ); "
            f"use --membrane exact to remove it.")


def choose_members(raws: dict[str, list[RawFit]], scenes: list, membrane: str) -> tuple[dict, dict, list]:
    """:func:`choose_and_refit` for every curve of an objective: one membrane model for all of them.

    Each curve is decided on its own (its large-stretch fits, its λ0); when one needs the exact membrane,
    every curve is refitted with it (one model for the shared W_ad and μh).

    Returns
    -------
    (raws, model, effects)
        Per slip condition the fits to use (one per curve), the report's ``model`` entry, and each
        curve's :class:`~.membrane.Effect` per slip condition.
    """
    slips = list(raws)
    n = len(scenes)
    per = [choose_and_refit({s: raws[s][i] for s in slips}, scenes[i], membrane) for i in range(n)]
    exact = [k for k, (_, info, _) in enumerate(per) if info["membrane"] != "large-stretch"]
    chosen = per[exact[0]][1]["membrane"] if exact else "large-stretch"
    out = {s: [] for s in slips}
    for i, (fits, info, effects) in enumerate(per):
        if exact and info["membrane"] != chosen:
            fits = {s: refit(raws[s][i], effects.get(s), chosen) for s in slips}
        for s in slips:
            out[s].append(fits[s])
    info = dict(per[exact[0] if exact else 0][1])
    if n > 1:
        which = exact[0] if exact else 0
        info["why"] = (f"one membrane model for the {n} curves; curve {which + 1} ({scenes[which].source or 'scene'}): "
                       + info["why"])
        if exact:
            info["membrane"] = chosen
    return out, info, [p[2] for p in per]


def wants_profile(fit, model: dict) -> bool:
    """Whether the reported fit (an :class:`~.objective.ObjectiveFit`) needs likelihood profiles: always
    with the large-stretch membrane (cheap); with the exact one when the covariance is missing or wide
    (standard error of ln W_ad or ln μh above :data:`MAX_COVARIANCE_SE`), when the data end before
    pull-off (W_ad is then bounded from one side) or when the optimum sits on the kink at the turning
    point (docs/numerics.md B4)."""
    from .intervals import no_pull_off  # noqa: PLC0415
    if model["membrane"] == "large-stretch" or fit.best.covar is None:
        return True
    for name in ("ln_work_of_adhesion", "ln_mu_h"):  # a wide or missing covariance interval is not trusted
        se = fit.best.params[name].stderr
        if se is None or not math.isfinite(se) or se > MAX_COVARIANCE_SE:
            return True
    shared, offs = fit.si()
    try:
        return no_pull_off(fit) or any(
            m.model.near_turning_point(shared["work_of_adhesion"], shared["mu_h"], off["x_offset"])
            for m, off in zip(fit.members, offs))
    except ModelDomainError:
        return True


#: |ΔBIC| between the two membrane models below which the data cannot tell them apart (the slip
#: verdict's "strong evidence" threshold): the intervals then cover both models' intervals
MEMBRANE_DBIC = 6.0


def membrane_evidence(large: dict, exact: dict) -> float:
    """ΔBIC = BIC(large-stretch) − BIC(exact) of each model's best slip condition (positive: the data
    prefer the exact membrane); both are dicts slip -> :class:`~.objective.ObjectiveFit`.  Both models
    have the same parameters, so ΔBIC is the difference of -2 ln L with every noise level profiled out."""
    return float(min(f.criteria()[1] for f in large.values()) - min(f.criteria()[1] for f in exact.values()))
