"""What one fit says about the truth, and the per-cell summary of the recovery study (``recovery.py``).

Works on the report dictionary (``FitResult.as_dict()``, docs/contracts.md A5/A5b), old and new shapes: a
parameter without ``status`` is ``determined`` when its ``ci95`` is two-sided; ``ci95`` may be
``[low, None]`` (``lower_bound``) or ``[None, high]`` (``upper_bound``).

Coverage counts the claims a report makes: a two-sided interval covers when it holds the truth, a
lower bound when the truth is at or above it, an upper bound when at or below; ``undetermined``
makes no claim (counted, not in the coverage).  A fit that raised is an ``error``.
"""
from __future__ import annotations

import math
from collections import Counter

import numpy as np
from scipy import stats

PARAMS = ("work_of_adhesion", "mu_h")
SHORT = {"work_of_adhesion": "W", "mu_h": "muh"}
STATUSES = ("determined", "lower_bound", "upper_bound", "undetermined", "error")
OUTCOMES = ("right", "wrong", "undecided", "error")


def _num(x) -> float | None:
    return None if x is None or not math.isfinite(float(x)) else float(x)


def status_of(p: dict) -> str:
    """The A5b status of one reported parameter (old reports: from the shape of ``ci95``)."""
    if p.get("status"):
        return str(p["status"])
    ci = p.get("ci95") or [None, None]
    lo, hi = _num(ci[0]), _num(ci[1])
    if lo is not None and hi is not None:
        return "determined"
    return "lower_bound" if lo is not None else "upper_bound" if hi is not None else "undetermined"


def judge(p: dict, truth: float) -> dict:
    """Status, value, bounds, relative error and whether the claim holds the truth."""
    status = status_of(p)
    ci = p.get("ci95") or [None, None]
    lo, hi = _num(ci[0]), _num(ci[1])
    value = _num(p.get("value"))
    if status == "undetermined":
        covered = None
    else:
        covered = (lo is None or lo <= truth) and (hi is None or truth <= hi)
        if status == "lower_bound":
            covered = lo is not None and truth >= lo
        elif status == "upper_bound":
            covered = hi is not None and truth <= hi
    return {"status": status, "value": value, "lo": lo, "hi": hi, "covered": covered,
            "rel_err": None if value is None else value / truth - 1.0}


def outcome(selected, true_slip: str) -> str:
    """right / wrong / undecided slip selection."""
    if selected is None:
        return "undecided"
    return "right" if selected == true_slip else "wrong"


def min_covered(n: int, nominal: float = 0.95, alpha: float = 0.01) -> int:
    """Fewest covering intervals among n calibrated ones that is not in the lower ``alpha`` tail.

    ``P(X < min_covered) <= alpha`` for X ~ Binomial(n, nominal).
    """
    return int(stats.binom.ppf(alpha, n, nominal)) if n > 0 else 0


def band(n: int, nominal: float = 0.95) -> tuple[float, float]:
    """Central 95 % range of the covering fraction of n calibrated intervals."""
    lo, hi = stats.binom.ppf([0.025, 0.975], n, nominal)
    return float(lo) / n, float(hi) / n


def _param_summary(recs: list[dict], name: str) -> dict:
    ok = [r[name] for r in recs if r.get("error") is None]
    errs = np.array([j["rel_err"] for j in ok if j["rel_err"] is not None], float)
    claims = [j for j in ok if j["covered"] is not None]
    covered = sum(bool(j["covered"]) for j in claims)
    counts = Counter(j["status"] for j in ok)
    counts["error"] = len(recs) - len(ok)
    return {"bias": float(errs.mean()) if errs.size else None,
            "scatter": float(errs.std(ddof=1)) if errs.size > 1 else None,
            "median_rel_err": float(np.median(errs)) if errs.size else None,
            "claims": len(claims), "covered": covered,
            "coverage": covered / len(claims) if claims else None,
            "min_covered": min_covered(len(claims)),
            "below_binomial": bool(claims) and covered < min_covered(len(claims)),
            "false_determined": sum(1 for j in claims if j["status"] == "determined" and not j["covered"]),
            "status": {s: counts.get(s, 0) for s in STATUSES}}


def summarize(recs: list[dict]) -> dict:
    """One cell: replicate count, per-parameter bias/scatter/coverage/status, slip outcomes, cost."""
    wall = [r["wall_s"] for r in recs if r.get("wall_s") is not None]
    out = {"n": len(recs), "errors": sum(r.get("error") is not None for r in recs),
           "slip_outcomes": {o: sum(r["slip_outcome"] == o for r in recs) for o in OUTCOMES},
           "median_wall_s": float(np.median(wall)) if wall else None,
           "warned_duplicates": sum(bool(r.get("warned_duplicates")) for r in recs)}
    for name in PARAMS:
        out[name] = _param_summary(recs, name)
    return out


def cells(records: list[dict], keys: tuple[str, ...]) -> list[dict]:
    """Records grouped by ``keys`` (in first-seen order), each group summarised."""
    groups: dict[tuple, list] = {}
    for r in records:
        groups.setdefault(tuple(r[k] for k in keys), []).append(r)
    return [dict(zip(keys, k)) | summarize(v) for k, v in groups.items()]
