"""Least squares of an objective with several blocks (several curves, or a curve and its contact radius).

Per slip condition, after each member's own fit (:func:`~.lsq.fit_slip`: its start values, its row split
found by likelihood):

1. **the joint fit** from the inverse-variance mean of the members' own W_ad and μh and from each
   member's own optimum (best two minimised);
2. **noise levels**: each block's σ (force, and each secondary observable) is unknown unless given; it
   is re-estimated from that block's residuals, σ² = RSS/(n - k), and the fit repeated until the σ's
   settle (iteratively reweighted least squares).  The fixed point maximises the likelihood with every
   σ profiled out (:class:`~.objective.ObjectiveFit`);
3. **the row split** is re-checked at the joint optimum (a member whose pull-off row moves is refitted);
4. **covariance** from a secant Jacobian at the scale of each parameter's uncertainty
   (:func:`.intervals.secant_covariance`: a row next to a curve's fold has an infinite slope).

One block (one curve, force only) needs none of this: its optimum is the member's own fit.
"""
from __future__ import annotations

import math

import numpy as np

from .intervals import apply_secant
from .lsq import COARSE_TOL, FINE_TOL, RawFit, minimise
from .membrane import EXACT_TOL
from .objective import SIGMA_FLOOR, Block, Member, ObjectiveFit, SharedParametrisation, check_splits, objective_residual, \
    split_blocks
from .observables import OBSERVABLES, PRIMARY

__all__ = ["SIGMA_RTOL", "MAX_REWEIGHT", "SIGMA_FLOOR", "objective_fit", "members_of"]

#: stop re-estimating the noise levels when none moves by more than this fraction
SIGMA_RTOL = 0.02
MAX_REWEIGHT = 4
_LN = {"work_of_adhesion": "ln_work_of_adhesion", "mu_h": "ln_mu_h"}


def _noise_floor(values: np.ndarray) -> float:
    """A last-resort noise level: 1e-3 of the largest magnitude (never 0)."""
    v = float(np.max(np.abs(values))) if np.size(values) else 1.0
    return 1e-3 * v if v > 0 else 1e-12


def _sigma_f(raw: RawFit) -> float:
    return raw.scale if raw.sigma_given else raw.scale * math.sqrt(max(raw.best.redchi, 1e-300))


def members_of(singles: list[RawFit], curves: list, sigmas: dict, observables: tuple[str, ...],
               labels: list[str]) -> list[Member]:
    """Members at their own optima, with a block for every secondary observable each curve has."""
    out = []
    for raw, curve, label in zip(singles, curves, labels):
        blocks = []
        for name in observables:
            if name == PRIMARY:
                continue
            obs = OBSERVABLES[name]
            data = obs.rows(curve)
            if data is None:
                continue
            given = sigmas.get(name)
            sigma = given if given is not None else (obs.noise(data.values) or _noise_floor(data.values))
            blocks.append(Block(observable=obs, data=data, sigma=float(sigma), given=given is not None))
        given_f = sigmas.get(PRIMARY)
        out.append(Member(model=raw.model, par=raw.par, sigma_f=given_f if given_f is not None else _sigma_f(raw),
                          blocks=blocks, label=label, single=raw))
    return out


def _mean_start(singles: list[RawFit]) -> dict:
    """Inverse-variance mean of the members' ln W_ad and ln μh (equal weights without covariances)."""
    out = {}
    for name, ln in _LN.items():
        vals, wts = [], []
        for r in singles:
            p = r.best.params[ln]
            vals.append(p.value)
            wts.append(1.0 / p.stderr ** 2 if p.stderr and np.isfinite(p.stderr) and p.stderr > 0 else 0.0)
        w = np.array(wts) if sum(wts) > 0 else np.ones(len(vals))
        out[name] = math.exp(float(np.average(vals, weights=w)))
    return out


def _minimise_starts(residual, spar, starts, offsets, fine: float):
    """Score every shared start by one evaluation, minimise the best two (second coarsely, refined
    only if it wins); returns the best lmfit result."""
    scored = []
    for s in starts:
        r = residual(spar.params(s, offsets))
        scored.append((float(r @ r), s))
    scored.sort(key=lambda t: t[0])
    best = None
    for i, (_, s) in enumerate(scored[:2]):
        res = minimise(residual, spar.params(s, offsets), scale_covar=False, tol=fine if i == 0 else COARSE_TOL)
        if best is not None and res.chisqr < best.chisqr * (1 - 1e-6):
            res = minimise(residual, res.params, scale_covar=False, tol=fine)
        if best is None or res.chisqr < best.chisqr:
            best = res
    return best


def _reweight(members: list[Member], best) -> bool:
    """Re-estimate every non-given σ from its block's residuals; True when one moved by > SIGMA_RTOL."""
    blocks = split_blocks(np.asarray(best.residual), members)
    k_share = 2.0 / len(members)
    moved = False
    for m, (rf, sec) in zip(members, blocks):
        k = k_share + len(m.par.names) - 2
        if not m.single.sigma_given and rf.size > k + 1:
            new = m.sigma_f * math.sqrt(float(rf @ rf) / (rf.size - k))
            moved |= abs(new / m.sigma_f - 1.0) > SIGMA_RTOL
            m.sigma_f = max(new, SIGMA_FLOOR * m.par.f_scale)
        for b, rb in zip(m.blocks, sec):
            if b.given or rb.size < 2:
                continue
            new = b.sigma * math.sqrt(float(rb @ rb) / rb.size)
            moved |= abs(new / b.sigma - 1.0) > SIGMA_RTOL
            b.sigma = max(new, SIGMA_FLOOR * float(np.max(np.abs(b.data.values))))
    return moved


def objective_fit(slip: str, singles: list[RawFit], curves: list, segs: list, sigmas: dict,
                  observables: tuple[str, ...], labels: list[str]) -> ObjectiveFit:
    """One slip condition's optimum of the objective of ``curves`` (module docstring).

    Parameters
    ----------
    slip : str
    singles : list of RawFit
        Each curve's own fit of this slip condition.
    curves : list of adhfit.data.Curve
    segs : list of Segments
        Each curve's row-order segments (the free split's).
    sigmas : dict
        Observable name -> given noise σ (SI); absent: estimated.
    observables : tuple of str
        The observables to fit (the force always).
    labels : list of str
    """
    members = members_of(singles, curves, sigmas, observables, labels)
    given = {PRIMARY: sigmas.get(PRIMARY) is not None, **{n: sigmas.get(n) is not None for n in observables}}
    if len(members) == 1 and not members[0].blocks:
        return ObjectiveFit.from_single(singles[0], labels[0])
    spar = SharedParametrisation(tuple(m.par for m in members))
    offsets = []
    for r in singles:
        si = r.par.si(r.best.params)
        offsets.append({k: si[k] for k in ("x_offset", "force_offset", "force_drift")})
    starts = [_mean_start(singles)] + [{k: r.par.si(r.best.params)[k] for k in _LN} for r in singles]
    # an exact history costs ~10x a large-stretch one: its members start at their own exact optima, and
    # 1e-5 of χ² is far below what the intervals and the slip comparison need (see .membrane EXACT_TOL)
    fine = EXACT_TOL if any(m.model.membrane != "large-stretch" for m in members) else FINE_TOL
    best = _minimise_starts(objective_residual(members, spar), spar, starts, offsets, fine)
    fit = ObjectiveFit(slip, members, spar, best, given, joint=True)
    for _ in range(MAX_REWEIGHT):
        moved = _reweight(members, best)
        moved |= check_splits(fit, segs)
        if not moved:
            break
        best = minimise(objective_residual(members, spar), best.params, scale_covar=False, tol=fine)
        fit.best = best
    apply_secant(fit)
    return fit
