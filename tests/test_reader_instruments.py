"""Instrument exports (docs/contracts.md A4b): one curve written in six layouts reads as the clean CSV.

The files in tests/data/instruments/ were written by make_instruments.py from clean.csv by moving
the decimal point on decimal strings (no arithmetic), so every layout must give the clean file's SI
arrays to the last bit or two of a double (``rtol=1e-12``: values are parsed from differently
scaled decimals, e.g. 0.0717 mm versus 71.7 um, whose nearest doubles differ by ~1 ulp after the
unit factor).  Expected values come from the clean file and the known layout, not from the reader's
description of itself.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from adhfit.data import read_curve

HERE = Path(__file__).resolve().parent / "data" / "instruments"
CLEAN = HERE / "clean.csv"

#: file -> (lines before the first data row that are listed as excluded, columns as written, units,
#: ignored columns)
LAYOUTS = {
    "bluehill.csv": (7, {"time": "Time", "displacement": "Extension", "force": "Load"},
                     {"time": "s", "displacement": "mm", "force": "N"}, []),
    "mts_testsuite.txt": (6, {"time": "Time", "displacement": "Crosshead", "force": "Load"},
                          {"time": "sec", "displacement": "mm", "force": "N"}, []),
    "labview.lvm": (22, {"time": "X_Value", "displacement": "Deflection", "force": "Force"},
                    {"time": "s", "displacement": "mm", "force": "N"}, ["Comment"]),
    "excel_eu.csv": (0, {"time": "Time [s]", "displacement": "Displacement [µm]", "force": "Force [mN]"},
                     {"time": "s", "displacement": "µm", "force": "mN"}, []),
    "extra_columns.csv": (0, {"time": "time [s]", "displacement": "displacement [um]", "force": "force [mN]"},
                          {"time": "s", "displacement": "um", "force": "mN"},
                          ["cycle", "temperature [°C]", "strain [%]"]),
    "position_load.csv": (0, {"time": "Time [s]", "displacement": "Position [mm]", "force": "Load [N]"},
                          {"time": "s", "displacement": "mm", "force": "N"}, []),
}


@pytest.fixture(scope="module")
def clean():
    return read_curve(CLEAN, "displacement")


def test_clean_reference_is_the_sample():
    sample = Path(__file__).resolve().parents[1] / "sample_data" / "fea_displacement_no-slip" / "curve.csv"
    assert CLEAN.read_bytes() == sample.read_bytes()


@pytest.mark.parametrize("name", sorted(LAYOUTS))
def test_layout_reads_as_the_clean_file(clean, name):
    above, columns, units, ignored = LAYOUTS[name]
    c = read_curve(HERE / name, "displacement")
    assert len(c) == len(clean) == 200
    np.testing.assert_allclose(c.x, clean.x, rtol=1e-12, atol=0)
    np.testing.assert_allclose(c.force, clean.force, rtol=1e-12, atol=0)
    np.testing.assert_allclose(c.time, clean.time, rtol=1e-12, atol=0)
    assert c.i_turn == clean.i_turn
    assert dict(c.columns) == columns and dict(c.units) == units
    assert [cell for cell, _ in c.ignored_columns] == ignored
    # every line is the header, a data row or listed as excluded, and only lines above the data are
    n_lines = len((HERE / name).read_bytes().splitlines())
    header = c.line[0] - 1 - (1 if name in ("bluehill.csv", "mts_testsuite.txt") else 0)
    assert {header, *c.line.tolist(), *(n for n, _ in c.excluded)} == set(range(1, n_lines + 1))
    assert len(c.excluded) == above and all(n < c.line[0] for n, _ in c.excluded)


def test_exclusion_reasons_name_what_was_left_out():
    c = read_curve(HERE / "bluehill.csv", "displacement")
    assert c.excluded == ((1, "metadata above the header"), (2, "metadata above the header"),
                          (3, "metadata above the header"), (4, "metadata above the header"),
                          (5, "metadata above the header"), (6, "blank line"), (8, "units row"))
    lvm = read_curve(HERE / "labview.lvm", "displacement")
    assert {reason for _, reason in lvm.excluded} == {"LabVIEW header", "blank line"} and lvm.line[0] == 24
    assert lvm.excluded[12] == (13, "blank line")


def test_layout_is_described_for_reports():
    assert read_curve(HERE / "excel_eu.csv", "displacement").layout.startswith(
        "semicolon-separated, decimal comma")
    mts = read_curve(HERE / "mts_testsuite.txt", "displacement").layout
    assert mts.startswith("tab-separated, 4 metadata line(s), units row") and "BOM" in mts
    assert read_curve(HERE / "labview.lvm", "displacement").layout.startswith("LabVIEW .lvm")


def test_lvm_recognised_by_content_not_only_suffix(tmp_path, clean):
    copy = tmp_path / "export.txt"
    copy.write_bytes((HERE / "labview.lvm").read_bytes())
    np.testing.assert_allclose(read_curve(copy, "displacement").force, clean.force, rtol=1e-12)


def test_utf16_export(tmp_path, clean):
    """Excel's 'Unicode text' is UTF-16 with a BOM, tab-separated."""
    text = (HERE / "mts_testsuite.txt").read_bytes().decode("utf-8-sig")
    path = tmp_path / "unicode.txt"
    path.write_bytes(text.encode("utf-16"))
    np.testing.assert_allclose(read_curve(path, "displacement").x, clean.x, rtol=1e-12)


def test_units_in_parentheses_on_the_header(tmp_path, clean):
    lines = (HERE / "position_load.csv").read_text().splitlines()
    lines[0] = "Time (s),Crosshead (mm),Standard force (N)"
    path = tmp_path / "paren.csv"
    path.write_text("\n".join(lines) + "\n")
    c = read_curve(path, "displacement")
    np.testing.assert_allclose(c.force, clean.force, rtol=1e-12)
    assert dict(c.units) == {"time": "s", "displacement": "mm", "force": "N"}
