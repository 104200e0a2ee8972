"""LabVIEW measurement files (``.lvm``, text): the layout from their header blocks.

An ``.lvm`` file opens with ``LabVIEW Measurement``, a file header (``Separator``,
``Decimal_Separator``, ``X_Columns``, ...) closed by ``***End_of_Header***``, then a segment header
(``Channels``, ``Y_Unit_Label``, ``X_Dimension``, ...) closed the same way, then the column names
(``X_Value``, the channel names, ``Comment``) and the data.  Units come from ``Y_Unit_Label`` (one per
channel, in column order); ``X_Value`` is time in seconds when ``X_Dimension`` is ``Time``.  A file
with several segments is refused (export one segment per curve).
"""
from __future__ import annotations

import re

from ..errors import DataError, shown
from .text import Layout, classify_lines

__all__ = ["lvm_layout"]

_END = "***end_of_header***"
_SEP = {"tab": "\t", "comma": ",", "semicolon": ";", "space": " "}


def _fields(lines: list[str], stop: int, sep: str) -> dict[str, list[str]]:
    """Header key -> values (the cells after the key), for the lines before ``stop``."""
    out: dict[str, list[str]] = {}
    for line in lines[:stop]:
        cells = [c.strip() for c in line.split(sep)]
        if cells and cells[0]:
            out[cells[0].lower()] = [c for c in cells[1:]]
    return out


def lvm_layout(lines: list[str], where: str) -> Layout:
    """The layout of a LabVIEW ``.lvm`` file; its header lines are listed as excluded."""
    ends = [i for i, line in enumerate(lines) if line.strip().lower().startswith(_END)]
    if not ends:
        raise DataError("LabVIEW file without '***End_of_Header***': the header never ends", path=where)
    if len(ends) > 2:
        raise DataError(f"LabVIEW file with {len(ends) - 1} data segments; adhfit reads one curve per file "
                        "(save each segment to its own file)", path=where, line=ends[2] + 1)
    m = next((re.match(r"^\s*separator[\t,;: ]+(\w+)", line, re.IGNORECASE) for line in lines[:ends[0]]
              if line.strip().lower().startswith("separator")), None)
    sep = _SEP.get(m.group(1).lower(), "\t") if m else "\t"
    head = _fields(lines, ends[-1], sep)
    decimal = (head.get("decimal_separator") or ["."])[0] or "."
    if decimal not in (".", ","):
        raise DataError(f"LabVIEW Decimal_Separator {shown(decimal)} is not '.' or ','", path=where)
    header = next((i for i in range(ends[-1] + 1, len(lines)) if lines[i].strip()), None)
    if header is None:
        raise DataError("LabVIEW file without column names after its header", path=where)
    names = [c.strip() for c in lines[header].split(sep)]
    y_units = [u for u in head.get("y_unit_label", [])]
    is_time = (head.get("x_dimension") or [""])[0].lower() == "time"
    units: list[str | None] = []
    channel = 0
    for name in names:
        if name.lower() == "x_value":
            units.append("s" if is_time else None)
        elif name.lower() == "comment" or not name:
            units.append(None)
        else:
            unit = y_units[channel] if channel < len(y_units) else ""
            units.append(unit or None)
            channel += 1
    layout = Layout(sep=sep, decimal=decimal, header_no=header + 1, units=units,
                    time_columns=("X_Value",) if is_time else ())
    classify_lines(lines, layout, "LabVIEW header")
    layout.description = ("LabVIEW .lvm, " + {"\t": "tab", ",": "comma", ";": "semicolon", " ": "space"}[sep]
                          + "-separated" + (", decimal comma" if decimal == "," else "")
                          + ", units from Y_Unit_Label")
    return layout
