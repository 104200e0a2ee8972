"""Reading measured curves as instruments write them (docs/contracts.md A4, A4b).

:data:`FORMATS` (:mod:`.formats`) is the one list of the file formats adhfit reads: how each is
recognised (first bytes or suffix), how its bytes become tables of text lines and how a table's
layout is found.  :mod:`.text` decodes text and finds the layout of delimited text (separator,
decimal mark, metadata lines, header, units row, data lines); :mod:`.lvm` does the same for LabVIEW
``.lvm`` files from their header blocks; :mod:`.xlsx` writes each sheet of an Excel workbook as
lines; :mod:`.columns` maps header cells to adhfit's columns (aliases, units, overrides) and raises
one-line errors for what stays ambiguous.  :func:`adhfit.data.read_curve` puts them together.
"""
from __future__ import annotations

from .columns import ALIASES, Assignment, assign
from .formats import FORMATS, Format, find_format, folder_patterns
from .text import Layout, Table, read_lines

__all__ = ["ALIASES", "Assignment", "FORMATS", "Format", "Layout", "Table", "assign", "find_format",
           "folder_patterns", "read_lines"]
