"""Tests of adhfit.data: measured curves from CSV (docs/contracts.md A4)."""
from __future__ import annotations

import hashlib

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from adhfit.data import MIN_ROWS, Curve, read_curve
from adhfit.errors import DataError, InputError
from adhfit.units import ureg

# A displacement-controlled curve: loading to 40 um, unloading past pull-off.  Row 9 (after the
# turning point) has the same displacement as row 3 on loading, as happens around a pull-off jump.
DISP = [0, 10, 20, 30, 40, 30, 20, 20, 10, 5, 0, -5]
FORCE = [0.0, 0.5, 1.2, 2.0, 3.1, 2.0, 0.8, -0.2, -0.5, -1.0, -1.1, 0.0]


def csv_text(header="displacement [um],force [mN]", x=DISP, f=FORCE, sep=","):
    return "\n".join([header] + [f"{a}{sep}{b}" for a, b in zip(x, f)]) + "\n"


@pytest.fixture
def write(tmp_path):
    def _write(text, name="curve.csv", mode="w"):
        path = tmp_path / name
        if isinstance(text, bytes):
            path.write_bytes(text)
        else:
            path.write_text(text, encoding="utf-8", newline="")
        return path
    return _write


def error(write, text, control="displacement") -> DataError:
    path = write(text)
    with pytest.raises(DataError) as info:
        read_curve(path, control)
    assert info.value.path == str(path)
    assert str(info.value).startswith(str(path))
    return info.value


# ---------------------------------------------------------------------------------------------
# reading
def test_displacement_curve_in_si(write):
    path = write(csv_text())
    c = read_curve(path, "displacement")
    assert isinstance(c, Curve) and len(c) == len(DISP)
    np.testing.assert_allclose(c.x, np.array(DISP) * 1e-6, rtol=1e-12)
    np.testing.assert_allclose(c.force, np.array(FORCE) * 1e-3, rtol=1e-12)
    assert c.displacement is c.x and c.pressure is None
    assert c.time is None and c.contact_radius is None
    assert c.line.tolist() == list(range(2, 2 + len(DISP)))
    assert c.i_turn == 4 and c.loading == slice(0, 5) and c.unloading == slice(4, None)
    assert c.excluded == ()
    assert c.sha256 == hashlib.sha256(path.read_bytes()).hexdigest()
    assert dict(c.units) == {"displacement": "um", "force": "mN"}
    assert c.control == "displacement" and c.path == str(path)


def test_arrays_are_read_only_copies(write):
    c = read_curve(write(csv_text()), "displacement")
    for a in (c.x, c.force, c.line):
        with pytest.raises(ValueError):
            a[0] = 1.0
    with pytest.raises(TypeError):
        c.units["force"] = "N"  # type: ignore[index]


def test_pressure_curve_with_optional_columns(write):
    p = [0.2, 0.6, 1.0, 1.4, 1.0, 0.6, 0.2, -0.2, -0.6, -1.0]
    rows = "\n".join(f"{i * 0.5},{pi},{fi},{ri}" for i, (pi, fi, ri) in
                     enumerate(zip(p, [0, 1, 2, 3, 2, 1, 0, -1, -0.5, 0], [0, 50, 100, 150, 150, 150, 120, 80, 30, 0])))
    c = read_curve(write("time [ms],pressure [kPa],force [N],contact_radius [mm]\n" + rows + "\n"), "pressure")
    np.testing.assert_allclose(c.pressure, np.array(p) * 1e3)
    np.testing.assert_allclose(c.time, np.arange(10) * 0.5e-3)
    assert c.contact_radius[1] == pytest.approx(0.05)
    assert c.i_turn == 3 and c.displacement is None
    frame = c.to_frame()
    assert list(frame.columns) == ["line", "pressure [Pa]", "force [N]", "time [s]", "contact_radius [m]",
                                   "loading"]
    assert frame["loading"].sum() == 4


def test_turning_point_by_row_order_first_maximum(write):
    x = [0, 10, 20, 40, 40, 30, 20, 10, 0, -5, -10]
    c = read_curve(write(csv_text(x=x, f=range(len(x)))), "displacement")
    assert c.i_turn == 3  # first occurrence of the maximum


@pytest.mark.parametrize("dunit, funit, dscale, fscale", [
    ("um", "mN", 1e-6, 1e-3), ("µm", "uN", 1e-6, 1e-6), ("μm", "N", 1e-6, 1.0), ("mm", "gf", 1e-3, 9.80665e-3),
    ("nm", "kN", 1e-9, 1e3), ("m", "mN", 1.0, 1e-3),
])
def test_units_are_converted(write, dunit, funit, dscale, fscale):
    c = read_curve(write(csv_text(header=f"displacement [{dunit}], force [{funit}]")), "displacement")
    np.testing.assert_allclose(c.x, np.array(DISP) * dscale, rtol=1e-12)
    np.testing.assert_allclose(c.force, np.array(FORCE) * fscale, rtol=1e-12)


@given(values=st.lists(st.floats(-1e3, 1e3, allow_nan=False), min_size=MIN_ROWS, max_size=30),
       unit=st.sampled_from(["um", "mm", "nm", "in", "thou"]))
@settings(suppress_health_check=[HealthCheck.function_scoped_fixture], max_examples=40)
def test_round_trip_through_units(write, values, unit):
    """SI -> file in `unit` (converted by pint) -> read_curve -> the same SI values."""
    si = np.array(values) * 1e-6
    x = np.concatenate([[0.0], np.abs(si).cumsum() + 1e-6, [0.0]])   # loading then one unloading row
    in_unit = ureg.Quantity(x, "m").to(unit).magnitude
    text = csv_text(header=f"displacement [{unit}],force [N]", x=[repr(float(v)) for v in in_unit], f=range(len(x)))
    c = read_curve(write(text), "displacement")
    np.testing.assert_allclose(c.x, x, rtol=1e-12, atol=1e-300)


@pytest.mark.parametrize("sep", [";", "\t"])
def test_other_separators(write, sep):
    header = f"displacement [um]{sep}force [mN]"
    c = read_curve(write(csv_text(header=header, sep=sep)), "displacement")
    np.testing.assert_allclose(c.force, np.array(FORCE) * 1e-3)


def test_crlf_and_bom_keep_line_numbers(write):
    text = csv_text().replace("\n", "\r\n")
    c = read_curve(write(b"\xef\xbb\xbf" + text.encode()), "displacement")
    assert c.line[0] == 2 and c.line[-1] == 1 + len(DISP)


def test_blank_and_comment_lines_are_listed(write):
    lines = csv_text().splitlines()
    lines.insert(0, "# rig 3, sample A")
    lines.insert(4, "")
    lines.insert(8, "   # pull-off jump next")
    lines.append("")
    c = read_curve(write("\n".join(lines) + "\n"), "displacement")
    assert c.excluded == ((1, "comment line"), (5, "blank line"), (9, "comment line"),
                          (len(lines), "blank line"))
    assert len(c) == len(DISP)


@given(inserts=st.lists(st.tuples(st.integers(1, len(DISP)), st.sampled_from(["", "# note", "  "])),
                        max_size=6))
@settings(suppress_health_check=[HealthCheck.function_scoped_fixture], max_examples=30)
def test_no_line_is_dropped_silently(write, inserts):
    lines = csv_text().splitlines()
    for pos, text in inserts:
        lines.insert(pos, text)
    c = read_curve(write("\n".join(lines) + "\n"), "displacement")
    header = lines.index("displacement [um],force [mN]") + 1
    accounted = {header, *c.line.tolist(), *(n for n, _ in c.excluded)}
    assert accounted == set(range(1, len(lines) + 1))
    assert len(c) == len(DISP)


# ---------------------------------------------------------------------------------------------
# errors: file level
def test_missing_file(tmp_path):
    with pytest.raises(DataError, match="cannot read the file") as info:
        read_curve(tmp_path / "none.csv", "displacement")
    assert info.value.path.endswith("none.csv")


@pytest.mark.parametrize("text", ["", "   \n\n"])
def test_empty_file(write, text):
    assert str(error(write, text)).endswith(": the file is empty")


def test_only_comments(write):
    assert "no header line" in str(error(write, "# nothing\n\n# here\n"))


def test_bad_control_is_input_error(write):
    with pytest.raises(InputError, match="The 'control' parameter must be one of 'displacement', 'pressure'"):
        read_curve(write(csv_text()), "force")


# errors: header
def test_header_without_unit(write):
    err = error(write, csv_text(header="displacement [um],force"))
    assert err.line == 1 and err.column == "force"
    assert "bad header 'force': columns must be written 'name [unit]', e.g. 'force [mN]'" in str(err)


def test_unit_of_wrong_dimension(write):
    err = error(write, csv_text(header="displacement [um],force [kPa]"))
    assert str(err).endswith("line 1, column 'force [kPa]': unit kPa is not a force (e.g. 'mN')")


def test_unit_not_understood(write):
    err = error(write, csv_text(header="displacement [furlongz],force [mN]"))
    assert err.column == "displacement [furlongz]" and "not understood" in str(err)


def test_unknown_column_suggests_and_lists(write):
    err = error(write, csv_text(header="displacment [um],force [mN]"))
    msg = str(err)
    assert err.column == "displacment [um]" and "unknown column; did you mean 'displacement'?" in msg
    assert "found 'displacment [um]', 'force [mN]'" in msg
    assert "expected 'displacement [um]', 'force [mN]'" in msg and "optional: 'time [s]'" in msg


def test_column_of_other_control(write):
    err = error(write, csv_text(header="displacement [um],force [mN]"), control="pressure")
    assert "unknown column (it belongs to control = 'displacement', not 'pressure')" in str(err)


def test_missing_column(write):
    text = "time [s],force [mN]\n" + "\n".join(f"{i},{i}" for i in range(12))
    err = error(write, text)
    msg = str(err)
    assert "missing column 'displacement [um]' (any length unit) for control = 'displacement'" in msg
    assert "found 'time [s]', 'force [mN]'" in msg
    err = error(write, "pressure [kPa],time [s]\n" + "\n".join(f"{i},{i}" for i in range(12)), "pressure")
    assert "missing column 'force [mN]' (any force unit) for control = 'pressure'" in str(err)


def test_duplicate_column(write):
    err = error(write, "displacement [um],force [mN],force [N]\n" + "1,2,3\n" * 12)
    assert "duplicate column 'force'" in str(err) and err.column == "force [N]"


# errors: cells and rows
def replace_row(text: str, row: int, new: str) -> str:
    lines = text.splitlines()
    lines[row] = new
    return "\n".join(lines) + "\n"


@pytest.mark.parametrize("cell, fragment", [
    ("abc", "'abc' is not a number"),
    ("", "empty cell"),
    ("  ", "empty cell"),
    ("nan", "'nan' is not a finite number"),
    ("NaN", "'NaN' is not a finite number"),
    ("inf", "'inf' is not a finite number"),
    ("1_0", "'1_0' is not a plain decimal number"),
    ("1.2.3", "'1.2.3' is not a number"),
])
def test_bad_cell_names_line_and_column(write, cell, fragment):
    err = error(write, replace_row(csv_text(), 6, f"30,{cell}"))
    assert err.line == 7 and err.column == "force [mN]"
    assert f"line 7, column 'force [mN]': {fragment}" in str(err)


def test_brief_example_message_and_first_bad_cell_in_file_order(write):
    text = csv_text()
    for _ in range(5):
        text += "1,1\n"
    text = replace_row(text, 16, "abc,abc")   # line 17, both columns
    text = replace_row(text, 15, "1,abc")     # line 16, force only: first in file order
    err = error(write, text)
    assert str(err).endswith("line 16, column 'force [mN]': 'abc' is not a number (2 more bad cells in the file)")
    text = replace_row(text, 15, "1,1")
    assert "line 17, column 'displacement [um]': 'abc' is not a number" in str(error(write, text))


def test_decimal_comma_hint(write):
    text = csv_text(header="displacement [um];force [mN]", sep=";")
    err = error(write, replace_row(text, 3, "20;1,2"))
    assert "'1,2' is not a number (use a decimal point)" in str(err)


@pytest.mark.parametrize("row, n", [("30,2.0,", 3), ("30", 1)])
def test_wrong_number_of_cells(write, row, n):
    err = error(write, replace_row(csv_text(), 4, row))
    assert err.line == 5 and f"{n} cells, but the header has 2 columns (displacement, force)" in str(err)


@pytest.mark.parametrize("rows", ['30,"2.0\n"', '30,"2\n0"'])
def test_quoted_multiline_cell_refused(write, rows):
    err = error(write, csv_text().replace("30,2.0\n", rows + "\n", 1))
    assert err.line == 5 and "unbalanced quote" in str(err)


def test_quoted_cells_are_fine(write):
    c = read_curve(write(csv_text().replace("30,2.0\n", '"30","2.0"\n', 1)), "displacement")
    assert c.force[3] == pytest.approx(2e-3)


def test_too_few_rows(write):
    err = error(write, csv_text(x=[0, 1, 2, 3, 4, 3, 2, 1, 0], f=range(9)))
    assert str(err).endswith("only 9 data rows; at least 10 are needed (loading, then unloading)")


def test_no_unloading(write):
    err = error(write, csv_text(x=range(12), f=range(12)))
    assert "no unloading: the largest displacement (line 13)" in str(err)
    assert err.column == "displacement [um]" and err.line == 13
    err = error(write, csv_text(x=[*range(10), 9, 9], f=range(12)))   # plateau at the end
    assert "no unloading" in str(err)


def test_no_loading(write):
    err = error(write, csv_text(x=range(12, 0, -1), f=range(12)))
    assert "no loading: the largest displacement (line 2) is the first row" in str(err)


def test_time_must_run_forward(write):
    t = [0, 1, 2, 3, 4, 5, 4, 7, 8, 9, 10, 11]
    text = "displacement [um],force [mN],time [s]\n" + "\n".join(
        f"{a},{b},{c}" for a, b, c in zip(DISP, FORCE, t))
    err = error(write, text)
    assert err.line == 8 and err.column == "time [s]" and "time runs backwards" in str(err)


def test_negative_contact_radius(write):
    r = [0, 1, 2, 3, 4, 4, 4, -1, 3, 2, 1, 0]
    text = "displacement [um],force [mN],contact_radius [um]\n" + "\n".join(
        f"{a},{b},{c}" for a, b, c in zip(DISP, FORCE, r))
    err = error(write, text)
    assert err.line == 9 and "negative contact radius" in str(err)


def test_curve_constructor_validates():
    with pytest.raises(InputError, match="'force' parameter"):
        Curve(path="x", control="displacement", x=[1.0, 2.0], force=[1.0], line=[2, 3], i_turn=1)
    with pytest.raises(InputError, match="'i_turn' parameter"):
        Curve(path="x", control="displacement", x=[1.0, 2.0], force=[1.0, 2.0], line=[2, 3], i_turn=2)


def test_latin1_file_with_micro_sign(write):
    text = csv_text(header="displacement [\xb5m],force [mN]").encode("latin-1")
    c = read_curve(write(text), "displacement")
    np.testing.assert_allclose(c.x, np.array(DISP) * 1e-6)
    assert c.sha256 == hashlib.sha256(text).hexdigest()


def test_header_only(write):
    assert "only 0 data rows" in str(error(write, "displacement [um],force [mN]\n"))


def test_repr_is_short(write):
    c = read_curve(write(csv_text()), "displacement")
    assert repr(c).endswith("control='displacement', rows=12, i_turn=4, excluded=0, "
                            "columns=['displacement', 'force'])")
