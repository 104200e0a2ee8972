"""Excel workbooks (``.xlsx``, ``.xlsm``): each sheet as a table of text lines.

Testing software (Instron Bluehill, ZwickRoell testXpert, ...) saves results as workbooks laid out
like its CSV exports: metadata rows above the header, units in the header cells or in a units row
under it.  Each sheet is read with openpyxl (read-only, the cached values of formulas; pandas'
``read_excel`` would turn an error cell such as ``#DIV/0!`` into an empty one) and written as
tab-separated lines, one per sheet row, so row ``n`` of the sheet is line ``n`` in every
message, and the text layout rules (:mod:`.text`) then find its header, units row and data.  Cells
that are numbers are written exactly (``repr`` of the float); text cells keep their text, with
line breaks inside a cell made spaces.  Which sheet holds the curve is decided by
:func:`adhfit.data.read_curve` (the one sheet whose columns fit the test's control).
"""
from __future__ import annotations

import csv
import datetime as dt
import io
import math
import zipfile
from typing import Any

from ..errors import DataError, clip, shown
from .text import Table, check_line_lengths

__all__ = ["workbook_tables", "SHEET_SEPARATORS", "MAX_UNZIPPED_BYTES"]

#: A sheet's rows are written tab-separated; only tab is tried when finding their layout.
SHEET_SEPARATORS = ("\t",)
#: Largest workbook content (uncompressed) read: ~10 times a 10^6-row, three-column sheet.  A zip
#: that unpacks to more is refused before it is parsed (a 'zip bomb' must not fill the memory).
MAX_UNZIPPED_BYTES = 2 * 1024**3


def _cell(value: Any) -> str:
    """One cell as text: numbers exactly, empty cells empty, line breaks in text as spaces."""
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return ""
    if isinstance(value, bool):
        return "TRUE" if value else "FALSE"
    if isinstance(value, float):
        return repr(value)
    if isinstance(value, (dt.datetime, dt.date, dt.time)):
        return value.isoformat()
    return " ".join(str(value).splitlines())


def _rows(ws: Any) -> list[list[Any]]:
    """A read-only worksheet's rows from row 1 (missing rows empty), whatever dimension it declares."""
    ws.reset_dimensions()  # a wrong <dimension> tag would otherwise cut the rows read
    return [list(row) for row in ws.iter_rows(values_only=True)]


def _lines(rows: list[list[Any]]) -> list[str]:
    """Sheet rows -> tab-separated lines (quoted where a cell holds a tab or a quote), all as wide as
    the widest filled row (so an empty data cell stays an empty cell), trailing empty rows dropped."""
    cells = [[_cell(v) for v in row] for row in rows]
    width = max((max((j + 1 for j, c in enumerate(row) if c), default=0) for row in cells), default=0)
    while cells and not any(cells[-1]):
        cells.pop()
    out = []
    for row in cells:
        row = (row + [""] * width)[:width]
        buf = io.StringIO()
        csv.writer(buf, delimiter="\t", lineterminator="").writerow(row)
        out.append(buf.getvalue())
    return out


def _check_zip(raw: bytes, where: str) -> None:
    try:
        with zipfile.ZipFile(io.BytesIO(raw)) as z:
            names = z.namelist()
            size = sum(i.file_size for i in z.infolist())
    except zipfile.BadZipFile as exc:
        raise DataError(f"not a readable Excel workbook: the zip archive is damaged ({exc})", path=where) from None
    if "xl/workbook.xml" not in names:
        raise DataError("a zip archive, but not an Excel workbook (no xl/workbook.xml); adhfit reads .xlsx, "
                        ".csv, .tsv, .txt and LabVIEW .lvm files", path=where)
    if size > MAX_UNZIPPED_BYTES:
        raise DataError(f"the workbook unpacks to {size / 1024**3:.1f} GB, more than the "
                        f"{MAX_UNZIPPED_BYTES / 1024**3:.0f} GB adhfit reads: save the curve's sheet as CSV",
                        path=where)


def workbook_tables(raw: bytes, where: str) -> list[Table]:
    """Every non-empty sheet of an ``.xlsx`` workbook as a :class:`~adhfit.readers.text.Table`.

    Parameters
    ----------
    raw : bytes
        The file's bytes.
    where : str
        The file, for messages; each table's ``where`` adds its sheet (``"run.xlsx, sheet 'Data'"``).

    Returns
    -------
    list of Table
        In workbook order; line ``n`` of a table is row ``n`` of its sheet.

    Raises
    ------
    DataError
        A damaged or non-Excel zip, a workbook too large, a workbook with no filled sheet, or a cell
        too long to be data (:data:`~adhfit.readers.text.MAX_LINE_CHARS`).
    """
    _check_zip(raw, where)
    try:
        import openpyxl  # noqa: PLC0415 - loads only when a workbook is read
    except ImportError:
        raise DataError("reading .xlsx needs the openpyxl package (pip install openpyxl), or save the sheet "
                        "as CSV", path=where) from None
    try:
        book = openpyxl.load_workbook(io.BytesIO(raw), read_only=True, data_only=True)
        try:
            sheets = {ws.title: _rows(ws) for ws in book.worksheets}
        finally:
            book.close()
    except Exception as exc:  # noqa: BLE001 - openpyxl raises many types for a damaged workbook
        raise DataError(f"not a readable Excel workbook ({type(exc).__name__}: {clip(str(exc))})", path=where) from None
    tables = []
    for name, rows in sheets.items():
        lines = _lines(rows)
        if not any(lines):
            continue
        here = f"{where}, sheet '{name}'"
        check_line_lengths(lines, here)
        tables.append(Table(where=here, lines=lines, note=f"sheet '{name}'", sheet=str(name)))
    if not tables:
        raise DataError(f"the workbook's sheets are empty ({', '.join(shown(str(n), 40) for n in sheets)})", path=where)
    return tables
