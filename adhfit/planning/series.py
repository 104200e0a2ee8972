"""``--global K``: the set of K pressures (displacement control) or gaps (pressure control) that a joint fit
of one membrane (one W_ad, one μh, one slip condition, offsets and noise per curve; docs/contracts.md A7)
determines best.

Each curve's information about (ln W_ad, ln μh), its own nuisances profiled out
(:func:`.information.reduced_information`), adds up over the curves; the joint widths follow from the
sum.  The joint ΔBIC is the sum of the curves' Σ n_g ln(RSS_wrong,g / RSS_true,g); each curve's term is
sampled as for one test (:mod:`.verdict`) and the draws are added.  The other condition's joint fit
shares W_ad and μh over the curves, so its misfit is at least the sum of the curves' own: the joint
P(slip decided) given here is a lower bound.  The set chosen is the one with the narrowest W_ad interval
(then μh) among those that decide the slip with P ≥ 0.9 for every true condition; without one, the set
with the largest P(slip decided).  All sets are tried up to :data:`MAX_SETS`, greedily beyond.

With ``radius_noise`` (a filmed test) each curve's information includes its contact-radius block; the
slip verdict stays force-only (a lower bound on its P).
"""
from __future__ import annotations

import itertools
import math

import numpy as np

from ..errors import InputError
from .information import widths_from_information
from .recommend import P_DECIDED
from .verdict import DECISIVE, SEED, Misfit, sample_delta_bic

__all__ = ["best_set", "MAX_SETS"]

#: largest number of K-subsets tried exhaustively
MAX_SETS = 20_000
_DRAWS = 4000


def _candidates(plan, axis: str) -> list[int]:
    """Protocols along ``axis`` at the other varied setting's value of the recommended protocol (or the value
    with the most protocols inside the domain)."""
    names = list(plan.axes)
    entries = plan.protocols
    if len(names) == 1:
        return [i for i, e in enumerate(entries) if e["in_domain"]]
    other = names[1] if names[0] == axis else names[0]
    if plan.recommended is not None:
        fixed = entries[plan.recommended]["grid"][other]
    else:
        values = plan.axes[other]
        fixed = max(values, key=lambda v: sum(e["in_domain"] for e in entries if e["grid"][other] == v))
    return [i for i, e in enumerate(entries) if e["in_domain"] and e["grid"][other] == fixed]


def _score(entries, subset, slips, values, samples) -> tuple:
    widths = {}
    for s in slips:
        total = sum(np.asarray(entries[i]["by_slip"][s]["information"]) for i in subset)
        w = widths_from_information(total, values)
        for k, v in w.items():
            widths[k] = max(widths.get(k, 0.0), v["width"])
    p = {s: float(np.mean(sum(samples[(i, s)] for i in subset) > DECISIVE)) for s in slips}
    wrong = {s: float(np.mean(sum(samples[(i, s)] for i in subset) < -DECISIVE)) for s in slips}
    return widths, p, wrong


def best_set(plan, k: int, slips: tuple, w: float, mu: float, membrane: str) -> dict:
    """The ``series`` entry of plan.json (module docstring)."""
    control = plan.base.scene.control
    axis = "pressure" if control == "displacement" else "gap"
    if axis not in plan.axes:
        raise InputError("--global", k, f"used with --vary {axis}=LO:HI:K ({control} control: the series varies the "
                         f"{axis})", f"Add e.g. --vary {axis}=" + ("0.5:1.5kPa:8." if axis == "pressure" else "0:0.4mm:8."))
    cands = [i for i in _candidates(plan, axis)
             if all(plan.protocols[i]["by_slip"][s].get("information") is not None for s in slips)]
    if k > len(cands):
        raise InputError("--global", k, f"at most {len(cands)} (the {axis} values inside the model's domain)",
                         "Widen the --vary range or lower K.")
    entries = plan.protocols
    values = {"work_of_adhesion": w, "mu_h": mu}
    samples = {}
    for n, i in enumerate(cands):
        for s in slips:
            samples[(i, s)] = sample_delta_bic(Misfit(**entries[i]["by_slip"][s]["misfit"]),
                                               np.random.default_rng(SEED + 7919 * n + (s == "frictionless")), _DRAWS)

    def key(subset):
        widths, p, _ = _score(entries, subset, slips, values, samples)
        ok = min(p.values()) >= P_DECIDED
        return (0 if ok else 1, widths["work_of_adhesion"] if ok else -min(p.values()), widths["mu_h"])

    if math.comb(len(cands), k) <= MAX_SETS:
        best = min(itertools.combinations(cands, k), key=key)
        how = "every set tried"
    else:  # greedy: add the curve that improves the set most
        best = ()
        for _ in range(k):
            best = min((best + (i,) for i in cands if i not in best), key=key)
        how = "sets built greedily"
    widths, p, wrong = _score(entries, best, slips, values, samples)
    chosen = sorted(float(entries[i]["grid"][axis]) for i in best)
    ok = min(p.values()) >= P_DECIDED
    unit = "Pa" if axis == "pressure" else "m"
    why = (f"{axis}s {', '.join(f'{v:.4g}' for v in chosen)} {unit} ({how} of {len(cands)} candidates): expected 95 % width "
           f"of the shared W_ad {100 * widths['work_of_adhesion'] / w:.3g} %, μh {100 * widths['mu_h'] / mu:.3g} %; "
           f"P(slip decided) at least {min(p.values()):.3f}" +
           ("" if ok else f" — below {P_DECIDED:g}: no set of {k} decides the slip; more curves or less noise") +
           ("; with the filmed contact radius (the slip verdict from the force alone)"
            if plan.inputs.get("radius_noise") else "; force only (--radius-noise adds a filmed contact radius)"))
    return {"k": k, "axis": axis, axis: chosen, "protocols": sorted(best), "ci95_width": widths,
            "p_slip_decided_at_least": p, "p_wrong_slip": wrong, "reached": ok, "why": why}
