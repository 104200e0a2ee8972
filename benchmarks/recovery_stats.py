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


# --- issue 20's "Done when" (replicate study) -------------------------------------------------------
#: coverage targets of issue 20: both parameters pooled per noise level; W_ad from the true slip's own fit
TARGET_POOLED = 0.93
TARGET_OWN_SLIP = 0.90
#: a fit detaches "early" when its model's first detached row is at least this many rows before the
#: data's jump (the first row past the true turning point, where the noise-free force drops to zero) (issue 20 reports 2-16 rows; one row can move with a legitimate W_ad change)
EARLY_ROWS = 2


def proportion(k: int, n: int, level: float = 0.95) -> dict:
    """k of n with the two-sided Clopper-Pearson and Wilson intervals (None when n = 0)."""
    if n == 0:
        return {"k": 0, "n": 0, "rate": None, "cp": [None, None], "wilson": [None, None]}
    tail = (1.0 - level) / 2
    lo = 0.0 if k == 0 else float(stats.beta.ppf(tail, k, n - k + 1))
    hi = 1.0 if k == n else float(stats.beta.ppf(1.0 - tail, k + 1, n - k))
    z, p = float(stats.norm.ppf(1.0 - tail)), k / n
    mid, half = (p + z * z / (2 * n)), z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n))
    den = 1 + z * z / n
    return {"k": k, "n": n, "rate": p, "cp": [lo, hi], "wilson": [(mid - half) / den, (mid + half) / den]}


def _claims(judged: list[dict]) -> dict:
    claims = [j for j in judged if j is not None and j.get("covered") is not None]
    return proportion(sum(bool(j["covered"]) for j in claims), len(claims))


def _rows_early(rec: dict, slip: str, against: str = "true") -> int | None:
    """How many rows before the data's jump row (the first row past the true turning point; ``"detected"``:
    the row ``detect_jump`` finds) the ``slip`` fit's model detaches (negative: after)."""
    f, ref = rec.get("fits", {}).get(slip, {}), (rec.get("jump") or {}).get(against)
    row = f.get("first_detached_row")
    return None if row is None or ref is None else int(ref) - int(row)


def issue20_cell(recs: list[dict]) -> dict:
    """One group of records: pooled coverage of both parameters, W_ad / μh coverage from the true slip's
    own fit, early-detachment optima, slip outcomes by evidence word."""
    ok = [r for r in recs if r.get("error") is None and "fits" in r]
    other = {"no-slip": "frictionless", "frictionless": "no-slip"}
    out = {"n": len(recs), "with_fits": len(ok), "errors": sum(r.get("error") is not None for r in recs),
           "pooled": {name: _claims([r[name] for r in ok]) for name in PARAMS},
           "own_slip": {name: _claims([r["fits"].get(r["slip"], {}).get(name) for r in ok]) for name in PARAMS},
           "other_slip": {name: _claims([r["fits"].get(other[r["slip"]], {}).get(name) for r in ok])
                          for name in PARAMS}}
    early = {"reported": [], "own": [], "any": [], "one_row": [], "late": [], "no_detected_jump": [],
             "detected_not_true": [], "not_success": [],
             "vs_detected_differs": []}
    for r in ok:
        tag = [r["case"], r["slip"], r["noise"], r["rep"]]
        by = {s: _rows_early(r, s) for s in r["fits"]}
        if (r.get("jump") or {}).get("detected") is None:
            early["no_detected_jump"].append(tag)
        elif r["jump"]["detected"] != r["jump"]["true"]:
            early["detected_not_true"].append(tag + [r["jump"]["detected"], r["jump"]["true"]])
        if (by.get(r.get("parameters_from")) or 0) >= EARLY_ROWS:
            early["reported"].append(tag + [by[r["parameters_from"]]])
        if (by.get(r["slip"]) or 0) >= EARLY_ROWS:
            early["own"].append(tag + [by[r["slip"]]])
        if any((v or 0) >= EARLY_ROWS for v in by.values()):
            early["any"].append(tag + [{s: v for s, v in by.items()}])
        if any(v == 1 for v in by.values()):
            early["one_row"].append(tag + [{s: v for s, v in by.items()}])
        if any(v is not None and v <= -EARLY_ROWS for v in by.values()):
            early["late"].append(tag + [{s: v for s, v in by.items()}])
        det = {s: _rows_early(r, s, "detected") for s in r["fits"]}
        if any(v is not None and v != by[s] for s, v in det.items()):
            early["vs_detected_differs"].append(tag + [det])
        if any(f.get("success") is False for f in r["fits"].values()):
            early["not_success"].append(tag)
    out["early"] = early
    words: dict[str, dict] = {}
    for r in ok:
        w = words.setdefault(r.get("evidence") or "none", {"uses": 0, "right": 0, "wrong": 0})
        w["uses"] += 1
        w["right" if r.get("favoured") == r["slip"] else "wrong"] += 1
    out["words"] = words
    out["selected"] = {o: sum(r["slip_outcome"] == o for r in recs) for o in OUTCOMES}
    return out


def issue20(records: list[dict], keys: tuple[str, ...]) -> list[dict]:
    """:func:`issue20_cell` per group of ``keys`` (first-seen order)."""
    groups: dict[tuple, list] = {}
    for r in records:
        groups.setdefault(tuple(r[k] for k in keys), []).append(r)
    return [dict(zip(keys, k)) | issue20_cell(v) for k, v in groups.items()]
