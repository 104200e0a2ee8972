"""report.json (docs/contracts.md A5): the fit result as JSON, SI values, never NaN."""
from __future__ import annotations

import json
from pathlib import Path

from .files import write_text

__all__ = ["report_dict", "write_json"]


def _has_null_numbers(d, path=""):
    """Paths of keys whose value is None inside "parameters" (numbers that could not be computed)."""
    out = []
    if isinstance(d, dict):
        for k, v in d.items():
            out += _has_null_numbers(v, f"{path}.{k}" if path else k)
    elif d is None and path.split(".")[-1] in ("value", "stderr", "ci95"):
        out.append(path)
    return out


def report_dict(result, extra: dict | None = None) -> dict:
    """The report.json content of a :class:`~adhfit.fitting.result.FitResult`.

    Every non-finite number becomes ``null``; when an estimate or its error is null, a warning
    saying so is added (a null must never pass unexplained).  ``extra`` keys (e.g. the CLI's
    ``engine_startup_s``, the one-off compile or cache load kept out of ``wall_time_s``) are added.
    """
    d = result.as_dict()
    d.update(extra or {})
    params = d.get("parameters", {}) or {}
    # a one-sided or undetermined estimate says so in its status; only unexplained nulls get a warning
    missing = [m for m in _has_null_numbers(params, "parameters")
               if (params.get(m.split(".")[1]) or {}).get("status", "determined") == "determined"]
    if missing:
        d["warnings"] = list(d["warnings"]) + [f"not computed (null in this report): {', '.join(missing)}"]
    return d


def write_json(result, path: str | Path, *, extra: dict | None = None) -> Path:
    """Write report.json atomically; ``allow_nan=False`` guarantees strict JSON."""
    return write_text(path, dumps(report_dict(result, extra)))


def dumps(d: dict) -> str:
    """The text of report.json: strict JSON (no NaN), indented, UTF-8 characters kept."""
    return json.dumps(d, indent=2, allow_nan=False, ensure_ascii=False) + "\n"
