"""Header cells -> adhfit's columns: names and aliases, units, overrides, and ambiguity errors.

A header cell is ``name [unit]``, ``name (unit)`` or a bare ``name`` (its unit then comes from a
units row, from LabVIEW's ``Y_Unit_Label`` or from an override).  Names are compared without case,
``_``/``-`` or a leading ``Axial``; the usual instrument names are aliases (:data:`ALIASES`).
Columns adhfit does not use are ignored and listed.  What stays ambiguous (two columns for one
quantity, no unit anywhere, no column for a required quantity) is one error line naming the file,
the choices and the flag that settles it.
"""
from __future__ import annotations

import difflib
import re
from dataclasses import dataclass, field
from typing import Mapping

from ..errors import DataError, InputError, clip, shown
from ..units import DIMENSIONS, unit_factor

__all__ = ["ALIASES", "COLUMNS", "REQUIRED", "OPTIONAL", "EXAMPLE", "Assignment", "assign", "role_of",
           "split_cell", "check_overrides"]

#: Known columns -> physical dimension (a key of adhfit.units.DIMENSIONS).
COLUMNS: dict[str, str] = {"displacement": "length", "pressure": "pressure", "force": "force",
                           "time": "time", "contact_radius": "length"}
#: Columns each control mode needs; ``time`` and ``contact_radius`` are optional for both.
REQUIRED = {"displacement": ("displacement", "force"), "pressure": ("pressure", "force")}
OPTIONAL = ("time", "contact_radius")
EXAMPLE = {"displacement": "displacement [um]", "pressure": "pressure [kPa]", "force": "force [mN]",
           "time": "time [s]", "contact_radius": "contact_radius [um]"}
#: Header names (compared in lower case, ``_``/``-`` as spaces, without a leading "axial" or
#: "compressive") per column.
ALIASES: dict[str, tuple[str, ...]] = {
    "force": ("force", "load", "standard force", "kraft", "standardkraft"),
    "displacement": ("displacement", "extension", "position", "crosshead", "deflection",
                     "crosshead position", "crosshead displacement", "weg", "standardweg", "traversenweg"),
    "pressure": ("pressure", "druck"),
    "time": ("time", "test time", "running time", "elapsed time", "total time", "zeit", "testzeit"),
    "contact_radius": ("contact radius",),
}
_PREFIXES = ("axial ", "compressive ")
#: LabVIEW's names for channels nobody named: their quantity is read from Y_Unit_Label's units.
_GENERIC = re.compile(r"^(untitled( \d+)?|voltage( \d+)?|(dev\d+/)?ai\d+|channel ?\d*)$")
_ROLE = {alias: role for role, names in ALIASES.items() for alias in names}
_CELL = re.compile(r"^(.*?)\s*[\[(]\s*([^\[\]()]*?)\s*[\])]\s*$")


def split_cell(cell: str) -> tuple[str, str | None]:
    """``'Load (N)'`` -> ``('Load', 'N')``; ``'Load'`` -> ``('Load', None)``; ``'(mm)'`` -> ``('', 'mm')``."""
    m = _CELL.match(cell.strip())
    if m is None:
        return cell.strip(), None
    return m.group(1).strip(), (m.group(2).strip() or None)


def normalise(name: str) -> str:
    """Lower case, ``_``/``-`` as spaces, single spaces, no leading ``axial``."""
    text = " ".join(re.sub(r"[_\-]", " ", name).lower().split())
    for prefix in _PREFIXES:
        text = text[len(prefix):] if text.startswith(prefix) else text
    return text


def role_of(name: str) -> str | None:
    """The adhfit column a header name stands for, or ``None``."""
    return _ROLE.get(normalise(name))


def _unit_cell(cell: str) -> str | None:
    """A units-row cell without its brackets; ``None`` when empty."""
    text = cell.strip()
    if len(text) >= 2 and text[0] + text[-1] in ("()", "[]"):
        text = text[1:-1].strip()
    return text or None


SIGNS = {"force_sign": ("compressive-positive", "tensile-positive"),
         "displacement_sign": ("into-substrate-positive", "away-positive")}


def check_overrides(control: str, columns: Mapping[str, str] | None, units: Mapping[str, str] | None,
                    force_sign: str | None, displacement_sign: str | None) -> None:
    """Raise :class:`InputError` for override keys or values that can never be valid."""
    usable = (*REQUIRED[control], *OPTIONAL)
    for name, given in (("columns", columns), ("units", units)):
        for key, value in (given or {}).items():
            if key not in usable:
                raise InputError(name, {key: value}, f"keys among {', '.join(map(repr, usable))} "
                                                     f"(under {control} control)")
            if not isinstance(value, str) or not value.strip():
                raise InputError(name, {key: value}, f"a non-empty {'column name' if name == 'columns' else 'unit'}")
    for name, value in (("force_sign", force_sign), ("displacement_sign", displacement_sign)):
        if value is not None and value not in SIGNS[name]:
            raise InputError(name, value, "one of " + ", ".join(map(repr, SIGNS[name])))
    if displacement_sign is not None and control != "displacement":
        raise InputError("displacement_sign", displacement_sign, "given under displacement control only",
                         f"This curve is under {control} control.")


@dataclass
class Assignment:
    """Which header column is which adhfit column, in what unit.

    Attributes
    ----------
    index : dict
        adhfit column -> 0-based column index in the file.
    header : dict
        adhfit column -> header cell as written.
    units : dict
        adhfit column -> unit (as written, or as overridden).
    factors : dict
        adhfit column -> factor to SI.
    ignored : list of (str, str)
        Header cells not used, with the reason.
    inferred : dict
        adhfit column -> how it was found from its unit (a generic LabVIEW channel name).
    """

    index: dict[str, int] = field(default_factory=dict)
    header: dict[str, str] = field(default_factory=dict)
    units: dict[str, str] = field(default_factory=dict)
    factors: dict[str, float] = field(default_factory=dict)
    ignored: list[tuple[str, str]] = field(default_factory=list)
    inferred: dict[str, str] = field(default_factory=dict)


#: Header cells listed in a message at most (a 5,000-column header is summarised, not printed).
_LISTED = 12


def listed(cells: list[str]) -> str:
    """Header cells for a message: each cut (:func:`adhfit.errors.shown`), at most ``_LISTED`` of them."""
    out = ", ".join(shown(c, 40) for c in cells[:_LISTED])
    return out + (f", and {len(cells) - _LISTED} more" if len(cells) > _LISTED else "")


def _tail(cells: list[str], control: str) -> str:
    expected = ", ".join(repr(EXAMPLE[n]) for n in REQUIRED[control])
    optional = ", ".join(repr(EXAMPLE[n]) for n in OPTIONAL)
    return f"found {listed(cells)}; expected {expected} (optional: {optional})"


def _find(role: str, name: str, cells: list[str], where: str, no: int) -> int:
    """The column ``--columns role=name`` names (by its name, without unit, or the whole cell)."""
    hits = [j for j, c in enumerate(cells)
            if c.strip() == name.strip() or normalise(split_cell(c)[0]) == normalise(name)]
    if len(hits) == 1:
        return hits[0]
    what = "no column" if not hits else f"{len(hits)} columns"
    raise DataError(f"--columns {role}={clip(name)}: {what} of that name; the columns are {listed(cells)}",
                    path=where, line=no)


def assign(cells: list[str], control: str, *, where: str, header_no: int, units_row: list[str] | None = None,
           units_no: int | None = None, file_units: list[str | None] | None = None,
           time_columns: tuple[str, ...] = (), columns: Mapping[str, str] | None = None,
           units: Mapping[str, str] | None = None) -> Assignment:
    """Map the header's cells to adhfit's columns; see the module docstring for the rules."""
    forced = {role: _find(role, name, cells, where, header_no) for role, name in (columns or {}).items()}
    by_index = {j: role for role, j in forced.items()}
    if len(by_index) < len(forced):
        raise DataError("--columns names one column for two quantities: "
                        + ", ".join(f"{r}={(columns or {})[r]}" for r in forced), path=where, line=header_no)
    usable = (*REQUIRED[control], *OPTIONAL)
    out, chosen, other, generic = Assignment(), {}, [], []
    for j, cell in enumerate(cells):
        name = split_cell(cell)[0]
        from_x = j not in by_index and not role_of(name) and name in time_columns
        role = by_index.get(j) or role_of(name) or ("time" if from_x else None)
        if j not in by_index and role in forced:
            out.ignored.append((cell, f"another {role} column (--columns {role}= chose "
                                      f"'{clip(cells[forced[role]])}')"))
        elif from_x and "time" in chosen:
            out.ignored.append((cell, "another X_Value column (the first one is time)"))
        elif role is None:
            out.ignored.append((cell or f"column {j + 1}", "not a column adhfit reads" if name else "no name"))
            generic += [j] if _GENERIC.match(normalise(name)) else []
        elif role not in usable:
            out.ignored.append((cell, f"a {role} column, not used under {control} control"))
            other.append(j)
        else:
            chosen.setdefault(role, []).append(j)
    raw = {j: _raw_unit(j, cells, units_row, file_units)[0] for j in generic}
    for role, j in _by_unit(chosen, generic, raw, control, cells, where, header_no).items():
        chosen[role] = [j]
        out.ignored.remove((cells[j], "not a column adhfit reads"))
        out.inferred[role] = f"'{cells[j]}' read as {role} from its unit {raw[j]}"
    for role, js in chosen.items():
        if len(js) > 1:
            names = " and ".join(shown(cells[j], 40) for j in js)
            raise DataError(f"duplicate column '{role}': {names} both read as {role}; choose one with "
                            f"--columns {role}=NAME", path=where, column=cells[js[1]], line=header_no)
    _missing(cells, chosen, other, control, where, header_no, out.ignored)
    for role, (j,) in chosen.items():
        _unit(out, role, j, cells, units_row, units_no, file_units, units, where, header_no)
    for role in units or {}:
        if role not in out.index:
            raise DataError(f"--units {role}={clip(units[role])}: the file has no {role} column; "
                            f"{_tail(cells, control)}", path=where, line=header_no)
    return out


def _missing(cells: list[str], chosen: dict, other: list[int], control: str, where: str, no: int,
             ignored: list[tuple[str, str]]) -> None:
    """Raise for the first required column not found, with the closest candidate when there is one."""
    for role in REQUIRED[control]:
        if role in chosen:
            continue
        tail = _tail(cells, control)
        for j in other:
            owner = role_of(split_cell(cells[j])[0])
            raise DataError(f"unknown column (it belongs to control = '{owner}', not '{control}'); {tail}",
                            path=where, column=cells[j], line=no)
        unused = [c for c, why in ignored if why == "not a column adhfit reads"]
        for cell in unused:
            close = difflib.get_close_matches(normalise(split_cell(cell)[0]), [role, *ALIASES[role]], n=1,
                                              cutoff=0.6)
            if close:
                raise DataError(f"unknown column; did you mean '{role}'? {tail}; or name it with "
                                f"--columns {role}=NAME", path=where, column=cell, line=no)
        noun = DIMENSIONS[COLUMNS[role]][1].split(" ", 1)[1]
        aliases = ", ".join(a.title() for a in ALIASES[role][1:])
        also = f"; also read as {role}: {aliases}" if aliases else ""
        raise DataError(f"missing column '{EXAMPLE[role]}' (any {noun} unit) for control = '{control}'; "
                        f"{tail}{also}; or name it with --columns {role}=NAME", path=where, line=no)


def _unit(out: Assignment, role: str, j: int, cells: list[str], units_row: list[str] | None,
          units_no: int | None, file_units: list[str | None] | None, units: Mapping[str, str] | None,
          where: str, no: int) -> None:
    """Record column ``j`` as ``role`` with its unit: override, header, units row, then file header."""
    cell = cells[j]
    unit, from_row = _raw_unit(j, cells, units_row, file_units)
    line = units_no if from_row else no
    if units and role in units:
        out.factors[role] = unit_factor(units[role], COLUMNS[role], name=f"units {role}")
        unit = units[role]
    elif unit is None:
        if role == "time":
            out.ignored.append((cell, "time without a unit (give it with --units time=s)"))
            return
        example = EXAMPLE[role]
        raise DataError(f"bad header '{clip(cell)}': columns must be written 'name [unit]', e.g. '{example}', "
                        f"or have a units row under the header; or give the unit with --units "
                        f"{role}={split_cell(example)[1]}", path=where, column=cell, line=no)
    else:
        try:
            out.factors[role] = unit_factor(unit, COLUMNS[role], name=cell)
        except InputError as exc:
            if role == "time":  # optional: a clock time ('hh:mm:ss') is left out and listed
                out.ignored.append((cell, f"time in {shown(unit)}, not a unit of time"))
                return
            raise DataError(exc.reason, path=where, column=cell, line=line) from None
    out.index[role], out.header[role], out.units[role] = j, cell, unit


def _raw_unit(j: int, cells: list[str], units_row: list[str] | None, file_units: list[str | None] | None
              ) -> tuple[str | None, bool]:
    """Column ``j``'s unit from the header cell, else the units row (flag True), else the file header."""
    unit = split_cell(cells[j])[1]
    if unit is None and units_row is not None and j < len(units_row) and _unit_cell(units_row[j]):
        return _unit_cell(units_row[j]), True
    if unit is None and file_units is not None and j < len(file_units):
        unit = file_units[j]
    return unit, False


def _by_unit(chosen: dict, generic: list[int], raw: dict[int, str | None], control: str, cells: list[str],
             where: str, no: int) -> dict[str, int]:
    """Required columns found among generically named channels (``Untitled``) by their unit alone."""
    found = {}
    for role in REQUIRED[control]:
        if role in chosen:
            continue
        fits = []
        for j in generic:
            try:
                unit_factor(raw[j] or "", COLUMNS[role], name=cells[j])
                fits.append(j)
            except InputError:
                pass
        if len(fits) > 1:
            names = " and ".join(shown(cells[j], 40) for j in fits)
            raise DataError(f"{names} both have {DIMENSIONS[COLUMNS[role]][1]} unit, so either could be the "
                            f"{role}; choose one with --columns {role}=NAME", path=where, line=no)
        if fits:
            found[role] = fits[0]
    return found
