"""Write one measured curve in six instrument layouts (see README.md in this folder).

The curve is ``clean.csv`` (a copy of sample_data/fea_displacement_no-slip/curve.csv: time [s],
displacement [um], force [mN]).  Every layout holds exactly the same numbers, only written the way an
instrument or a spreadsheet writes them, so a reader must recover the same arrays and a fit the same
W_ad and mu*h.  Run from the repository root: ``python tests/data/instruments/make_instruments.py``.
Conversions are done on decimal strings (shifting the decimal point), so no file carries rounding.
"""
from __future__ import annotations

import csv
from decimal import Decimal
from pathlib import Path

HERE = Path(__file__).resolve().parent


def _rows() -> list[tuple[str, str, str]]:
    with open(HERE / "clean.csv", encoding="utf-8", newline="") as fh:
        rows = list(csv.reader(fh))
    assert rows[0] == ["time [s]", "displacement [um]", "force [mN]"], rows[0]
    return [tuple(r) for r in rows[1:]]


def _shift(text: str, places: int, comma: bool = False) -> str:
    """``text`` times 10**places, written in plain notation (exact: only the decimal point moves)."""
    out = format(Decimal(text).scaleb(places), "f")
    return out.replace(".", ",") if comma else out


def _write(name: str, text: str, encoding: str = "utf-8") -> None:
    (HERE / name).write_bytes(text.encode(encoding))


def bluehill(rows) -> None:
    """Instron Bluehill: quoted cells, metadata lines, header, units row in parentheses; mm and N."""
    lines = ['"Results Table 1"', '"Sample ID:","adhesion-A1"', '"Test date:","30 Nov 2026"',
             '"Method:","membrane adhesion.im_tens"', '"Rate 1","0.01500","mm/s"', "",
             '"Time","Extension","Load"', '"(s)","(mm)","(N)"']
    lines += [f'"{t}","{_shift(d, -3)}","{_shift(f, -3)}"' for t, d, f in rows]
    _write("bluehill.csv", "\r\n".join(lines) + "\r\n")


def mts(rows) -> None:
    """MTS TestSuite: UTF-8 with BOM, tab-separated, metadata block, units row without brackets."""
    lines = ["Test Run Name:\tadhesion-A1", "Specimen Name:\tSpecimen 1", "Station Name:\tCriterion 43",
             "Test Date:\t11/30/2026 14:02", "", "Time\tCrosshead\tLoad", "sec\tmm\tN"]
    lines += [f"{t}\t{_shift(d, -3)}\t{_shift(f, -3)}" for t, d, f in rows]
    _write("mts_testsuite.txt", "\ufeff" + "\r\n".join(lines) + "\r\n")


def labview(rows) -> None:
    """LabVIEW .lvm: header blocks, tab-separated, decimal commas, Y_Unit_Label, X_Value = time."""
    head = ["LabVIEW Measurement\t", "Writer_Version\t2", "Reader_Version\t2", "Separator\tTab",
            "Decimal_Separator\t,", "Multi_Headings\tNo", "X_Columns\tOne", "Time_Pref\tRelative",
            "Operator\tlab", "Date\t2026/11/30", "Time\t14:02:11,5", "***End_of_Header***\t", "\t",
            "Channels\t2\t", "Samples\t200\t200\t", "Date\t2026/11/30\t2026/11/30\t",
            "Time\t14:02:11,5\t14:02:11,5\t", "Y_Unit_Label\tN\tmm\t", "X_Dimension\tTime\tTime\t",
            "X0\t0,0000000000000000E+0\t0,0000000000000000E+0\t", "Delta_X\t0,500000\t0,500000\t",
            "***End_of_Header***\t", "X_Value\tForce\tDeflection\tComment"]
    body = [f"{_shift(t, 0, True)}\t{_shift(f, -3, True)}\t{_shift(d, -3, True)}\t" for t, d, f in rows]
    _write("labview.lvm", "\r\n".join(head + body) + "\r\n")


def excel_eu(rows) -> None:
    """European Excel 'CSV (semicolon)': ';', decimal commas, µm, Windows-1252 (µ is byte 0xB5)."""
    lines = ["Time [s];Displacement [µm];Force [mN]"]
    lines += [f"{_shift(t, 0, True)};{_shift(d, 0, True)};{_shift(f, 0, True)}" for t, d, f in rows]
    _write("excel_eu.csv", "\r\n".join(lines) + "\r\n", encoding="cp1252")


def extra_columns(rows) -> None:
    """Logged extras (cycle, temperature, strain) between the columns adhfit reads."""
    lines = ["cycle,time [s],temperature [°C],displacement [um],strain [%],force [mN]"]
    for i, (t, d, f) in enumerate(rows):
        lines.append(f"1,{t},{23.0 + 0.01 * (i % 7):.2f},{d},{float(d) / 20:.4f},{f}")
    _write("extra_columns.csv", "\n".join(lines) + "\n")


def position_load(rows) -> None:
    """'Position' and 'Load' in mm and N, units in brackets."""
    lines = ["Time [s],Position [mm],Load [N]"]
    lines += [f"{t},{_shift(d, -3)},{_shift(f, -3)}" for t, d, f in rows]
    _write("position_load.csv", "\n".join(lines) + "\n")


if __name__ == "__main__":
    data = _rows()
    for make in (bluehill, mts, labview, excel_eu, extra_columns, position_load):
        make(data)
