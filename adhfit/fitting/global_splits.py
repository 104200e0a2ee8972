"""The row split of each curve in a global fit: where its pull-off row lies at the joint optimum
(step 4 of :mod:`.global_fit`)."""
from __future__ import annotations


from .model import CurveModel, ModelDomainError
from .series import Member, radius_prediction

__all__ = ["check_splits"]


def _fixed(curve, scene, slip, points, seg, j):
    return CurveModel(curve, scene, slip, points=points, fixed_split=True, segments=seg.split_before(j, curve.force))


def _block_cost(m, sub) -> float:
    """χ² of one curve (force rows, pull-off term, contact radius) at internal values ``sub``."""
    r = m.force_residual()(sub)
    cost = float(r @ r)
    if m.radius is not None:
        si = m.par.si(sub)
        a = radius_prediction(m.model, si["work_of_adhesion"], si["mu_h"], si["x_offset"])
        ra = (m.radius.values - a[m.radius.rows]) / m.sigma_a
        cost += float(ra @ ra)
    return cost


def check_splits(members, curves, scenes, segs, slip, points, spar, params) -> bool:
    """Put each curve's pull-off row where the joint optimum puts it; True when one moved.

    The free split's row at the joint optimum and its two neighbours (the row split is discrete: one
    row off costs a many-σ residual) are compared with the current split by the curve's χ² at the
    joint optimum; the cheapest wins."""
    shared, offsets = spar.si(params)
    v = params.valuesdict()
    changed = False
    for i, m in enumerate(members):
        free = CurveModel(curves[i], scenes[i], slip, points=points, segments=segs[i])
        try:
            j = free.split(shared["work_of_adhesion"], shared["mu_h"], offsets[i]["x_offset"])
        except ModelDomainError:
            continue
        now = m.model.segments.i_jump if m.model.fixed_split else None
        if j == now:
            continue
        sub = spar.member_values(v, i)
        best_model, best_cost = m.model, _block_cost(m, sub)
        cands = [free] if j is None else []
        for jj in ([] if j is None else (j - 1, j, j + 1)):
            if segs[i].i_turn + 1 < jj < free.x.size - 1 and jj != now:
                cands.append(_fixed(curves[i], scenes[i], slip, points, segs[i], jj))
        for model in cands:
            trial = Member(model=model, par=m.par, sigma_f=m.sigma_f, radius=m.radius, sigma_a=m.sigma_a)
            try:
                cost = _block_cost(trial, sub)
            except ModelDomainError:
                continue
            if cost < best_cost:
                best_model, best_cost = model, cost
        if best_model is not m.model:
            m.model, m._residual, changed = best_model, None, True
    return changed
