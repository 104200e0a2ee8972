"""Reading measured curves as instruments write them (docs/contracts.md A4b).

:mod:`.text` decodes a file and finds its layout (separator, decimal mark, metadata lines, header,
units row, data lines); :mod:`.lvm` does the same for LabVIEW ``.lvm`` files from their header
blocks; :mod:`.columns` maps header cells to adhfit's columns (aliases, units, overrides) and
raises one-line errors for what stays ambiguous.  :func:`adhfit.data.read_curve` puts them together.
"""
from __future__ import annotations

from .columns import ALIASES, Assignment, assign
from .lvm import lvm_layout
from .text import Layout, is_lvm, read_lines, text_layout


def detect_layout(lines: list[str], where: str, *, lvm: bool = False) -> Layout:
    """Find the layout of a curve file's lines: LabVIEW ``.lvm`` (when ``lvm``, or recognised from its
    first line, :mod:`.lvm`) or delimited text (:mod:`.text`)."""
    return lvm_layout(lines, where) if lvm or is_lvm(lines) else text_layout(lines, where)


__all__ = ["ALIASES", "Assignment", "Layout", "assign", "detect_layout", "read_lines"]
