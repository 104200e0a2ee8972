"""Which membrane model a fit needs (docs/contracts.md A6 ``auto``), and what the approximation costs.

After a least-squares fit with the large-stretch membrane (fast), the exact neo-Hookean membrane is
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
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from ..errors import AdhfitError
from .lsq import COARSE_TOL, RawFit, minimise, residual_function
from .model import CurveModel, ModelDomainError

__all__ = ["Effect", "approximation_effect", "decide", "FORCE_THRESHOLD", "SHIFT_THRESHOLD", "EXACT_POINTS"]

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
    args = (si["work_of_adhesion"], si["mu_h"], si["x_offset"], si["force_offset"])
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
    start.update({k: 2 * si[k] - si2[k] for k in ("x_offset", "force_offset")})
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
               f"(σ = {e.sigma:.3g} N) and shifts W_ad by {100 * worst.shift['work_of_adhesion']:+.2g} % and μh by "
               f"{100 * worst.shift['mu_h']:+.2g} % ({_in_se(worst)})")
    resolved = any(x.resolved() for x in effects.values())
    if requested == "auto":
        membrane = "exact" if resolved else "large-stretch"
        rule = (f"the data resolve that (thresholds {FORCE_THRESHOLD:g} σ, {SHIFT_THRESHOLD:g} standard error)"
                if resolved else f"below what the data resolve ({FORCE_THRESHOLD:g} σ, {SHIFT_THRESHOLD:g} "
                f"standard error)")
        return {"membrane": membrane, "why": f"auto: {numbers}, {rule}."}
    verdict = "the data resolve that" if resolved else "below what the data resolve"
    return {"membrane": requested, "why": f"{requested} requested: {numbers}, {verdict}."}


def _in_se(e: Effect) -> str:
    parts = [f"{abs(e.shift[k]) / e.se[k]:.2g}" for k in ("work_of_adhesion", "mu_h") if e.se[k]]
    return f"{' and '.join(parts)} standard errors" if parts else "standard errors unknown"
