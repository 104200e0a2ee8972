"""Words and numbers shared by every report (HTML, Markdown, the CLI summary, plots).

Everything reads the report.json dictionary (:meth:`FitResult.as_dict`), so a saved report renders the
same as a fresh one; missing keys are skipped, never guessed.
"""
from __future__ import annotations

import math
from typing import Any, Mapping

__all__ = ["PARAMETERS", "SCENE_FIELDS", "display", "fmt", "estimate_text", "interval_text", "status_text",
           "seed_text", "scene_value"]

#: report name -> (symbol, plain name, SI -> display factor, display unit)
PARAMETERS = {
    "work_of_adhesion": ("W_ad", "work of adhesion", 1.0, "J/m²"),
    "mu_h": ("μh", "membrane stiffness (shear modulus × thickness)", 1.0, "N/m"),
    "displacement_offset": ("δ₀", "displacement offset", 1e6, "µm"),
    "x_offset": ("δ₀", "displacement offset", 1e6, "µm"),
    "displacement": ("δ₀", "displacement offset", 1e6, "µm"),
    "pressure_offset": ("P₀", "pressure offset", 1e-3, "kPa"),
    "pressure": ("P₀", "pressure offset", 1e-3, "kPa"),
    "force_offset": ("F₀", "load-cell zero (force offset)", 1e3, "mN"),
    "force": ("F₀", "load-cell zero (force offset)", 1e3, "mN"),
    "contact_radius_offset": ("a₀", "contact-radius offset", 1e6, "µm"),
}

#: scene key (report.json provenance.scene) -> (label, SI -> display factor, display unit)
SCENE_FIELDS = {
    "membrane_radius": ("membrane radius b (clamped, after pre-stretch)", 1e3, "mm"),
    "prestretch": ("pre-stretch λ0", 1.0, ""),
    "mu_h": ("membrane stiffness μh", 1.0, "N/m"),
    "model": ("membrane model", 1.0, ""),
    "substrate_radius": ("substrate radius R_s", 1e3, "mm"),
    "control": ("control", 1.0, ""),
    "pressure": ("fixed pressure P", 1e-3, "kPa"),
    "gap": ("fixed gap d", 1e3, "mm"),
    "slip": ("slip condition asked for", 1.0, ""),
    "work_of_adhesion": ("work of adhesion W_ad", 1.0, "J/m²"),
    "contact_radius_max": ("largest contact radius on loading", 1e3, "mm"),
    "displacement_max": ("largest displacement on loading", 1e3, "mm"),
    "pressure_max": ("largest pressure on loading", 1e-3, "kPa"),
}

_WHY = {
    ("work_of_adhesion", "lower_bound"): "the test never reached delamination",
    ("work_of_adhesion", "upper_bound"): "the data bound it from above only",
    ("mu_h", "lower_bound"): "the data bound it from below only",
    ("mu_h", "upper_bound"): "the data bound it from above only",
}


def display(name: str, unit: str | None = None) -> tuple[str, str, float, str]:
    """(symbol, plain name, factor, unit) of a parameter; unknown names keep their SI unit."""
    return PARAMETERS.get(name, (name, name.replace("_", " "), 1.0, unit or ""))


def _finite(x: Any) -> bool:
    return isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x)


def fmt(x: Any, digits: int = 4) -> str:
    """A number with ``digits`` significant digits; ``n/a`` for a missing one."""
    if not _finite(x):
        return "n/a" if x is None or isinstance(x, (int, float)) else str(x)
    return f"{x:.{digits}g}"


def status_text(d: Mapping[str, Any]) -> str:
    """The estimate's status: ``determined``, ``lower_bound``, ``upper_bound`` or ``undetermined``."""
    status = d.get("status")
    if status:
        return str(status)
    return "determined" if _finite(d.get("value")) else "undetermined"


def _ci(d: Mapping[str, Any]) -> tuple[Any, Any]:
    ci = d.get("ci95")
    if not isinstance(ci, (list, tuple)) or len(ci) != 2:
        return None, None
    return ci[0], ci[1]


def interval_text(name: str, d: Mapping[str, Any], *, unit: bool = True) -> str:
    """The 95 % interval in display units: ``[lo, hi]``, ``≥ lo``, ``≤ hi`` or ``n/a``."""
    _, _, k, u = display(name, d.get("unit"))
    lo, hi = _ci(d)
    tail = f" {u}" if unit and u else ""
    if _finite(lo) and _finite(hi):
        return f"[{fmt(lo * k)}, {fmt(hi * k)}]{tail}"
    if _finite(lo):
        return f"≥ {fmt(lo * k)}{tail}"
    if _finite(hi):
        return f"≤ {fmt(hi * k)}{tail}"
    return "n/a"


def estimate_text(name: str, d: Mapping[str, Any]) -> str:
    """One honest line: ``0.3987 ± 0.0013 J/m² (95 % [0.396, 0.401])``; a one-sided bound as
    ``≥ 0.35 J/m² (lower bound: …)``; ``not determined by these data`` otherwise."""
    _, _, k, u = display(name, d.get("unit"))
    status = status_text(d)
    why = d.get("why") or d.get("reason") or _WHY.get((name, status), "")
    if status in ("lower_bound", "upper_bound"):
        bound = interval_text(name, d)
        if bound == "n/a" and _finite(d.get("value")):
            bound = ("≥ " if status == "lower_bound" else "≤ ") + f"{fmt(d['value'] * k)} {u}".strip()
        kind = status.replace("_", " ")
        return f"{bound} ({kind}{': ' + why if why else ''})"
    if status == "undetermined" or not _finite(d.get("value")):
        return "not determined by these data" + (f" ({why})" if why else "")
    se = d.get("stderr")
    text = fmt(d["value"] * k)
    if _finite(se):
        text += f" ± {fmt(se * k, 2)}"
    text += f" {u}" if u else ""
    ci = interval_text(name, d, unit=False)
    return text + (f" (95 % {ci})" if ci != "n/a" else "")


def seed_text(d: Mapping[str, Any]) -> str:
    """What the seed means for this method; never "seed None"."""
    prov = d.get("provenance", {}) or {}
    seed = prov.get("seed", d.get("seed"))
    if d.get("method") == "mcmc" or isinstance(d.get("mcmc"), Mapping):
        seed = seed if seed is not None else (d.get("mcmc") or {}).get("seed")
        return f"seed {seed}" if seed is not None else "seed not recorded"
    return "no random numbers used" if seed is None else f"no random numbers used (seed {seed} recorded)"


def scene_value(key: str, value: Any) -> tuple[str, str, str]:
    """(label, value, unit) of one scene field for display; ``inf`` for a flat substrate."""
    label, k, unit = SCENE_FIELDS.get(key, (key.replace("_", " "), 1.0, ""))
    if value is None:
        return label, "not set (fitted)" if key in ("mu_h", "work_of_adhesion") else "not set", ""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return label, str(value), ""
    if not math.isfinite(value):
        return label, "∞ (flat)" if key == "substrate_radius" else str(value), ""
    return label, fmt(value * k, 6), unit
