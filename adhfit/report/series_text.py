"""Words and numbers of a global (series) fit's reports, shared by report.html and report.md.

Reads the report.json dictionary (``FitResult.as_dict()`` with ``curves``), so a saved report renders
the same as a fresh one.
"""
from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

from .text import estimate_text, fmt, interval_text

__all__ = [
    "CURVE_HEADER",
    "FLAG_WORDS",
    "SLIP_HEADER",
    "curve_label",
    "curve_legend",
    "curve_rows",
    "scene_text",
    "slip_rows",
    "width_comparison",
]

FLAG_WORDS = {"redchi": "misfit: the shared values do not follow it",
              "redchi_contact_radius": "contact radius misfit",
              "pull": "disagrees with the other curves"}

CURVE_HEADER = ["#", "curve", "scene", "rows", "force noise σ (mN)", "χ²/n force", "χ²/n contact radius",
                "W_ad alone (J/m², 95 %)", "μh alone (N/m, 95 %)", "pull on W_ad, μh (σ)", "p",
                "share of W_ad, μh precision", "flags"]

SLIP_HEADER = ["slip", "reduced χ²", "BIC", "W_ad", "μh", "probability"]


def curve_label(file: Any) -> str:
    """A short name: ``folder/file.csv`` of a path, the text itself otherwise."""
    text = str(file)
    if text.startswith("<"):
        return text.strip("<>")
    p = Path(text)
    return f"{p.parent.name}/{p.name}" if p.parent.name else p.name


def scene_text(c: Mapping[str, Any]) -> str:
    """The curve's own scene value: ``P = 0.8 kPa`` (displacement control) or ``gap = 1.2 mm``."""
    sc = c.get("scene") or {}
    if sc.get("control") == "displacement" and sc.get("pressure") is not None:
        return f"P = {fmt(sc['pressure'] * 1e-3)} kPa"
    if sc.get("control") == "pressure" and sc.get("gap") is not None:
        return f"gap = {fmt(sc['gap'] * 1e3)} mm"
    return str(sc.get("control") or "")


def _pct(x: Any) -> str:
    return "n/a" if not isinstance(x, (int, float)) else f"{100 * x:.0f} %"


def _alone(c: Mapping[str, Any], name: str) -> str:
    """``0.4058 [0.3957, 0.4162]`` (value and 95 % interval, no unit), or the bound's words."""
    a = (c.get("alone") or {}).get(name)
    if not isinstance(a, Mapping):
        return "n/a"
    if a.get("status", "determined") != "determined" or a.get("value") is None:
        return estimate_text(name, a)
    return f"{fmt(a['value'])} {interval_text(name, a, unit=False)}"


def curve_rows(d: Mapping[str, Any]) -> list[list[str]]:
    """One row of plain text per curve, columns :data:`CURVE_HEADER`."""
    rows = []
    for k, c in enumerate(d.get("curves") or []):
        lo = c.get("leave_one_out") or {}
        s = lo.get("shift_in_stderr") or {}
        share = lo.get("contribution") or {}
        cr = c.get("contact_radius") or {}
        sf = c.get("sigma_force")
        rows.append([str(k + 1), curve_label(c.get("file")), scene_text(c), str(c.get("n_points")),
                     fmt(None if sf is None else sf * 1e3, 2), fmt(c.get("redchi"), 3), fmt(cr.get("redchi"), 3) if cr else "not fitted",
                     _alone(c, "work_of_adhesion"), _alone(c, "mu_h"),
                     f"{fmt(s.get('work_of_adhesion'), 2)}, {fmt(s.get('mu_h'), 2)}",
                     fmt(lo.get("p_value"), 2),
                     f"{_pct(share.get('work_of_adhesion'))}, {_pct(share.get('mu_h'))}",
                     "; ".join(FLAG_WORDS.get(f, f) for f in c.get("flags") or []) or "—"])
    return rows


def curve_legend() -> list[str]:
    """What the per-curve columns mean (plain sentences)."""
    return ["χ²/n: the curve's own reduced χ² against the shared fit, in units of its row-to-row noise "
            "(about 1 when the curve agrees; flagged above 2).",
            "alone: the curve's own least-squares fit, for comparison.",
            "pull: how far the shared value moves when the curve is left out, in standard errors of the "
            "shared value; p: the chance of a pull this large if the curve agrees with the others (χ², 2 "
            "degrees of freedom; flagged below 0.001).",
            "share of precision: how much of the shared value's precision (1/σ²) the curve brings "
            "(1 − σ²/σ²_without; linearised)."]


def slip_rows(d: Mapping[str, Any]) -> list[list[str]]:
    """Per slip condition: reduced χ², BIC, its W_ad and μh, its probability (MCMC), columns :data:`SLIP_HEADER`
    (least squares: without the probability)."""
    slip = d.get("slip") or {}
    probs = slip.get("probabilities") or {}
    rows = []
    for s, f in (d.get("fits") or {}).items():
        p = f.get("parameters") or {}
        mark = " (reported)" if s == slip.get("parameters_from") else ""
        rows.append([s + mark, fmt(f.get("redchi"), 4), fmt(f.get("bic"), 6),
                     estimate_text("work_of_adhesion", p["work_of_adhesion"]) if "work_of_adhesion" in p else "n/a",
                     estimate_text("mu_h", p["mu_h"]) if "mu_h" in p else "n/a",
                     fmt(probs.get(s), 4)][:None if probs else -1])
    return rows


def width_comparison(d: Mapping[str, Any]) -> str | None:
    """One sentence: the shared W_ad interval's relative width against the narrowest single-curve one."""
    w = (d.get("parameters") or {}).get("work_of_adhesion") or {}
    ci = w.get("ci95")
    if not ci or None in ci or not w.get("value"):
        return None
    widths = []
    for c in d.get("curves") or []:
        a = (c.get("alone") or {}).get("work_of_adhesion") or {}
        aci, v = a.get("ci95"), a.get("value")
        if aci and None not in aci and v:
            widths.append(((aci[1] - aci[0]) / v, curve_label(c.get("file"))))
    shared = (ci[1] - ci[0]) / w["value"]
    if not widths:
        return f"The shared W_ad interval is {100 * shared:.2g} % wide; no single curve determines W_ad alone."
    best, name = min(widths)
    return (f"The shared W_ad interval is {100 * shared:.2g} % of the value wide; the narrowest single-curve "
            f"interval ({name}) is {100 * best:.2g} %.")
