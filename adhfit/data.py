"""Measured force curves: CSV (DESIGN.md A4) -> a read-only :class:`Curve` in SI units.

Headers are ``name [unit]`` with any unit pint understands.  Displacement control needs
``displacement`` (a length: δ up to an offset, pressing in positive) and ``force`` (compressive
positive); pressure control needs ``pressure`` and ``force``; ``time`` and ``contact_radius`` are
optional.  Rows are in measured order: loading, then unloading, possibly past pull-off.

Nothing is dropped silently: blank and ``#`` comment lines are skipped and listed in
:attr:`Curve.excluded`; any other row that cannot be used is an error naming file, line and column.
"""
from __future__ import annotations

import csv
import difflib
import hashlib
import io
import re
from dataclasses import dataclass, field
from pathlib import Path
from types import MappingProxyType
from typing import Any, Mapping

import numpy as np
import pandas as pd

from .errors import DataError, InputError
from .units import DIMENSIONS, unit_factor

__all__ = ["Curve", "read_curve", "COLUMNS", "MIN_ROWS"]

#: Known columns -> physical dimension (a key of adhfit.units.DIMENSIONS).
COLUMNS: dict[str, str] = {"displacement": "length", "pressure": "pressure", "force": "force",
                           "time": "time", "contact_radius": "length"}
#: Columns each control mode needs; ``time`` and ``contact_radius`` are optional for both.
REQUIRED = {"displacement": ("displacement", "force"), "pressure": ("pressure", "force")}
OPTIONAL = ("time", "contact_radius")
_EXAMPLE = {"displacement": "displacement [um]", "pressure": "pressure [kPa]", "force": "force [mN]",
            "time": "time [s]", "contact_radius": "contact_radius [um]"}
#: Fewest data rows a curve may have (loading and unloading both need several points).
MIN_ROWS = 10

_HEADER = re.compile(r"^\s*([^\[\]]*?)\s*\[\s*([^\[\]]+?)\s*\]\s*$")


def _readonly(a: Any, dtype: type = float) -> np.ndarray:
    arr = np.array(a, dtype=dtype, copy=True)
    arr.setflags(write=False)
    return arr


@dataclass(frozen=True, eq=False)
class Curve:
    """One measured curve in SI units, rows in measured order.

    Attributes
    ----------
    path : str
        The CSV file.
    control : {"displacement", "pressure"}
        Which variable the test drives.
    x : ndarray
        The control variable: displacement δ (m, up to an offset, pressing in positive) or pressure
        (Pa).  Also available as :attr:`displacement` or :attr:`pressure`.
    force : ndarray
        Force, N, compressive positive.
    time : ndarray or None
        Time, s.
    contact_radius : ndarray or None
        Contact radius, m.
    line : ndarray of int
        1-based line of each row in the file (the header is line 1 unless comments precede it).
    i_turn : int
        Row index of the end of loading: the first occurrence of the largest control value, found
        by row order (never by value ranges: rows either side of a pull-off jump may share a value).
    excluded : tuple of (int, str)
        Lines left out, with the reason (blank lines, comment lines).
    sha256 : str
        Hash of the file's bytes, for reports.
    units : mapping
        Column name -> unit as written in the file (e.g. ``{"force": "mN"}``), for plots in the
        user's units.

    All arrays are read-only copies of equal length.
    """

    path: str
    control: str
    x: np.ndarray
    force: np.ndarray
    line: np.ndarray
    i_turn: int
    time: np.ndarray | None = None
    contact_radius: np.ndarray | None = None
    excluded: tuple[tuple[int, str], ...] = ()
    sha256: str = ""
    units: Mapping[str, str] = field(default_factory=dict)

    def __post_init__(self) -> None:
        set_ = object.__setattr__
        if self.control not in REQUIRED:
            raise InputError("control", self.control, "one of 'displacement', 'pressure'")
        for key in ("x", "force", "time", "contact_radius"):
            if getattr(self, key) is not None:
                set_(self, key, _readonly(getattr(self, key)))
        set_(self, "line", _readonly(self.line, int))
        n = len(self.x)
        for key in ("force", "line", "time", "contact_radius"):
            a = getattr(self, key)
            if a is not None and a.shape != (n,):
                raise InputError(key, f"array of shape {a.shape}", f"a 1-D array of length {n} (as x)")
        if not (isinstance(self.i_turn, (int, np.integer)) and 0 <= self.i_turn < n):
            raise InputError("i_turn", self.i_turn, f"a row index in [0, {n})")
        set_(self, "i_turn", int(self.i_turn))
        set_(self, "excluded", tuple((int(a), str(b)) for a, b in self.excluded))
        set_(self, "units", MappingProxyType(dict(self.units)))

    def __len__(self) -> int:
        return len(self.x)

    def __repr__(self) -> str:
        return (f"Curve(path={self.path!r}, control={self.control!r}, rows={len(self)}, "
                f"i_turn={self.i_turn}, excluded={len(self.excluded)}, columns={list(self.units)})")

    @property
    def displacement(self) -> np.ndarray | None:
        """Displacement δ (m) under displacement control, else ``None``."""
        return self.x if self.control == "displacement" else None

    @property
    def pressure(self) -> np.ndarray | None:
        """Pressure (Pa) under pressure control, else ``None``."""
        return self.x if self.control == "pressure" else None

    @property
    def loading(self) -> slice:
        """Rows of the loading stage, the turning row included."""
        return slice(0, self.i_turn + 1)

    @property
    def unloading(self) -> slice:
        """Rows of the unloading stage, from the turning row on."""
        return slice(self.i_turn, None)

    def to_frame(self) -> pd.DataFrame:
        """The curve as a DataFrame in SI: ``line``, ``<control> [m|Pa]``, ``force [N]``, optional
        ``time [s]``, ``contact_radius [m]``, and ``loading`` (True up to and including ``i_turn``)."""
        cols: dict[str, Any] = {"line": self.line,
                                f"{self.control} [{'m' if self.control == 'displacement' else 'Pa'}]": self.x,
                                "force [N]": self.force}
        if self.time is not None:
            cols["time [s]"] = self.time
        if self.contact_radius is not None:
            cols["contact_radius [m]"] = self.contact_radius
        cols["loading"] = np.arange(len(self)) <= self.i_turn
        return pd.DataFrame(cols)


def read_curve(path: str | Path, control: str) -> Curve:
    """Read a measured curve (CSV, DESIGN.md A4).

    Parameters
    ----------
    path : str or Path
        CSV file; separator ``,`` (``;`` or tab also recognised from the header line); UTF-8.
    control : {"displacement", "pressure"}
        The test's control mode, which decides the required columns.

    Returns
    -------
    Curve
        Values converted to SI; blank and comment lines listed in ``excluded``.

    Raises
    ------
    DataError
        Naming the file and, where it applies, the line and column: unreadable or empty file,
        header without ``[unit]``, unknown, duplicate or missing column (with the columns found and
        expected), unit of the wrong dimension, wrong number of cells, empty, non-numeric or
        non-finite cell, fewer than :data:`MIN_ROWS` rows, time running backwards, negative contact
        radius, no loading or no unloading stage.
    """
    if control not in REQUIRED:
        raise InputError("control", control, "one of 'displacement', 'pressure'")
    where = str(path)
    raw, lines = _read_lines(path, where)
    header_no, rows, excluded = _classify(lines, where)
    header = lines[header_no - 1]
    sep = next((s for s in (",", ";", "\t") if s in header), ",")
    names, factors, units = _parse_header(header, sep, control, where, header_no)
    table = _table(lines, header, rows, sep, names, where)
    if len(rows) < MIN_ROWS:
        raise DataError(f"only {len(rows)} data rows; at least {MIN_ROWS} are needed (loading, then "
                        "unloading)", path=where)

    line_no = np.array(rows, dtype=int)
    headers = _cells(header, sep)
    values, bad = {}, []
    for j, name in enumerate(names):
        values[name], col_bad = _numbers(table.iloc[:, j])
        bad += [(i, j, table.iloc[i, j]) for i in col_bad]
    if bad:
        i, j, cell = min(bad)
        more = f" ({len(bad) - 1} more bad cells in the file)" if len(bad) > 1 else ""
        raise DataError(_describe(cell) + more, path=where, column=headers[j], line=int(line_no[i]))
    values = {name: v * factors[name] for name, v in values.items()}
    x = values[control]
    _check_physics(values, line_no, headers, names, control, where)
    return Curve(path=where, control=control, x=x, force=values["force"], line=line_no,
                 i_turn=int(np.argmax(x)), time=values.get("time"),
                 contact_radius=values.get("contact_radius"), excluded=tuple(excluded),
                 sha256=hashlib.sha256(raw).hexdigest(), units=units)


def _read_lines(path: str | Path, where: str) -> tuple[bytes, list[str]]:
    """The file's bytes and its lines (any line ending; line n is ``lines[n - 1]``)."""
    try:
        raw = Path(path).read_bytes()
    except OSError as exc:
        raise DataError(f"cannot read the file ({exc.strerror or exc})", path=where) from None
    if not raw.strip():
        raise DataError("the file is empty", path=where)
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError:
        text = raw.decode("latin-1")  # every byte maps: a non-UTF-8 'µ' must not stop a read
    lines = text.replace("\r\n", "\n").replace("\r", "\n").split("\n")
    if lines and lines[-1] == "":
        lines.pop()
    return raw, lines


def _classify(lines: list[str], where: str) -> tuple[int, list[int], list[tuple[int, str]]]:
    """Header line number, data line numbers, and the (line, reason) of blank and comment lines."""
    excluded: list[tuple[int, str]] = []
    header_no, rows = None, []
    for no, line in enumerate(lines, start=1):
        stripped = line.strip()
        if not stripped or stripped.startswith("#"):
            excluded.append((no, "blank line" if not stripped else "comment line"))
        elif header_no is None:
            header_no = no
        else:
            rows.append(no)
    if header_no is None:
        raise DataError("the file has no header line (only blank or comment lines)", path=where)
    return header_no, rows, excluded


def _table(lines: list[str], header: str, rows: list[int], sep: str, names: list[str], where: str
           ) -> pd.DataFrame:
    """The data rows as strings, one per line in ``rows``; a row of the wrong shape is an error."""
    for no in rows:
        if lines[no - 1].count('"') % 2:  # a quoted cell spanning lines would shift every line number
            raise DataError("unbalanced quote (cells spanning several lines are not supported)",
                            path=where, line=no)
        cells = next(csv.reader([lines[no - 1]], delimiter=sep))
        if len(cells) != len(names):
            raise DataError(f"{len(cells)} cells, but the header has {len(names)} columns "
                            f"({', '.join(names)})", path=where, line=no)
    body = "\n".join([header] + [lines[no - 1] for no in rows])
    try:
        table = pd.read_csv(io.StringIO(body), sep=sep, dtype=str, keep_default_na=False, na_filter=False,
                            index_col=False, skip_blank_lines=False)
    except (pd.errors.ParserError, ValueError) as exc:  # the checks above should leave none
        raise DataError(f"cannot parse the table ({exc})", path=where) from None
    if len(table) != len(rows):
        raise DataError(f"read {len(table)} rows from {len(rows)} data lines", path=where)
    return table


def _cells(line: str, sep: str) -> list[str]:
    return [c.strip() for c in next(csv.reader([line], delimiter=sep))]


def _parse_header(header: str, sep: str, control: str, where: str, no: int
                  ) -> tuple[list[str], dict[str, float], dict[str, str]]:
    """Column names, SI factors and units from the header line; every header problem is an error."""
    cells = _cells(header, sep)
    expected = [_EXAMPLE[n] for n in REQUIRED[control]]
    optional = [_EXAMPLE[n] for n in OPTIONAL]
    tail = (f"found {', '.join(repr(c) for c in cells)}; expected {', '.join(map(repr, expected))} "
            f"(optional: {', '.join(map(repr, optional))})")
    names: list[str] = []
    factors: dict[str, float] = {}
    units: dict[str, str] = {}
    for cell in cells:
        m = _HEADER.match(cell)
        if m is None or not m.group(1):
            raise DataError(f"bad header '{cell}': columns must be written 'name [unit]', e.g. 'force [mN]'",
                            path=where, column=cell, line=no)
        name, unit = m.group(1).lower(), m.group(2)
        usable = [*REQUIRED[control], *OPTIONAL]
        if name not in usable:
            other = "" if name not in COLUMNS else f" (it belongs to control = '{name}', not '{control}')"
            close = difflib.get_close_matches(name, usable, n=1, cutoff=0.6)
            hint = f" did you mean '{close[0]}'?" if close else ""
            raise DataError(f"unknown column{other};{hint} {tail}", path=where, column=cell, line=no)
        if name in names:
            raise DataError(f"duplicate column '{name}'; {tail}", path=where, column=cell, line=no)
        try:
            factors[name] = unit_factor(unit, COLUMNS[name], name=cell)
        except InputError as exc:
            raise DataError(exc.reason, path=where, column=cell, line=no) from None
        names.append(name)
        units[name] = unit
    for name in REQUIRED[control]:
        if name not in names:
            noun = DIMENSIONS[COLUMNS[name]][1].split(" ", 1)[1]
            raise DataError(f"missing column '{_EXAMPLE[name]}' (any {noun} unit) for control = '{control}'; "
                            f"{tail}", path=where, line=no)
    return names, factors, units


def _numbers(column: pd.Series) -> tuple[np.ndarray, np.ndarray]:
    """Cells of one column as floats, and the row indices of cells that are not finite numbers."""
    values = pd.to_numeric(column.str.strip(), errors="coerce").to_numpy(dtype=float)
    return values, np.flatnonzero(~np.isfinite(values))


def _describe(cell: str) -> str:
    """Why a cell is not usable."""
    if not cell.strip():
        return "empty cell"
    try:
        value = float(cell)
    except ValueError:
        return f"{cell!r} is not a number" + (" (use a decimal point)" if "," in cell else "")
    if np.isfinite(value):
        return f"{cell!r} is not a plain decimal number"
    return f"{cell!r} is not a finite number (NaN and inf are not data)"


def _check_physics(values: dict[str, np.ndarray], line_no: np.ndarray, headers: list[str], names: list[str],
                   control: str, where: str) -> None:
    """Row-order checks: time runs forward, radii are not negative, loading and unloading exist."""
    col = dict(zip(names, headers))
    if "time" in values:
        back = np.flatnonzero(np.diff(values["time"]) < 0)
        if back.size:
            i = back[0] + 1
            raise DataError("time runs backwards here: rows must be in measured order",
                            path=where, column=col["time"], line=int(line_no[i]))
    if "contact_radius" in values and (values["contact_radius"] < 0).any():
        i = int(np.flatnonzero(values["contact_radius"] < 0)[0])
        raise DataError("negative contact radius", path=where, column=col["contact_radius"],
                        line=int(line_no[i]))
    x = values[control]
    i_turn = int(np.argmax(x))
    largest = f"the largest {control} (line {line_no[i_turn]})"
    if np.all(x[i_turn:] == x[i_turn]):
        raise DataError(f"no unloading: {largest} is not followed by any smaller value; rows must be "
                        "loading, then unloading", path=where, column=col[control], line=int(line_no[-1]))
    if i_turn == 0:
        raise DataError(f"no loading: {largest} is the first row; rows must be loading, then unloading",
                        path=where, column=col[control], line=int(line_no[0]))
