"""The view layer: words and numbers of a report, shared by every format (Markdown, HTML, the CLI, plots).

Everything reads the report.json dictionary (:meth:`FitResult.as_dict`, docs/contracts.md A5), so a saved
report renders the same as a fresh one; missing keys are skipped, never guessed.  Symbols and SI units
come from the parameter table (:data:`adhfit.params.FITTED`); the display unit of each SI unit is chosen
here, once (:data:`DISPLAY_UNITS`).

A page is a :class:`View`: a title, a subtitle and :class:`Section` s of plain-text blocks
(:class:`Note`, :class:`Bullets`, :class:`Table`, :class:`Figure`).  Blocks hold plain text only; each
writer escapes it for its format, so no text from a file name, a scene or a fit reaches a page raw.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Mapping

from ..params import FITTED

__all__ = ["DISPLAY_UNITS", "OFFSET_SENTENCE", "SCENE_FIELDS", "Bullets", "Figure", "Note", "Section", "Table",
           "View", "curve_label", "display", "estimate_text", "finite", "fmt", "interval_text", "offset_name",
           "scene_value", "seed_text", "status_text"]

#: SI unit -> (SI -> display factor, display unit)
DISPLAY_UNITS = {"J/m^2": (1.0, "J/m²"), "N/m": (1.0, "N/m"), "m": (1e6, "µm"), "Pa": (1e-3, "kPa"),
                 "N": (1e3, "mN")}

#: How every offset enters the fit, in one place (``fitting.model.CurveModel.predict``): the control offset
#: shifts the measured displacement or pressure; the force offset is added to the MODEL force.
OFFSET_SENTENCE = ("Offsets as computed: the displacement (or pressure) offset δ_0 (P_0) is added to the measured "
                   "displacement (pressure) before the model is evaluated; the load-cell zero F_0 is added to the "
                   "model force (predicted force = model force + F_0), so the measured force minus F_0 is the "
                   "membrane's force.")

#: report.json ``offsets`` short names -> parameter table rows
_OFFSETS = {"displacement": "displacement_offset", "x_offset": "displacement_offset",
            "pressure": "pressure_offset", "force": "force_offset"}

#: scene key (report.json provenance.scene) -> (label, SI unit)
SCENE_FIELDS = {
    "membrane_radius": ("membrane radius b (clamped, after pre-stretch)", "mm"),
    "prestretch": ("pre-stretch λ0", ""),
    "mu_h": ("membrane stiffness μh", "N/m"),
    "model": ("membrane model", ""),
    "substrate_radius": ("substrate radius R_s", "mm"),
    "control": ("control", ""),
    "pressure": ("fixed pressure P", "kPa"),
    "gap": ("fixed gap d", "mm"),
    "slip": ("slip condition asked for", ""),
    "work_of_adhesion": ("work of adhesion W_ad", "J/m²"),
    "contact_radius_max": ("largest contact radius on loading", "mm"),
    "displacement_max": ("largest displacement on loading", "mm"),
    "pressure_max": ("largest pressure on loading", "kPa"),
}
#: short plain names of the offsets (their parameter-table descriptions say how they enter the fit)
_PLAIN = {"force_offset": "load-cell zero (force offset)", "displacement_offset": "displacement offset",
          "pressure_offset": "pressure offset"}
_SCENE_FACTOR = {"mm": 1e3, "kPa": 1e-3, "N/m": 1.0, "J/m²": 1.0, "": 1.0}

_WHY = {
    ("work_of_adhesion", "lower_bound"): "the test never reached delamination",
    ("work_of_adhesion", "upper_bound"): "the data bound it from above only",
    ("mu_h", "lower_bound"): "the data bound it from below only",
    ("mu_h", "upper_bound"): "the data bound it from above only",
}


# ---------------------------------------------------------------- blocks of a page (plain text only)
@dataclass(frozen=True)
class Note:
    """A paragraph; ``tone`` is ``""``, ``"muted"``, ``"ok"``, ``"warn"``, ``"bad"`` or ``"verdict"``; each line
    of ``lines`` on its own line."""

    lines: tuple[str, ...]
    tone: str = ""


@dataclass(frozen=True)
class Bullets:
    """A list; ``tone`` as :class:`Note` (``"warn"``: one warning box per item)."""

    items: tuple[str, ...]
    tone: str = ""


@dataclass(frozen=True)
class Table:
    """A table of plain-text cells; columns in ``numeric`` align right, rows in ``flagged`` stand out."""

    header: tuple[str, ...]
    rows: tuple[tuple[str, ...], ...]
    numeric: tuple[int, ...] = ()
    flagged: tuple[int, ...] = ()


@dataclass(frozen=True)
class Figure:
    """A figure file written next to the report (``fit.png``) and its caption."""

    name: str
    caption: str


@dataclass(frozen=True)
class Section:
    """A titled part of the page: blocks and sub-sections; ``folded`` (the one-line summary) folds it away."""

    title: str
    blocks: tuple[Any, ...] = ()
    folded: str | None = None


@dataclass(frozen=True)
class View:
    """A whole report: title, subtitle lines and sections, in reading order."""

    title: str
    subtitle: tuple[str, ...]
    sections: tuple[Section, ...] = field(default_factory=tuple)


# ---------------------------------------------------------------- numbers and units
def offset_name(name: str) -> str:
    """The parameter-table row of an offset's report.json name (``force`` -> ``force_offset``)."""
    return _OFFSETS.get(name, name)


def display(name: str, unit: str | None = None) -> tuple[str, str, float, str]:
    """(symbol, plain name, SI -> display factor, display unit) of a parameter or offset.

    Symbols and SI units come from :data:`adhfit.params.FITTED`; names the table does not know keep
    ``unit`` as it is.
    """
    base, _, k = name.rpartition("_")
    if base and k.isdigit() and FITTED.get(offset_name(base)):  # a series' per-curve offset: ``force_offset_0``
        sym, plain, f, shown = display(base, unit)
        return f"{sym} [{int(k) + 1}]", f"{plain} of curve {int(k) + 1}", f, shown
    p = FITTED.get(offset_name(name))
    if p is None:
        return name, name.replace("_", " "), 1.0, unit or ""
    k, shown = DISPLAY_UNITS.get(p.unit, (1.0, p.unit))
    return p.symbol, _PLAIN.get(p.name, p.description), k, shown


def finite(x: Any) -> bool:
    """Whether ``x`` is a finite real number (not a bool)."""
    return isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x)


def fmt(x: Any, digits: int = 4) -> str:
    """A number with ``digits`` significant digits; ``n/a`` for a missing one."""
    if not finite(x):
        return "n/a" if x is None or isinstance(x, (int, float)) else str(x)
    if isinstance(x, int) and not isinstance(x, bool):
        return str(x)
    return f"{x:.{digits}g}"


def status_text(d: Mapping[str, Any]) -> str:
    """The estimate's status: ``determined``, ``lower_bound``, ``upper_bound`` or ``undetermined``."""
    status = d.get("status")
    if status:
        return str(status)
    return "determined" if finite(d.get("value")) else "undetermined"


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
    if finite(lo) and finite(hi):
        return f"[{fmt(lo * k)}, {fmt(hi * k)}]{tail}"
    if finite(lo):
        return f"≥ {fmt(lo * k)}{tail}"
    if finite(hi):
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
        if bound == "n/a" and finite(d.get("value")):
            bound = ("≥ " if status == "lower_bound" else "≤ ") + f"{fmt(d['value'] * k)} {u}".strip()
        return f"{bound} ({status.replace('_', ' ')}{': ' + why if why else ''})"
    if status == "undetermined" or not finite(d.get("value")):
        return "not determined by these data" + (f" ({why})" if why else "")
    se = d.get("stderr")
    text = fmt(d["value"] * k)
    if finite(se):
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
    """(label, value, unit) of one scene field for display; ``∞ (flat)`` for a flat substrate."""
    label, unit = SCENE_FIELDS.get(key, (key.replace("_", " "), ""))
    if value is None:
        return label, "not set (fitted)" if key in ("mu_h", "work_of_adhesion") else "not set", ""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return label, str(value), ""
    if not math.isfinite(value):
        return label, "∞ (flat)" if key == "substrate_radius" else str(value), ""
    return label, fmt(value * _SCENE_FACTOR.get(unit, 1.0), 6), unit


def curve_label(file: Any) -> str:
    """A short name of a curve: ``folder/file.csv`` of a path, the text itself otherwise."""
    text = str(file)
    if text.startswith("<"):
        return text.strip("<>")
    p = Path(text)
    return f"{p.parent.name}/{p.name}" if p.parent.name else p.name
