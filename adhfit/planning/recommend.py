"""The recommendation: the cheapest protocol that decides the slip and reaches the requested W_ad precision.

A protocol qualifies when it stays in the model's domain, the fit selects the true slip condition with
probability at least :data:`P_DECIDED` for every true condition considered, and the expected 95 %
interval of W_ad is at most ``target`` of W_ad wide.  Among those, the cheapest is the one with the
fewest rows (test time), then the shallowest loading (the least load on the membrane), then the largest
noise (the cheapest instrument); what is left is ranked by the narrowest W_ad interval.
"""
from __future__ import annotations

import math

__all__ = ["recommend", "P_DECIDED", "DEFAULT_TARGET", "qualifies"]

#: probability of a decided (and correct) slip verdict a recommended protocol must reach
P_DECIDED = 0.9
#: default requested precision: the expected 95 % width of W_ad over W_ad
DEFAULT_TARGET = 0.1


def _relative(entry: dict, w: float) -> float:
    v = entry["ci95_width"]["work_of_adhesion"]
    return v / w if v is not None and math.isfinite(v) else math.inf


def _p_decided(entry: dict) -> float:
    vals = [v for v in entry["p_slip_decided"].values()]
    return min(vals) if vals and None not in vals else 0.0


def qualifies(entry: dict, w: float, target: float) -> bool:
    """Whether a protocol decides the slip (P ≥ :data:`P_DECIDED`) and reaches ``target``."""
    return bool(entry["in_domain"]) and _p_decided(entry) >= P_DECIDED and _relative(entry, w) <= target


def _cost(entry: dict, w: float) -> tuple:
    s = entry["settings"]
    return (s["rows"], s.get("control_max", 0.0), -s["noise"], _relative(entry, w))


def _describe(entry: dict) -> str:
    s = entry["settings"]
    parts = [f"{k} = {v:.4g}" for k, v in s.items() if k not in ("control", "control_max") and isinstance(v, float)]
    return f"{s['control']} control, " + ", ".join(parts + [f"rows = {s['rows']}"])


def recommend(entries: list[dict], w: float, target: float) -> tuple[int | None, str]:
    """(index of the recommended protocol or None, why) — module docstring."""
    inside = [i for i, e in enumerate(entries) if e["in_domain"]]
    if not inside:
        return None, "no protocol stays inside the model's domain (see each protocol's why_not)"
    ok = [i for i in inside if qualifies(entries[i], w, target)]
    if ok:
        best = min(ok, key=lambda i: _cost(entries[i], w))
        e = entries[best]
        return best, (f"the cheapest of {len(ok)} protocol(s) (fewest rows, then shallowest loading, then largest "
                      f"noise) that decides the slip with probability ≥ {P_DECIDED:g} (here {_p_decided(e):.3f}) and "
                      f"reaches the requested W_ad precision (expected 95 % width {100 * _relative(e, w):.3g} % ≤ "
                      f"{100 * target:.3g} % of W_ad): {_describe(e)}")
    p_best = max(inside, key=lambda i: _p_decided(entries[i]))
    w_best = min(inside, key=lambda i: _relative(entries[i], w))
    return None, (f"no protocol reaches both P(slip decided) ≥ {P_DECIDED:g} and a W_ad width ≤ {100 * target:.3g} %: "
                  f"the best P(slip decided) is {_p_decided(entries[p_best]):.2f} ({_describe(entries[p_best])}), the "
                  f"narrowest W_ad interval {100 * _relative(entries[w_best], w):.3g} % ({_describe(entries[w_best])}); "
                  f"lower the noise, add rows, load deeper, or relax --target-precision")
