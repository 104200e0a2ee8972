"""What stays ambiguous in a curve file is one line naming the choices and the flag; the overrides
(``columns``, ``units``, ``force_sign``, ``displacement_sign``) settle it (docs/contracts.md A4b).

Files are built here from the clean instrument reference (tests/data/instruments/clean.csv), so the
expected SI arrays are the clean file's, read through the original ``name [unit]`` path.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from adhfit.cli import main
from adhfit.data import read_curve
from adhfit.errors import DataError, InputError

HERE = Path(__file__).resolve().parent / "data" / "instruments"
ROWS = [line.split(",") for line in (HERE / "clean.csv").read_text().splitlines()[1:]]


@pytest.fixture(scope="module")
def clean():
    return read_curve(HERE / "clean.csv", "displacement")


def table(tmp_path, header: str, row=lambda t, d, f: f"{t},{d},{f}", name="curve.csv", pre: str = "") -> Path:
    path = tmp_path / name
    path.write_text(pre + header + "\n" + "\n".join(row(*r) for r in ROWS) + "\n", encoding="utf-8")
    return path


def refused(path, **kw) -> str:
    with pytest.raises(DataError) as info:
        read_curve(path, "displacement", **kw)
    msg = str(info.value)
    assert msg.startswith(str(path)) and "\n" not in msg
    return msg


# ---------------------------------------------------------------------------------------------
# ambiguities: the message names the file, the choices and the flag
def test_two_force_columns(tmp_path, clean):
    path = table(tmp_path, "Time [s],Position [um],Load [mN],Standard force [mN]", lambda t, d, f: f"{t},{d},{f},{f}")
    msg = refused(path)
    assert "'Load [mN]' and 'Standard force [mN]' both read as force" in msg
    assert "--columns force=NAME" in msg and "line 1" in msg
    c = read_curve(path, "displacement", columns={"force": "Standard force"})
    np.testing.assert_allclose(c.force, clean.force, rtol=1e-12)
    assert c.columns["force"] == "Standard force [mN]"
    assert c.ignored_columns == (("Load [mN]", "another force column (--columns force= chose "
                                               "'Standard force [mN]')"),)


def test_two_displacement_columns(tmp_path, clean):
    path = table(tmp_path, "Extension [um],Position [um],Load [mN]", lambda t, d, f: f"{d},{d},{f}")
    msg = refused(path)
    assert "'Extension [um]' and 'Position [um]' both read as displacement" in msg
    assert "--columns displacement=NAME" in msg
    c = read_curve(path, "displacement", columns={"displacement": "Position [um]"})  # the whole cell works too
    np.testing.assert_allclose(c.x, clean.x, rtol=1e-12)


def test_no_unit_anywhere(tmp_path, clean):
    path = table(tmp_path, "Time,Position,Load")
    msg = refused(path)
    assert "column 'Position'" in msg and "--units displacement=um" in msg and "units row" in msg
    c = read_curve(path, "displacement", units={"displacement": "um", "force": "mN"})
    np.testing.assert_allclose(c.x, clean.x, rtol=1e-12)
    np.testing.assert_allclose(c.force, clean.force, rtol=1e-12)
    # time has no unit either: it is optional, so it is left out and listed, not guessed
    assert c.time is None and c.ignored_columns == (("Time", "time without a unit (give it with --units time=s)"),)


def test_no_force_column(tmp_path, clean):
    path = table(tmp_path, "t [s],s [um],F [mN]")
    msg = refused(path)
    assert "missing column 'displacement [um]' (any length unit)" in msg
    assert "Extension, Position, Crosshead, Deflection" in msg and "--columns displacement=NAME" in msg
    c = read_curve(path, "displacement", columns={"displacement": "s", "force": "F"})
    np.testing.assert_allclose(c.force, clean.force, rtol=1e-12)
    assert c.ignored_columns == (("t [s]", "not a column adhfit reads"),)


def test_columns_override_names_a_missing_column(tmp_path):
    msg = refused(table(tmp_path, "time [s],displacement [um],force [mN]"), columns={"force": "Load"})
    assert "--columns force=Load: no column of that name; the columns are 'time [s]'" in msg


def test_one_column_for_two_quantities(tmp_path):
    msg = refused(table(tmp_path, "time [s],displacement [um],force [mN]"),
                  columns={"force": "force", "displacement": "force"})
    assert "names one column for two quantities" in msg


def test_units_override_for_absent_column(tmp_path):
    msg = refused(table(tmp_path, "displacement [um],force [mN],temperature [K]"), units={"time": "s"})
    assert "--units time=s: the file has no time column" in msg


@pytest.mark.parametrize("kw, name", [
    ({"columns": {"load": "Load"}}, "columns"), ({"units": {"force": ""}}, "units"),
    ({"force_sign": "positive"}, "force_sign"), ({"displacement_sign": "down"}, "displacement_sign"),
])
def test_bad_override_is_input_error(tmp_path, kw, name):
    with pytest.raises(InputError, match=f"The '{name}' parameter"):
        read_curve(table(tmp_path, "time [s],displacement [um],force [mN]"), "displacement", **kw)


def test_units_override_of_unknown_unit(tmp_path):
    with pytest.raises(InputError, match="units force"):
        read_curve(table(tmp_path, "time [s],displacement [um],force [mN]"), "displacement",
                   units={"force": "kPa"})


def test_displacement_sign_only_under_displacement_control(tmp_path):
    with pytest.raises(InputError, match="displacement control only"):
        read_curve(table(tmp_path, "time [s],pressure [kPa],force [mN]"), "pressure",
                   displacement_sign="away-positive")


# ---------------------------------------------------------------------------------------------
# overrides change what they say, nothing else
def test_units_override_beats_the_file(tmp_path, clean):
    c = read_curve(table(tmp_path, "time [s],displacement [mm],force [mN]"), "displacement",
                   units={"displacement": "um"})
    np.testing.assert_allclose(c.x, clean.x, rtol=1e-12)
    assert c.units["displacement"] == "um"


def test_sign_overrides(tmp_path, clean):
    neg = lambda v: v[1:] if v.startswith("-") else "-" + v  # noqa: E731 - exact negation of a decimal
    path = table(tmp_path, "time [s],displacement [um],force [mN]", lambda t, d, f: f"{t},{neg(d)},{neg(f)}")
    msg = refused(path)
    assert "no unloading" in msg and "--displacement-sign away-positive" in msg
    c = read_curve(path, "displacement", force_sign="tensile-positive", displacement_sign="away-positive")
    np.testing.assert_array_equal(c.x, clean.x)
    np.testing.assert_array_equal(c.force, clean.force)
    assert "force sign tensile-positive" in c.layout and "displacement sign away-positive" in c.layout


# ---------------------------------------------------------------------------------------------
# other file shapes
def test_metadata_with_numbers_and_comments_above(tmp_path, clean):
    pre = "# exported by rig 3\nSample rate,10,Hz\nOperator,lab\n\n"
    c = read_curve(table(tmp_path, "time [s],displacement [um],force [mN]", pre=pre), "displacement")
    np.testing.assert_allclose(c.force, clean.force, rtol=1e-12)
    assert c.excluded == ((1, "comment line"), (2, "metadata above the header"),
                          (3, "metadata above the header"), (4, "blank line"))


def test_no_header_line(tmp_path):
    path = tmp_path / "bare.csv"
    path.write_text("\n".join(",".join(r) for r in ROWS) + "\n")
    msg = refused(path)
    assert "no header line above the first data row (line 1)" in msg


def test_decimal_comma_file_with_a_point(tmp_path):
    path = table(tmp_path, "time [s];displacement [um];force [mN]",
                 lambda t, d, f: ";".join(v.replace(".", ",") for v in (t, d, f)))
    lines = path.read_text().splitlines()
    lines[7] = lines[7].rsplit(";", 1)[0] + ";0.5"
    path.write_text("\n".join(lines) + "\n")
    msg = refused(path)
    assert "line 8, column 'force [mN]': '0.5' is not a number (this file writes decimal commas)" in msg


def test_lvm_rows_without_the_empty_comment_cell(tmp_path, clean):
    text = (HERE / "labview.lvm").read_text().replace("\t\n", "\n")
    path = tmp_path / "short.lvm"
    path.write_text(text)
    np.testing.assert_allclose(read_curve(path, "displacement").force, clean.force, rtol=1e-12)


def test_lvm_with_two_segments(tmp_path):
    text = (HERE / "labview.lvm").read_text()
    head = text[text.index("Channels"):text.index("X_Value")]
    path = tmp_path / "two.lvm"
    path.write_text(text + head + text[text.index("X_Value"):])
    assert "LabVIEW file with 2 data segments" in refused(path)


def test_pressure_control_export(tmp_path):
    """A pressure-controlled Bluehill-style export: units row, 'Pressure' and 'Load'."""
    p = [0.2, 0.6, 1.0, 1.4, 1.0, 0.6, 0.2, -0.2, -0.6, -1.0]
    f = [0, 1, 2, 3, 2, 1, 0, -1, -0.5, 0]
    path = tmp_path / "p.csv"
    path.write_text('"Test","p-1"\n"Pressure","Load","Cycle"\n"(kPa)","(N)",""\n'
                    + "\n".join(f'"{a}","{b}","1"' for a, b in zip(p, f)) + "\n")
    c = read_curve(path, "pressure")
    np.testing.assert_allclose(c.pressure, np.array(p) * 1e3)
    np.testing.assert_allclose(c.force, f)
    assert c.ignored_columns == (("Cycle", "not a column adhfit reads"),)


# ---------------------------------------------------------------------------------------------
# the command line: flags parsed, ambiguity one line and exit 2 before any fitting
def test_cli_ambiguous_file_one_line(tmp_path, capsys):
    path = table(tmp_path, "Time [s],Position [um],Load [mN],Standard force [mN]", lambda t, d, f: f"{t},{d},{f},{f}")
    code = main(["fit", str(path), "--scene", str(HERE / "scene.toml"), "-o", str(tmp_path / "out")])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1 and "--columns force=NAME" in err


def test_cli_flags_parse():
    from adhfit.cli.main import _build_parser  # noqa: PLC0415
    from adhfit.cli.arguments import read_options  # noqa: PLC0415
    args = _build_parser().parse_args(["fit", "x.csv", "--columns", "force=Load 2, displacement=Position",
                                       "--units", "displacement=mm,force=N", "--force-sign", "tensile-positive"])
    assert read_options(args) == {"columns": {"force": "Load 2", "displacement": "Position"},
                                  "units": {"displacement": "mm", "force": "N"}, "force_sign": "tensile-positive"}
    assert read_options(_build_parser().parse_args(["fit", "x.csv"])) == {}


def test_cli_bad_pairs_one_line(capsys):
    code = main(["fit", "x.csv", "--columns", "force"])
    err = capsys.readouterr().err
    assert code == 2 and "--columns takes KEY=VALUE pairs" in err


@pytest.mark.parametrize("units_row", ["(s),(um),(mN)", "s,um,mN"])
def test_units_row_under_unknown_names(tmp_path, clean, units_row):
    """A units row is recognised by its units when the header names nothing adhfit knows."""
    path = table(tmp_path, "t,s,F\n" + units_row, pre="Test,1\n")
    c = read_curve(path, "displacement", columns={"force": "F", "displacement": "s"})
    np.testing.assert_allclose(c.force, clean.force, rtol=1e-12)
    np.testing.assert_allclose(c.x, clean.x, rtol=1e-12)
    assert c.excluded == ((1, "metadata above the header"), (3, "units row"))
