"""Decode a curve file and find its layout: separator, decimal mark, header, units row, data lines.

Delimited text (``,`` ``;`` or tab, quoted or not, decimal point or comma) is recognised from its
data: for each separator and decimal mark the lines that split into two or more numbers are
counted, and the reading that makes the most lines numeric wins (ties: decimal point, then ``,``
``;`` tab).  ``csv.Sniffer`` is not used for this: on ``0;1,5`` it prefers ``,``, the wrong answer
for a European Excel file.  The header is the nearest non-numeric line above the first numeric
one; a line between them without any known column name is a units row.  Everything above the
header is metadata, reported with its line number.  LabVIEW ``.lvm`` files are read by :mod:`.lvm`
(:func:`adhfit.readers.detect_layout` chooses).
"""
from __future__ import annotations

import csv
import re
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path

from ..errors import DataError
from ..units import is_unit
from .columns import role_of, split_cell

__all__ = ["Layout", "Table", "MAX_LINE_CHARS", "read_bytes", "decode", "read_lines", "text_layout", "is_lvm",
           "split_line", "is_number", "check_line_lengths"]

#: Lines used to find the layout (the header of any real export is far above this).
_SNIFF_LINES = 2000
_NUMBER = {".": re.compile(r"^[+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?$"),
           ",": re.compile(r"^[+-]?(?:\d+,?\d*|,\d+)(?:[eE][+-]?\d+)?$")}
_SEPARATORS = (",", ";", "\t")
_SEP_NAME = {",": "comma-separated", ";": "semicolon-separated", "\t": "tab-separated"}


@dataclass
class Layout:
    """Where things are in a curve file.

    Attributes
    ----------
    sep, decimal : str
        Cell separator and decimal mark.
    header_no : int
        1-based line of the header.
    units_no : int or None
        1-based line of a units row under the header.
    rows : list of int
        Data lines (everything after the header that is not blank or a ``#`` comment).
    excluded : list of (int, str)
        Lines left out, with the reason.
    units : list of (str or None), optional
        Units per column given outside the header (LabVIEW ``Y_Unit_Label``).
    time_columns : tuple of str
        Header names that hold time in seconds (LabVIEW ``X_Value`` when ``X_Dimension`` is Time).
    description : str
        A short description for reports, e.g. ``"tab-separated, decimal comma, units row"``.
    """

    sep: str
    decimal: str
    header_no: int
    units_no: int | None = None
    rows: list[int] = field(default_factory=list)
    excluded: list[tuple[int, str]] = field(default_factory=list)
    units: list[str | None] | None = None
    time_columns: tuple[str, ...] = ()
    description: str = ""


#: Longest line of a curve file, in characters.  A real export's widest line (hundreds of columns)
#: is a few thousand; past this no cell is a number, a name or a unit, and Python's csv module
#: refuses fields over 131,072 characters anyway.
MAX_LINE_CHARS = 65_536


@dataclass(frozen=True)
class Table:
    """One table a curve may be read from (a text file, or one sheet of a workbook).

    Attributes
    ----------
    where : str
        The file (and sheet) for messages, e.g. ``"run.xlsx, sheet 'Data'"``.
    lines : list of str
        The table's rows as text lines; line ``n`` is ``lines[n - 1]`` (a sheet's row ``n``).
    note : str
        How the bytes were read, for :attr:`adhfit.data.Curve.layout` (the encoding, the sheet).
    sheet : str or None
        The sheet's name, for a workbook.
    """

    where: str
    lines: list[str]
    note: str = ""
    sheet: str | None = None


def read_bytes(path: str | Path, where: str) -> bytes:
    """The file's bytes; a one-line error for an unreadable or empty file."""
    try:
        raw = Path(path).read_bytes()
    except OSError as exc:
        raise DataError(f"cannot read the file ({exc.strerror or exc})", path=where) from None
    if not raw.strip():
        raise DataError("the file is empty", path=where)
    return raw


def decode(raw: bytes, where: str) -> tuple[list[str], str]:
    """A text file's lines (line n is ``lines[n - 1]``) and the encoding used.

    UTF-16 with a byte-order mark, else UTF-8 (with or without one), else Latin-1.  A file with NUL
    bytes that is not UTF-16 is binary (an instrument's own format, a zip, an image): refused by name.
    A line longer than :data:`MAX_LINE_CHARS` is refused with its number.
    """
    if raw[:2] in (b"\xff\xfe", b"\xfe\xff"):
        text, encoding = raw.decode("utf-16", errors="replace"), "UTF-16"
    elif b"\x00" in raw[:65536]:
        raise DataError("a binary file, not a text export (it holds NUL bytes; or UTF-16 text without a "
                        "byte-order mark); adhfit reads delimited text, LabVIEW .lvm and Excel .xlsx: export the "
                        "curve as CSV (UTF-8) or .xlsx", path=where)
    else:
        try:
            text, encoding = raw.decode("utf-8-sig"), "UTF-8" + (" with BOM" if raw[:3] == b"\xef\xbb\xbf" else "")
        except UnicodeDecodeError:
            text, encoding = raw.decode("latin-1"), "Latin-1"  # every byte maps: a non-UTF-8 'µ' must not stop a read
    lines = text.replace("\r\n", "\n").replace("\r", "\n").split("\n")
    if lines and lines[-1] == "":
        lines.pop()
    check_line_lengths(lines, where)
    return lines, encoding


def check_line_lengths(lines: list[str], where: str) -> None:
    """Refuse the first line longer than :data:`MAX_LINE_CHARS`, naming it."""
    long = next((no for no, line in enumerate(lines, start=1) if len(line) > MAX_LINE_CHARS), None)
    if long is not None:
        raise DataError(f"line of {len(lines[long - 1]):,} characters, longer than the {MAX_LINE_CHARS:,} a curve "
                        "file's line may hold (no number, column name or unit is that long): is this the "
                        "curve file? A cell holding a long note must be removed or shortened", path=where,
                        line=long)


def read_lines(path: str | Path, where: str) -> tuple[bytes, list[str], str]:
    """The file's bytes, its lines (line n is ``lines[n - 1]``) and the encoding used."""
    raw = read_bytes(path, where)
    lines, encoding = decode(raw, where)
    return raw, lines, encoding


def split_line(line: str, sep: str) -> list[str]:
    """Cells of one line (quotes removed), stripped."""
    return [c.strip() for c in next(csv.reader([line], delimiter=sep), [])]


def is_number(cell: str, decimal: str) -> bool:
    """Whether a stripped cell is a plain decimal number written with ``decimal``."""
    return bool(_NUMBER[decimal].match(cell))


def _skip(line: str) -> str | None:
    stripped = line.strip()
    if not stripped:
        return "blank line"
    return "comment line" if stripped.startswith("#") else None


def _numeric(cells: list[str], decimal: str) -> bool:
    """Two or more numbers, and numbers in most filled cells (a clock-time or note column may remain)."""
    filled = [c for c in cells if c]
    numbers = sum(is_number(c, decimal) for c in filled)
    return numbers >= 2 and 2 * numbers > len(filled)


def _sniff(lines: list[str], separators: tuple[str, ...] = _SEPARATORS) -> tuple[str, str, int]:
    """Separator, decimal mark and row width that make the most lines numeric (all cells first)."""
    best: tuple = ()
    for order, sep in enumerate(separators):
        cells = [split_line(line, sep) if _skip(line) is None else [] for line in lines]
        for decimal in (".", ","):
            if sep == "," and decimal == ",":
                continue
            rows = [c for c in cells if _numeric(c, decimal)]
            if not rows:
                continue
            width = Counter(len(c) for c in rows).most_common(1)[0][0]
            full = sum(1 for c in rows if len(c) == width and all(is_number(x, decimal) for x in c if x))
            key = (full, sum(1 for c in rows if len(c) == width), decimal == ".", -order)
            if not best or key > best[0]:
                best = (key, sep, decimal, width)
    if not best:
        return separators[0], ".", 0
    return best[1], best[2], best[3]


def is_lvm(lines: list[str]) -> bool:
    """Whether the lines are a LabVIEW measurement file (its first line says so)."""
    first = next((line for line in lines if line.strip()), "")
    return first.strip().lower().startswith("labview measurement")


def text_layout(lines: list[str], where: str, *, separators: tuple[str, ...] = _SEPARATORS) -> Layout:
    """Find the layout of a delimited-text curve file's lines (module docstring).

    ``separators`` limits the separators tried (a spreadsheet's rows rendered as text use tab only).
    """
    sep, decimal, width = _sniff(lines[:_SNIFF_LINES], separators)
    header_no, units_no = _find_header(lines, sep, decimal, width, where)
    layout = Layout(sep=sep, decimal=decimal, header_no=header_no, units_no=units_no)
    classify_lines(lines, layout, "metadata above the header")
    parts = [_SEP_NAME[sep]] + (["decimal comma"] if decimal == "," else [])
    n_meta = sum(1 for _, reason in layout.excluded if reason == "metadata above the header")
    parts += [f"{n_meta} metadata line(s)"] if n_meta else []
    parts += ["units row"] if units_no else []
    layout.description = ", ".join(parts)
    return layout


def _find_header(lines: list[str], sep: str, decimal: str, width: int, where: str) -> tuple[int, int | None]:
    """(header line, units row line or None), both 1-based."""
    content = [i for i, line in enumerate(lines) if _skip(line) is None]
    if not content:
        raise DataError("the file has no header line (only blank or comment lines)", path=where)
    cells = {i: split_line(lines[i], sep) for i in content[:_SNIFF_LINES]}
    first_data = next((i for i in content[:_SNIFF_LINES]
                       if len(cells[i]) == width and _numeric(cells[i], decimal)), None)
    if first_data is None:  # no numeric row: the first content line is the header
        return content[0] + 1, None
    above = [i for i in content if i < first_data]
    # walk up over broken data rows (a width-matching line with a number in it) to the header
    while above and len(cells[above[-1]]) == width and any(is_number(c, decimal) for c in cells[above[-1]]):
        above.pop()
    if not above:
        raise DataError(f"no header line above the first data row (line {first_data + 1}); the first "
                        "line of the table must name the columns, e.g. 'displacement [um],force [mN]'",
                        path=where, line=first_data + 1)
    last = above[-1]
    if len(above) >= 2 and _is_units_row(cells[last], cells[above[-2]], width):
        return above[-2] + 1, last + 1
    return last + 1, None


def _is_units_row(row: list[str], header: list[str], width: int) -> bool:
    """A line under the header naming no known column, while the header names at least one."""
    if len(row) != width or len(header) != width:
        return False
    if any(role_of(split_cell(c)[0]) is not None for c in row):
        return False
    filled = [c for c in row if c]
    return bool(filled) and (any(role_of(split_cell(c)[0]) is not None for c in header)
                             or all(c[0] + c[-1] in ("()", "[]") for c in filled)
                             or all(_is_unit(c) for c in filled))


def _is_unit(cell: str) -> bool:
    """Whether pint reads a cell as a unit (``mm``, ``kN``, ``sec``), never a plain number."""
    return not (is_number(cell, ".") or is_number(cell, ",")) and is_unit(cell)


def classify_lines(lines: list[str], layout: Layout, above_reason: str) -> None:
    """Fill ``layout.rows`` and ``layout.excluded`` from the header and units-row positions."""
    for no, line in enumerate(lines, start=1):
        if no == layout.header_no:
            continue
        reason = _skip(line)
        if no == layout.units_no:
            layout.excluded.append((no, "units row"))
        elif reason is not None:
            layout.excluded.append((no, reason))
        elif no < layout.header_no:
            layout.excluded.append((no, above_reason))
        else:
            layout.rows.append(no)
