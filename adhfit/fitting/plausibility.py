"""Data that are not what they seem: checks of a measured curve against its scene, before a fit.

Each finding is one plain sentence that names the column, the value (in the file's own unit) and the
likely fix.  What the fit can survive is a warning; what would make its numbers meaningless is an error.

* **Repeated rows** (an export that wrote every row twice): a row identical in every column to the
  row before it is left out of the fit, listed in :attr:`Curve.excluded` with the line it repeats, and
  named in a warning (lines compressed as ranges).  Counted twice, such rows would shrink every
  interval by √2 without adding information.
* **A load-cell zero far off** (warning): the rows before contact and after pull-off sit far from zero
  compared with the force range.  The fit can fit a force offset, but a zero this far off suggests an
  un-tared load cell or the wrong column read as force.
* **A reversed sign convention** (error): the control column falls before it rises (pressing in must be
  positive), or the force falls while loading (compressive must be positive); the sentence names the
  ``--displacement-sign`` / ``--force-sign`` options.
* **Units that make the test absurd** (error): a displacement range of many membrane radii (a column in
  furlong spans 116 km), a scene pressure that would need a membrane far stiffer than the forces allow,
  or forces larger than the pressure times the membrane's area could push.
"""
from __future__ import annotations

import dataclasses
import math
from typing import NamedTuple

import numpy as np

from ..errors import DataError

__all__ = ["Checked", "check_curve", "compress_lines", "DISPLACEMENT_SPAN", "FORCE_PER_DISPLACEMENT",
           "PRESSURE_AREA_MARGIN", "ZERO_FRACTION", "REVERSED_FRACTION"]

#: a displacement column spanning more than this many membrane radii b is not a membrane test (on
#: loading δ/b stays below 2, the parameter table's bound; unloading to pull-off adds at most a few b)
DISPLACEMENT_SPAN = 5.0
#: least dimensionless force per dimensionless displacement, f/(δ/b), at the end of loading; the model
#: gives 0.32-4.8 over p in [-0.9, 0.99], R_s/b in [0.05, inf], a_max/b in [0.05, 0.9] (larger with
#: larger contact); a 6x margin leaves room for contact radii down to ~1e-4 b
FORCE_PER_DISPLACEMENT = 0.05
#: under pressure control the force cannot exceed the largest pressure times π b² (the clamp's tension
#: pulls the other way); the sample curves reach 0.3-0.4 of it.  Allowed with this margin:
PRESSURE_AREA_MARGIN = 5.0
#: a load-cell zero beyond this fraction of the force range earns a warning (the fit's offset absorbs
#: a few per cent; tens of per cent mean a wrong tare or a wrong column)
ZERO_FRACTION = 0.2
#: a control value falling (or a force falling over loading) by more than this fraction of its range
#: before the end of loading is a reversed sign, not noise
REVERSED_FRACTION = 0.25

_UNITS = {"length": (("km", 1e3), ("m", 1.0), ("mm", 1e-3), ("um", 1e-6), ("nm", 1e-9)),
          "force": (("kN", 1e3), ("N", 1.0), ("mN", 1e-3), ("uN", 1e-6), ("nN", 1e-9)),
          "pressure": (("MPa", 1e6), ("kPa", 1e3), ("Pa", 1.0), ("mPa", 1e-3))}
_DIMENSION = {"displacement": "length", "force": "force", "pressure": "pressure"}


class Checked(NamedTuple):
    """The curve to fit (repeated rows left out) and the warnings found."""

    curve: object
    warnings: list[str]


def _si(value: float, dimension: str) -> str:
    """An SI value in a readable unit, e.g. ``116 km``, ``3.4 mN``."""
    for name, factor in _UNITS[dimension]:
        if abs(value) >= factor:
            return f"{value / factor:.3g} {name}"
    name, factor = _UNITS[dimension][-1]
    return f"{value / factor:.3g} {name}"


def _column(curve, name: str) -> str:
    unit = curve.units.get(name)
    return f"{name} [{unit}]" if unit else name


def _as_written(curve, name: str, value: float) -> str:
    """``value`` (SI) in the column's own unit, as the file writes it, e.g. ``5.8e+05 furlong``."""
    unit = curve.units.get(name)
    if not unit:
        return _si(value, _DIMENSION[name])
    from ..units import unit_factor  # noqa: PLC0415
    try:
        return f"{value / unit_factor(unit, _DIMENSION[name], name=name):.3g} {unit}"
    except (ValueError, ArithmeticError):
        return _si(value, _DIMENSION[name])


def compress_lines(lines) -> str:
    """Line numbers as ranges: ``[3, 5, 7, 9, 20]`` -> ``"3–9 (every 2nd line), 20"``."""
    v = sorted(int(n) for n in lines)
    out, i = [], 0
    while i < len(v):
        j = i
        if i + 1 < len(v):
            step = v[i + 1] - v[i]
            while j + 1 < len(v) and v[j + 1] - v[j] == step:
                j += 1
        if j - i >= 2:
            every = "" if step == 1 else f" (every {step}{'nd' if step == 2 else 'rd' if step == 3 else 'th'} line)"
            out.append(f"{v[i]}–{v[j]}{every}")
            i = j + 1
        else:
            out.append(str(v[i]))
            i += 1
    return ", ".join(out)


def _noise(force: np.ndarray) -> float:
    """Robust force noise σ from second differences (var Δ²F = 6σ² for white noise)."""
    d2 = np.diff(force, 2)
    return float(1.4826 * np.median(np.abs(d2 - np.median(d2))) / math.sqrt(6.0)) if d2.size else 0.0


def _without_repeats(curve) -> tuple[object, list[str]]:
    """Leave out rows identical in every column to the row before them."""
    cols = [a for a in (curve.x, curve.force, curve.time, curve.contact_radius) if a is not None]
    same = np.ones(len(curve.x) - 1, bool)
    for a in cols:
        same &= a[1:] == a[:-1]
    drop = np.flatnonzero(same) + 1
    if drop.size == 0:
        return curve, []
    keep = np.ones(len(curve.x), bool)
    keep[drop] = False
    excluded = list(curve.excluded) + [(int(curve.line[i]), f"repeats line {int(curve.line[i - 1])} "
                                                          "in every column") for i in drop]
    opt = {k: None if getattr(curve, k) is None else getattr(curve, k)[keep] for k in ("time", "contact_radius")}
    x = curve.x[keep]
    new = dataclasses.replace(curve, x=x, force=curve.force[keep], line=curve.line[keep], **opt,
                              i_turn=int(np.argmax(x)), excluded=tuple(sorted(excluded)))
    lines = compress_lines(curve.line[drop])
    what = f"line {lines} repeats the line before it" if drop.size == 1 else \
        f"lines {lines} repeat the line before them"
    return new, [f"{what} in every column ({drop.size} of {len(curve.x)} rows, as if the "
                 "export wrote rows twice): left out of the fit so that no measurement counts twice; "
                 "export the file again if the repeats are real readings"]


def _check_control_sign(curve) -> None:
    """The control column must rise while loading (pressing in / inflating is positive)."""
    x, i_turn = curve.x, curve.i_turn
    span = float(np.ptp(x))
    k = int(np.argmin(x[: i_turn + 1]))
    drop = float(x[0] - x[k])
    if span > 0 and drop > REVERSED_FRACTION * span:
        name = curve.control
        fix = ("if the instrument counts moving away from the substrate as positive, give "
               "--displacement-sign away-positive" if name == "displacement" else
               "check the sign of the pressure transducer (inflating must be positive)")
        raise DataError(f"the {name} falls by {_as_written(curve, name, drop)} from line {curve.line[0]} to line "
                        f"{curve.line[k]} before it rises, while loading must increase it ({'pressing in' if name == 'displacement' else 'inflating'} "
                        f"is positive); {fix}", path=curve.path, column=_column(curve, name))


def _baseline(curve, sigma: float) -> float | None:
    """Force of the rows before contact and after pull-off (median), ``None`` when there are none."""
    f, i_turn = curve.force, curve.i_turn
    tol = max(5.0 * sigma, 0.02 * float(np.ptp(f)))
    rows = []
    head = f[: i_turn + 1]
    n = _flat_run(head, tol)
    if n >= 3 and n < head.size:
        rows.append(head[:n])
    tail = f[i_turn:][::-1]
    n = _flat_run(tail, tol)
    if n >= 3 and n < tail.size:
        level = float(np.median(tail[:n]))
        before = tail[n:]
        if level - float(before.min()) > ZERO_FRACTION * float(np.ptp(f)):  # a pull-off jump up to it
            rows.append(tail[:n])
    return float(np.median(np.concatenate(rows))) if rows else None


def _flat_run(f: np.ndarray, tol: float) -> int:
    """Number of leading values within ``tol`` of the median of the first three."""
    ref = float(np.median(f[:3]))
    out = np.flatnonzero(np.abs(f - ref) > tol)
    return int(out[0]) if out.size else int(f.size)


def _check_force_sign(curve, base: float | None) -> None:
    """The force must rise while loading (compressive is positive)."""
    f, i = curve.force, curve.i_turn
    start = base if base is not None else float(np.median(f[:3]))
    rise = float(np.median(f[max(i - 1, 0): i + 2])) - start
    if rise < -REVERSED_FRACTION * float(np.ptp(f)):
        raise DataError(f"the force falls by {_as_written(curve, 'force', -rise)} while loading (from line "
                        f"{curve.line[0]} to line {curve.line[i]}), but pressing in must give a positive "
                        "(compressive) force; if the load cell counts tension as positive, give "
                        "--force-sign tensile-positive", path=curve.path, column=_column(curve, "force"))


def _check_displacement_span(curve, b: float) -> None:
    span = float(np.ptp(curve.x))
    if span > DISPLACEMENT_SPAN * b:
        col = _column(curve, "displacement")
        raise DataError(f"the displacements span {_si(span, 'length')} ({_as_written(curve, 'displacement', span)} "
                        f"as written), {span / b:.3g} times the membrane radius b = {_si(b, 'length')}, but a "
                        f"membrane test moves by at most a few b (under {_si(DISPLACEMENT_SPAN * b, 'length')} "
                        f"here): the unit in the header '{col}' is probably wrong (write the column's true "
                        "unit, or give --units displacement=UNIT), or the scene's membrane radius is",
                        path=curve.path, column=col)


def _loading(curve, base: float | None) -> tuple[float, float]:
    """Force rise over loading (N) and the control distance from first contact to the turn."""
    f, x, i = curve.force - (base or 0.0), curve.x, curve.i_turn
    f_load = float(f[i])
    touching = np.flatnonzero(f[: i + 1] <= 0.05 * f_load)
    k = int(touching[-1]) if touching.size else 0
    return f_load, float(x[i] - x[k])


def _check_scene_pressure(curve, scene, base: float | None) -> None:
    """Displacement control: |P b/(2μh)| < 1 needs μh > |P| b/2, and so stiff a membrane pushed by the
    loading displacement δ pushes back with at least ``FORCE_PER_DISPLACEMENT`` |P| b δ."""
    pressure, b = scene.pressure, scene.membrane_radius
    f_load, delta = _loading(curve, base)
    if not (pressure and f_load > 0 and delta > 0):
        return
    least = FORCE_PER_DISPLACEMENT * abs(pressure) * b * delta
    if least > f_load:
        largest = f_load / (FORCE_PER_DISPLACEMENT * b * delta)
        raise DataError(f"[test] pressure = {_si(pressure, 'pressure')} needs μh > |P|b/2 = "
                        f"{abs(pressure) * b / 2:.3g} N/m (|P b/2μh| < 1), and a membrane that stiff, pressed "
                        f"in by {_si(delta, 'length')}, pushes back with at least {_si(least, 'force')}, but "
                        f"the force column '{_column(curve, 'force')}' rises by only "
                        f"{_as_written(curve, 'force', f_load)}; for these data the pressure must be below "
                        f"about {_si(largest, 'pressure')}: the pressure's unit in the scene is probably wrong "
                        "(or the force column's)", path=scene.source or curve.path)


def _check_pressure_area(curve, scene, base: float | None) -> None:
    """Pressure control: the force cannot exceed the largest pressure times π b² by much."""
    b = scene.membrane_radius
    p_max = float(curve.x[curve.i_turn])
    f_load, _ = _loading(curve, base)
    if p_max <= 0 or f_load <= PRESSURE_AREA_MARGIN * p_max * math.pi * b * b:
        return
    cap = p_max * math.pi * b * b
    raise DataError(f"the force rises by {_as_written(curve, 'force', f_load)} ({_si(f_load, 'force')}), "
                    f"{f_load / cap:.3g} times what the largest pressure "
                    f"{_as_written(curve, 'pressure', p_max)} can push over the membrane's area π b² "
                    f"(b = {_si(b, 'length')}: at most {_si(cap, 'force')}): the unit in the force or the "
                    "pressure header is probably wrong (or the scene's membrane radius)",
                    path=curve.path, column=_column(curve, "force"))


def _zero_warning(curve, base: float | None) -> list[str]:
    span = float(np.ptp(curve.force))
    if base is None or span == 0 or abs(base) <= ZERO_FRACTION * span:
        return []
    return [f"the force column '{_column(curve, 'force')}' reads {_as_written(curve, 'force', base)} before "
            f"contact and after pull-off, {abs(base) / span:.0%} of the force range, instead of about 0: the "
            "load cell was probably not tared, or the column is not the contact force; check the tare "
            "and the column (the fitted force offset absorbs a small zero error, not a wrong column)"]


def check_curve(curve, scene) -> Checked:
    """Check a measured curve against its scene before a fit.

    Parameters
    ----------
    curve : adhfit.data.Curve
        The measured curve, in SI.
    scene : adhfit.scene.Scene
        Its scene (membrane radius, fixed pressure or gap).

    Returns
    -------
    Checked
        ``(curve, warnings)``: the curve to fit (rows that repeat the row before them in every column
        are left out and listed in ``Curve.excluded``) and a list of plain sentences.

    Raises
    ------
    DataError
        A reversed sign convention, or units that make the test absurd; the sentence names the column
        (or the scene key), its value in the file's unit, the plausible range and the likely fix.
    """
    curve, warnings = _without_repeats(curve)
    if curve.control == "displacement":
        _check_displacement_span(curve, scene.membrane_radius)
    _check_control_sign(curve)
    base = _baseline(curve, _noise(curve.force))
    _check_force_sign(curve, base)
    if curve.control == "displacement":
        _check_scene_pressure(curve, scene, base)
    else:
        _check_pressure_area(curve, scene, base)
    return Checked(curve, warnings + _zero_warning(curve, base))
