"""Which table of a file holds the curve: the only one (a text file), or the one sheet of a workbook
whose header has the columns the test's control needs.

A workbook often holds a results summary beside the raw data, or one sheet per specimen.  Each
sheet's layout and header are tried; the curve is the one sheet where both succeed.  Several such
sheets, or none, is one line naming each sheet (and, for none, why it was passed over); ``sheet=``
chooses.
"""
from __future__ import annotations

from typing import Mapping

from ..errors import DataError, InputError, clip, shown
from .columns import Assignment, assign
from .formats import Format
from .text import Layout, Table, split_line

__all__ = ["locate"]


def _header(source: Table, fmt: Format, control: str, columns: Mapping[str, str] | None,
            units: Mapping[str, str] | None) -> tuple[Layout, list[str], Assignment]:
    """A table's layout, header cells and column assignment (any of them may raise DataError)."""
    lines = source.lines
    layout = fmt.layout(lines, source.where)
    header = split_line(lines[layout.header_no - 1], layout.sep)
    spec = assign(header, control, where=source.where, header_no=layout.header_no,
                  units_row=None if layout.units_no is None else split_line(lines[layout.units_no - 1], layout.sep),
                  units_no=layout.units_no, file_units=layout.units, time_columns=layout.time_columns,
                  columns=columns, units=units)
    return layout, header, spec


def locate(tables: list[Table], fmt: Format, control: str, *, sheet: str | None = None,
           columns: Mapping[str, str] | None = None, units: Mapping[str, str] | None = None, where: str = ""
           ) -> tuple[Table, Layout, list[str], Assignment]:
    """The one table (sheet) holding the curve, with its layout, header cells and column assignment.

    Parameters
    ----------
    tables : list of Table
        The file's tables (:attr:`Format.tables`): one for a text file, one per sheet of a workbook.
    fmt : Format
        The file's format (its ``layout`` finds each table's header).
    control : {"displacement", "pressure"}
        Decides the columns a table must have.
    sheet : str, optional
        The sheet to read; by default the only table whose header has the columns ``control`` needs.
    columns, units : mapping, optional
        Overrides, as for :func:`adhfit.data.read_curve`.
    where : str
        The file, for messages.

    Raises
    ------
    DataError
        The one table's own error; or, for several tables, one line naming the sheets when several or
        none have the columns (and why each has not).
    InputError
        ``sheet`` not a sheet's name, or given for a file without sheets.
    """
    if sheet is not None and (not isinstance(sheet, str) or not sheet):
        raise InputError("sheet", sheet, "a sheet's name (a non-empty string)")
    names = [t.sheet for t in tables if t.sheet is not None]
    if sheet is not None:
        if not names:
            raise InputError("sheet", sheet, "given for a workbook (.xlsx) only",
                             f"{clip(where)} is read as {fmt.name}, which has no sheets.")
        tables = [t for t in tables if t.sheet == sheet]
        if not tables:
            raise InputError("sheet", sheet, "one of " + ", ".join(shown(n, 40) for n in names),
                             f"{clip(where)} has no sheet of that name.")
    if len(tables) == 1:
        return (tables[0], *_header(tables[0], fmt, control, columns, units))
    found, failed = [], []
    for source in tables:
        try:
            found.append((source, *_header(source, fmt, control, columns, units)))
        except DataError as exc:
            reason = str(exc).removeprefix(source.where).lstrip(":, ")
            failed.append(f"sheet {shown(source.sheet, 40)}, {clip(reason, 160)}")
    if len(found) == 1:
        return found[0]
    if not found:
        raise DataError(f"no sheet holds the columns of a curve under {control} control ("
                        + "; ".join(failed[:4]) + (f"; and {len(failed) - 4} more sheets" if len(failed) > 4 else "")
                        + "); name the sheet with the curve (Python: read_curve(..., sheet=NAME)) to see its "
                        "error in full", path=where)
    both = ", ".join(shown(s.sheet, 40) for s, *_ in found[:6])
    both += f" and {len(found) - 6} more" if len(found) > 6 else ""
    raise DataError(f"{len(found)} sheets hold the columns of a curve ({both}); adhfit reads one curve per "
                    "file: choose one with sheet=NAME (Python: read_curve(..., sheet=...)), or save each sheet "
                    "to its own file", path=where)
