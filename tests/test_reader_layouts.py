"""Layout variants around the six instrument files: two-column European files, clock-time columns,
unnamed LabVIEW channels, several X columns, and instrument name prefixes (docs/contracts.md A4b).

Expected arrays are the clean reference file's (tests/data/instruments/clean.csv).
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from adhfit.data import read_curve
from adhfit.errors import DataError

HERE = Path(__file__).resolve().parent / "data" / "instruments"
ROWS = [line.split(",") for line in (HERE / "clean.csv").read_text().splitlines()[1:]]
LVM = (HERE / "labview.lvm").read_text()


@pytest.fixture(scope="module")
def clean():
    return read_curve(HERE / "clean.csv", "displacement")


def write(tmp_path, text: str, name: str = "curve.csv") -> Path:
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


def test_two_column_european_file(tmp_path, clean):
    """'1,5;2,5' also splits on ',' into three cells, two of them numbers: the reading where every
    cell is a number must win."""
    body = "\n".join(f"{d.replace('.', ',')};{f.replace('.', ',')}" for _, d, f in ROWS)
    c = read_curve(write(tmp_path, "Displacement (µm);Force (mN)\n" + body + "\n"), "displacement")
    np.testing.assert_allclose(c.x, clean.x, rtol=1e-12)
    np.testing.assert_allclose(c.force, clean.force, rtol=1e-12)
    assert c.layout.startswith("semicolon-separated, decimal comma")


def test_clock_time_column_is_listed_not_fatal(tmp_path, clean):
    body = "\n".join(f"14:{i // 60:02d}:{i % 60:02d},{d},{f}" for i, (_, d, f) in enumerate(ROWS))
    c = read_curve(write(tmp_path, "Meta,line\nTime (hh:mm:ss),Position [um],Load [mN]\n" + body + "\n"),
                   "displacement")
    np.testing.assert_allclose(c.force, clean.force, rtol=1e-12)
    assert c.time is None and c.excluded == ((1, "metadata above the header"),)
    assert c.ignored_columns == (("Time (hh:mm:ss)", "time in 'hh:mm:ss', not a unit of time"),)
    # with a unit of time but clock-time cells, the column is left out too, naming the first such cell
    c = read_curve(write(tmp_path, "Time [s],Position [um],Load [mN]\n" + body + "\n"), "displacement")
    assert c.time is None and c.ignored_columns == (("Time [s]", "time not a number (line 2: '14:00:00')"),)


def test_unnamed_lvm_channels_are_found_by_their_units(tmp_path, clean):
    path = write(tmp_path, LVM.replace("X_Value\tForce\tDeflection", "X_Value\tUntitled\tUntitled 1"), "u.lvm")
    c = read_curve(path, "displacement")
    np.testing.assert_allclose(c.force, clean.force, rtol=1e-12)
    np.testing.assert_allclose(c.x, clean.x, rtol=1e-12)
    assert dict(c.columns) == {"time": "X_Value", "force": "Untitled", "displacement": "Untitled 1"}
    assert "'Untitled' read as force from its unit N" in c.layout


def test_unnamed_lvm_channels_with_one_dimension_are_ambiguous(tmp_path):
    text = LVM.replace("X_Value\tForce\tDeflection", "X_Value\tUntitled\tUntitled 1").replace(
        "Y_Unit_Label\tN\tmm", "Y_Unit_Label\tN\tN")
    with pytest.raises(DataError) as info:
        read_curve(write(tmp_path, text, "u.lvm"), "displacement")
    msg = str(info.value)
    assert "'Untitled' and 'Untitled 1' both have a force unit" in msg and "--columns force=NAME" in msg


def test_lvm_with_an_x_column_per_channel(tmp_path, clean):
    lines = LVM.splitlines()
    start = lines.index("X_Value\tForce\tDeflection\tComment")
    lines = [line.replace("X_Columns\tOne", "X_Columns\tMulti") for line in lines[:start]]
    lines.append("X_Value\tForce\tX_Value\tDeflection\tComment")
    for row in LVM.splitlines()[start + 1:]:
        t, f, d, _ = row.split("\t")
        lines.append(f"{t}\t{f}\t{t}\t{d}\t")
    c = read_curve(write(tmp_path, "\n".join(lines) + "\n", "multi.lvm"), "displacement")
    np.testing.assert_allclose(c.x, clean.x, rtol=1e-12)
    np.testing.assert_allclose(c.time, clean.time, rtol=1e-12)
    assert c.ignored_columns == (("X_Value", "another X_Value column (the first one is time)"),
                                 ("Comment", "not a column adhfit reads"))


@pytest.mark.parametrize("header", ["Running Time (s)\tAxial Displacement (um)\tAxial Force (mN)",
                                    "Test time (s)\tCompressive extension (um)\tCompressive load (mN)",
                                    "Elapsed_time (s)\tCrosshead_position (um)\tstandard-force (mN)",
                                    "Zeit (s)\tStandardweg (µm)\tStandardkraft (mN)"])
def test_instrument_name_variants(tmp_path, clean, header):
    body = "\n".join("\t".join(r) for r in ROWS)
    c = read_curve(write(tmp_path, header + "\n" + body + "\n"), "displacement")
    np.testing.assert_allclose(c.force, clean.force, rtol=1e-12)
    np.testing.assert_allclose(c.time, clean.time, rtol=1e-12)
    assert c.ignored_columns == ()


def test_quoted_tab_export_with_units_row(tmp_path, clean):
    rows = "\n".join("\t".join(f'"{v}"' for v in r) for r in ROWS)
    text = '"Test Run Name:"\t"A1"\n"Time"\t"Crosshead"\t"Load"\n"sec"\t"um"\t"mN"\n' + rows + "\n"
    c = read_curve(write(tmp_path, text, "q.txt"), "displacement")
    np.testing.assert_allclose(c.x, clean.x, rtol=1e-12)
    assert c.excluded == ((1, "metadata above the header"), (3, "units row"))
