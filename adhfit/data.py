"""Measured force curves (docs/contracts.md A4, A4b) -> a read-only :class:`Curve` in SI units.

Clean files have ``name [unit]`` headers (any unit pint understands).  Files as instruments write
them are read too, without flags wherever they are unambiguous (:mod:`adhfit.readers`): metadata
lines above the header, units in ``[ ]``, ``( )`` or a units row, quoted cells, ``,`` ``;`` or tab
separators, decimal commas, a UTF-8 byte-order mark, LabVIEW ``.lvm`` files, and the usual column
names (``Load``, ``Extension``, ``Position``, ...).  Displacement control needs a displacement (a
length: δ up to an offset, pressing in positive) and a force (compressive positive); pressure
control needs a pressure and a force; time and contact radius are optional.  Rows are in measured
order: loading, then unloading, possibly past pull-off.

Nothing is dropped silently: blank, comment and metadata lines and a units row are listed in
:attr:`Curve.excluded`, unused columns in :attr:`Curve.ignored_columns`; any other row that cannot be
used is an error naming file, line and column.
"""
from __future__ import annotations

import csv
import hashlib
import io
from dataclasses import dataclass, field
from pathlib import Path
from types import MappingProxyType
from typing import Any, Mapping

import numpy as np
import pandas as pd

from .errors import DataError, InputError, shown
from .readers.columns import COLUMNS, OPTIONAL, REQUIRED, Assignment, check_overrides, split_cell
from .readers.formats import SNIFF_BYTES, find_format
from .readers.tables import locate
from .readers.text import Layout, read_bytes

__all__ = ["Curve", "Binning", "read_curve", "COLUMNS", "MIN_ROWS", "OPTIONAL", "REQUIRED"]

#: Fewest data rows a curve may have (loading and unloading both need several points).
MIN_ROWS = 10



def _readonly(a: Any, dtype: type = float) -> np.ndarray:
    arr = np.array(a, dtype=dtype, copy=True)
    arr.setflags(write=False)
    return arr


@dataclass(frozen=True, eq=False)
class Binning:
    """How a dense curve's rows were averaged in bins of consecutive rows before a fit
    (:func:`adhfit.fitting.segments.thin`): what the bins cannot say themselves.

    Attributes
    ----------
    rows : int
        Rows of the curve as read.
    size : ndarray of int
        Rows averaged in each bin.
    row : ndarray
        Mean row index (0-based, of the curve as read) of each bin: the basis of a drift in row order.
    x_max : float
        The largest control value of the rows as read (the loading end), m or Pa.
    i_jump : int or None
        The first bin after the pull-off jump (bins never straddle it), ``None`` without one.
    gap : tuple of float or None
        Control values of the last attached and the first detached row as read: where the data
        place the pull-off.
    """

    rows: int
    size: np.ndarray
    row: np.ndarray
    x_max: float
    i_jump: int | None = None
    gap: tuple[float, float] | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "size", _readonly(self.size, int))
        object.__setattr__(self, "row", _readonly(self.row))


@dataclass(frozen=True, eq=False)
class Curve:
    """One measured curve in SI units, rows in measured order.

    Attributes
    ----------
    path : str
        The curve file (a workbook's sheet is named in :attr:`layout`).
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
        Lines left out, with the reason: ``"blank line"``, ``"comment line"``, ``"metadata above the
        header"``, ``"units row"``, ``"LabVIEW header"``.
    sha256 : str
        Hash of the file's bytes, for reports.
    units : mapping
        Column name -> unit as written in the file (e.g. ``{"force": "mN"}``), for plots in the
        user's units.
    ignored_columns : tuple of (str, str)
        Header cells of the columns not used (temperature, cycle, ...), with the reason.
    columns : mapping
        Column name -> header cell as written in the file (e.g. ``{"force": "Load (N)"}``).
    layout : str
        How the file was read, for reports (e.g. ``"tab-separated, 7 metadata line(s), units row"``),
        with any sign override.
    binning : Binning or None
        Set when each row is the mean of several consecutive rows as read (a dense log thinned
        before a fit); ``line`` is then each bin's first line.

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
    ignored_columns: tuple[tuple[str, str], ...] = ()
    columns: Mapping[str, str] = field(default_factory=dict)
    layout: str = ""
    binning: Binning | None = None

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
        if self.binning is not None and self.binning.size.shape != (n,):
            raise InputError("binning", f"{self.binning.size.size} bins", f"one bin per row ({n})")
        set_(self, "excluded", tuple((int(a), str(b)) for a, b in self.excluded))
        set_(self, "units", MappingProxyType(dict(self.units)))
        set_(self, "ignored_columns", tuple((str(a), str(b)) for a, b in self.ignored_columns))
        set_(self, "columns", MappingProxyType(dict(self.columns)))

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


def read_curve(path: str | Path, control: str, *, columns: Mapping[str, str] | None = None,
               units: Mapping[str, str] | None = None, force_sign: str | None = None,
               displacement_sign: str | None = None, sheet: str | None = None) -> Curve:
    """Read a measured curve (docs/contracts.md A4, A4b).

    Parameters
    ----------
    path : str or Path
        A file of any format in :data:`adhfit.readers.FORMATS`: delimited text (``,`` ``;`` or tab,
        decimal point or comma, UTF-8 with or without BOM, UTF-16 with BOM, Latin-1), an instrument
        export with metadata and a units row, a LabVIEW measurement file or an Excel workbook.
    control : {"displacement", "pressure"}
        The test's control mode, which decides the required columns.
    columns : mapping, optional
        Column name -> header name, e.g. ``{"force": "Load 2"}``, where the names do not tell.
    units : mapping, optional
        Column name -> unit, e.g. ``{"displacement": "mm"}``; overrides the file's.
    force_sign : {"compressive-positive", "tensile-positive"}, optional
        The file's force sign convention (default compressive-positive, adhfit's).
    displacement_sign : {"into-substrate-positive", "away-positive"}, optional
        The file's displacement sign convention (default into-substrate-positive, adhfit's).
    sheet : str, optional
        A workbook's sheet holding the curve; by default the one sheet whose header has the columns
        ``control`` needs.

    Returns
    -------
    Curve
        Values converted to SI; lines left out listed in ``excluded``, unused columns in
        ``ignored_columns``.

    Raises
    ------
    DataError
        Naming the file and, where it applies, the line and column: unreadable or empty file, no
        header, a column without a unit, unknown, duplicate or missing column (with the columns found
        and expected, and the flag that settles it), unit of the wrong dimension, wrong number of
        cells, empty, non-numeric or non-finite cell, fewer than :data:`MIN_ROWS` rows, time running
        backwards, negative contact radius, no loading or no unloading stage.
    InputError
        For a bad ``control`` or override.
    """
    if control not in REQUIRED:
        raise InputError("control", control, "one of 'displacement', 'pressure'")
    check_overrides(control, columns, units, force_sign, displacement_sign)
    where = str(path)
    raw = read_bytes(path, where)
    fmt = find_format(path, raw[:SNIFF_BYTES])
    tables = fmt.tables(raw, where)
    source, layout, header, spec = locate(tables, fmt, control, sheet=sheet, columns=columns, units=units,
                                          where=where)
    lines = source.lines
    table = _table(lines, layout, header, spec, source.where)
    if len(layout.rows) < MIN_ROWS:
        raise DataError(f"only {len(layout.rows)} data rows; at least {MIN_ROWS} are needed (loading, then "
                        "unloading)", path=source.where)
    line_no = np.array(layout.rows, dtype=int)
    values = _values(table, spec, line_no, layout.decimal, source.where)
    signs = {"force": force_sign == "tensile-positive", control: displacement_sign == "away-positive"}
    values = {k: -v if signs.get(k) else v for k, v in values.items()}
    x = values[control]
    _check_physics(values, line_no, spec.header, control, source.where)
    signs_given = {"force sign": force_sign, "displacement sign": displacement_sign}
    notes = [layout.description, source.note, *spec.inferred.values(),
             *(f"{k} {v}" for k, v in signs_given.items() if v)]
    return Curve(path=where, control=control, x=x, force=values["force"], line=line_no,
                 i_turn=int(np.argmax(x)), time=values.get("time"),
                 contact_radius=values.get("contact_radius"), excluded=tuple(sorted(layout.excluded)),
                 sha256=hashlib.sha256(raw).hexdigest(), units=spec.units, ignored_columns=tuple(spec.ignored),
                 columns=spec.header, layout=", ".join(n for n in notes if n))


def _table(lines: list[str], layout: Layout, header: list[str], spec: Assignment, where: str) -> pd.DataFrame:
    """The data rows as strings, one per line in ``layout.rows``; a row of the wrong shape is an error.

    A row may be short only by trailing columns that are not used (e.g. LabVIEW's empty Comment).
    """
    n, sep = len(header), layout.sep
    need = max(spec.index.values()) + 1
    body = [sep.join(f'"{h}"' if sep in h else h for h in header)]
    for no in layout.rows:
        line = lines[no - 1]
        if line.count('"') % 2:  # a quoted cell spanning lines would shift every line number
            raise DataError("unbalanced quote (cells spanning several lines are not supported)",
                            path=where, line=no)
        cells = next(csv.reader([line], delimiter=sep), [])
        if len(cells) > n or len(cells) < need:
            role = {j: r for r, j in spec.index.items()}
            names = ", ".join(role.get(j) or split_cell(h)[0] or f"column {j + 1}" for j, h in enumerate(header))
            raise DataError(f"{len(cells)} cells, but the header has {n} columns ({names})", path=where, line=no)
        body.append(line + sep * (n - len(cells)))
    try:
        table = pd.read_csv(io.StringIO("\n".join(body)), sep=sep, dtype=str, keep_default_na=False,
                            na_filter=False, index_col=False, skip_blank_lines=False, header=0,
                            names=[f"c{j}" for j in range(n)])
    except (pd.errors.ParserError, ValueError) as exc:  # the checks above should leave none
        raise DataError(f"cannot parse the table ({exc})", path=where) from None
    if len(table) != len(layout.rows):
        raise DataError(f"read {len(table)} rows from {len(layout.rows)} data lines", path=where)
    return table


def _values(table: pd.DataFrame, spec: Assignment, line_no: np.ndarray, decimal: str, where: str
            ) -> dict[str, np.ndarray]:
    """The used columns as floats in SI; the first bad cell in file order is an error."""
    values, bad = {}, []
    for name, j in list(spec.index.items()):
        values[name], col_bad = _numbers(table.iloc[:, j], decimal)
        if name == "time" and col_bad.size:  # optional: a clock-time column is left out, not an error
            i = int(col_bad[0])
            spec.ignored.append((spec.header[name], f"time not a number (line {line_no[i]}: "
                                                    f"{shown(table.iloc[i, j])})"))
            for d in (values, spec.index, spec.header, spec.units, spec.factors):
                d.pop(name)
            continue
        bad += [(i, j, name) for i in col_bad]
    if bad:
        i, j, name = min(bad)
        more = f" ({len(bad) - 1} more bad cells in the file)" if len(bad) > 1 else ""
        raise DataError(_describe(table.iloc[i, j], decimal) + more, path=where, column=spec.header[name],
                        line=int(line_no[i]))
    return {name: v * spec.factors[name] for name, v in values.items()}

def _numbers(column: pd.Series, decimal: str = ".") -> tuple[np.ndarray, np.ndarray]:
    """Cells of one column as floats, and the row indices of cells that are not finite numbers."""
    cells = column.str.strip()
    if decimal == ",":  # a '.' in a decimal-comma file is a thousands mark or a typo: not a number
        cells = cells.where(~cells.str.contains(".", regex=False), "x").str.replace(",", ".", regex=False)
    values = pd.to_numeric(cells, errors="coerce").to_numpy(dtype=float)
    return values, np.flatnonzero(~np.isfinite(values))


def _describe(cell: str, decimal: str = ".") -> str:
    """Why a cell is not usable."""
    if not cell.strip():
        return "empty cell"
    if decimal == "," and "." in cell:
        return f"{shown(cell)} is not a number (this file writes decimal commas)"
    try:
        value = float(cell.replace(",", ".") if decimal == "," else cell)
    except ValueError:
        return f"{shown(cell)} is not a number" + (" (use a decimal point)" if "," in cell else "")
    if np.isfinite(value):
        return f"{shown(cell)} is not a plain decimal number"
    return f"{shown(cell)} is not a finite number (NaN and inf are not data)"


def _check_physics(values: dict[str, np.ndarray], line_no: np.ndarray, col: Mapping[str, str], control: str,
                   where: str) -> None:
    """Row-order checks: time runs forward, radii are not negative, loading and unloading exist."""
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
    hint = ("; if the file counts displacement away from the substrate as positive, give "
            "--displacement-sign away-positive") if control == "displacement" else ""
    if np.all(x[i_turn:] == x[i_turn]):
        raise DataError(f"no unloading: {largest} is not followed by any smaller value; rows must be "
                        f"loading, then unloading{hint}", path=where, column=col[control], line=int(line_no[-1]))
    if i_turn == 0:
        raise DataError(f"no loading: {largest} is the first row; rows must be loading, then unloading{hint}",
                        path=where, column=col[control], line=int(line_no[0]))
