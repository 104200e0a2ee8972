"""Reading measured curves as instruments write them (docs/contracts.md A4b).

:mod:`.text` decodes a file and finds its layout (separator, decimal mark, metadata lines, header,
units row, data lines); :mod:`.lvm` does the same for LabVIEW ``.lvm`` files from their header
blocks; :mod:`.columns` maps header cells to adhfit's columns (aliases, units, overrides) and
raises one-line errors for what stays ambiguous.  :func:`adhfit.data.read_curve` puts them together.
"""
from __future__ import annotations

from .columns import ALIASES, Assignment, assign
from .text import Layout, detect_layout, read_lines

__all__ = ["ALIASES", "Assignment", "Layout", "assign", "detect_layout", "read_lines"]
