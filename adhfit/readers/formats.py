"""The file formats adhfit reads: :data:`FORMATS`, the only list of them in the code.

Each entry says how a file of that format is recognised (by its first bytes, ``sniff``, or by its
name's suffix), how its bytes become one or more tables of text lines (``tables``: one per text
file, one per sheet of a workbook) and how a table's layout is found (``layout``).  A file's
format is the first entry whose ``sniff`` accepts its first bytes, else the entry that lists its
suffix, else delimited text.  The content decides before the name: an Excel workbook saved as
``curve.csv`` is still read as a workbook.

Adding a format is one entry here (and its module); :func:`folder_patterns` tells a batch which
files a folder stands for.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Callable

from ..errors import DataError
from .lvm import lvm_layout
from .text import Layout, Table, decode, is_lvm, text_layout
from .xlsx import SHEET_SEPARATORS, workbook_tables

__all__ = ["FORMATS", "Format", "Table", "find_format", "folder_patterns", "SNIFF_BYTES"]

#: Bytes of a file's start given to each ``sniff``.
SNIFF_BYTES = 4096


@dataclass(frozen=True)
class Format:
    """How one file format is recognised and read.

    Attributes
    ----------
    name : str
        What the format is called in messages and reports.
    suffixes : tuple of str
        File-name suffixes (lower case, with the dot) of this format.
    tables : callable
        ``tables(raw, where) -> list[Table]``: the file's bytes as tables of text lines.
    layout : callable
        ``layout(lines, where) -> Layout``: separator, header, units row and data lines of a table.
    sniff : callable, optional
        ``sniff(head) -> bool``: whether the file's first :data:`SNIFF_BYTES` bytes are this format.
    folder_suffixes : tuple of str, optional
        The suffixes a folder given to a batch is searched for; default ``suffixes`` (``.txt`` is too
        common a suffix for notes, so plain text is found by ``.csv`` and ``.tsv`` only).
    """

    name: str
    suffixes: tuple[str, ...]
    tables: Callable[[bytes, str], list[Table]]
    layout: Callable[[list[str], str], Layout]
    sniff: Callable[[bytes], bool] | None = None
    folder_suffixes: tuple[str, ...] | None = None


def _text_tables(raw: bytes, where: str) -> list[Table]:
    lines, encoding = decode(raw, where)
    return [Table(where=where, lines=lines, note=encoding)]


def _sniff_lvm(head: bytes) -> bool:
    text = head.decode("utf-16", "replace") if head[:2] in (b"\xff\xfe", b"\xfe\xff") else head.decode("latin-1")
    return is_lvm(text.lstrip("\ufeff\xef\xbb\xbf").splitlines())


def _sheet_layout(lines: list[str], where: str) -> Layout:
    layout = text_layout(lines, where, separators=SHEET_SEPARATORS)
    layout.description = layout.description.replace("tab-separated", "Excel workbook", 1)
    return layout


def _old_excel(raw: bytes, where: str) -> list[Table]:
    raise DataError("an Excel 97-2003 workbook (.xls); adhfit reads .xlsx: open it in Excel or LibreOffice and "
                    "save it as .xlsx or CSV", path=where)


#: Every format adhfit reads, first match wins for ``sniff`` (docstring of the module).
FORMATS: dict[str, Format] = {
    "xlsx": Format(name="Excel workbook", suffixes=(".xlsx", ".xlsm"), tables=workbook_tables,
                   layout=_sheet_layout, sniff=lambda head: head.startswith(b"PK\x03\x04")),
    "xls": Format(name="Excel 97-2003 workbook", suffixes=(".xls",), tables=_old_excel, layout=_sheet_layout,
                  sniff=lambda head: head.startswith(b"\xd0\xcf\x11\xe0\xa1\xb1\x1a\xe1"), folder_suffixes=()),
    "lvm": Format(name="LabVIEW measurement", suffixes=(".lvm",), tables=_text_tables, layout=lvm_layout,
                  sniff=_sniff_lvm),
    "text": Format(name="delimited text", suffixes=(".csv", ".tsv", ".txt"), tables=_text_tables,
                   layout=text_layout, folder_suffixes=(".csv", ".tsv")),
}
#: The format of a file no entry recognises.
DEFAULT = "text"


def find_format(path: str | Path, head: bytes) -> Format:
    """The format of the file at ``path`` whose first bytes are ``head`` (module docstring)."""
    for fmt in FORMATS.values():
        if fmt.sniff is not None and fmt.sniff(head[:SNIFF_BYTES]):
            return fmt
    suffix = Path(path).suffix.lower()
    return next((f for f in FORMATS.values() if suffix in f.suffixes), FORMATS[DEFAULT])


def folder_patterns() -> tuple[str, ...]:
    """Glob patterns (``"*.csv"``, ...) of the files a folder given to a batch stands for."""
    return tuple(f"*{s}" for f in FORMATS.values()
                 for s in (f.folder_suffixes if f.folder_suffixes is not None else f.suffixes))
