"""Hostile and mistaken inputs: each a named one-line error, fast, with long values cut when echoed.

Each case failed on the code before this file: a 10^6-character unit parsed for hours (pint's parser
is quadratic), a CSV field over 131,072 characters and a TOML scene nested 1,000 deep gave 'internal
error', a megabyte cell was echoed in full, and a membrane radius written as a plain number was
blamed on the pressure's unit.
"""
from __future__ import annotations

import re
import time

import numpy as np
import pytest

from adhfit.data import read_curve
from adhfit.errors import ECHO_LIMIT, DataError, InputError, clip, shown
from adhfit.readers.text import MAX_LINE_CHARS
from adhfit.scene import PLAIN_LENGTH_MAX, load_scene
from adhfit.units import MAX_UNIT_CHARS, is_unit, parse_quantity, unit_factor

#: a message may quote a few cut values and the columns found; a megabyte is never in it
SHORT = 1500
#: seconds: every refusal below is a length check, done before any parsing (pint took hours)
QUICK = 5.0

N = 12
X = np.r_[np.linspace(0.0, 0.4, N), np.linspace(0.38, 0.1, N)]
F = np.r_[np.linspace(0.0, 2.0, N), np.linspace(1.8, -0.5, N)]


def _csv(tmp_path, header="displacement [mm],force [N]", rows=None, above=""):
    rows = rows if rows is not None else [f"{x},{f}" for x, f in zip(X, F)]
    path = tmp_path / "curve.csv"
    path.write_text(above + header + "\n" + "\n".join(rows) + "\n", encoding="utf-8")
    return path


def _refused(call, match, exc=DataError):
    t0 = time.perf_counter()
    with pytest.raises(exc, match=match) as err:
        call()
    elapsed = time.perf_counter() - t0
    msg = str(err.value)
    assert elapsed < QUICK, f"took {elapsed:.1f} s"
    assert len(msg) < SHORT and "\n" not in msg, msg[:300]
    return msg


# ---------------------------------------------------------------------------------------------
# the echo helper
def test_shown_and_clip_cut_long_values_and_say_how_long():
    assert shown("kPa") == "'kPa'" and clip("Load (N)") == "Load (N)"
    long = "x" * 1_000_000
    assert len(shown(long)) < ECHO_LIMIT + 30 and "1000000 characters" in shown(long)
    assert len(clip(long)) < ECHO_LIMIT + 30 and "1000000 characters" in clip(long)
    deep: list = []
    for _ in range(5000):
        deep = [deep]
    assert "nested too deeply" in shown(deep)


def test_input_error_cuts_a_megabyte_value():
    msg = str(InputError("units", "m" * 1_000_000, "a unit of length"))
    assert len(msg) < 300 and "1000000 characters" in msg


# ---------------------------------------------------------------------------------------------
# units
@pytest.mark.parametrize("length", [MAX_UNIT_CHARS + 1, 10_000, 1_000_000])
def test_a_long_unit_is_refused_before_pint_parses_it(length):
    unit = ("m*" * length)[:length - 1] + "m"
    _refused(lambda: unit_factor(unit, "length", name="units displacement"),
             rf"longer than the {MAX_UNIT_CHARS} a unit may have", InputError)
    t0 = time.perf_counter()
    assert not is_unit(unit)
    assert time.perf_counter() - t0 < QUICK


def test_the_longest_real_units_still_parse():
    assert unit_factor("kilogram_force / centimeter ** 2", "pressure", name="x") == pytest.approx(98066.5)


def test_a_long_value_string_is_refused_by_name():
    msg = _refused(lambda: parse_quantity("1 " + "m*" * 500_000 + "m", "length", name="membrane_radius"),
                   "'membrane_radius' parameter must be a length", InputError)
    assert "1,000,003 characters" in msg


def test_a_long_unit_in_a_header_names_the_column(tmp_path):
    path = _csv(tmp_path, header=f"displacement [{'m*' * 2000}m],force [N]")
    _refused(lambda: read_curve(path, "displacement"),
             r"line 1, column 'displacement \[m\*m\*.*characters\)': unit .* longer than the 64")


def test_a_long_unit_override_names_the_override(tmp_path):
    path = _csv(tmp_path, header="displacement,force [N]")
    _refused(lambda: read_curve(path, "displacement", units={"displacement": "m*" * 50_000 + "m"}),
             "'units displacement' parameter must be a unit of a length", InputError)


def test_a_long_cell_under_the_header_is_not_parsed_as_a_unit(tmp_path):
    """Under a header of unknown names, a line is a units row when pint reads every cell as a unit."""
    path = _csv(tmp_path, header="x,y\nmm," + "m*" * 25_000 + "m")
    msg = _refused(lambda: read_curve(path, "displacement"), r"line 2: missing column 'displacement")
    assert "50001 characters" in msg


# ---------------------------------------------------------------------------------------------
# long lines and cells in curve files
@pytest.mark.parametrize("where", ["data", "metadata", "header"])
def test_a_field_over_the_csv_limit_is_a_named_error(tmp_path, where):
    huge = "z" * 200_000  # Python's csv refuses fields over 131,072 characters: an 'internal error' before
    rows = [f"{x},{f}" for x, f in zip(X, F)]
    if where == "data":
        rows[3] = f"{X[3]},{huge}"
        path, line = _csv(tmp_path, rows=rows), 5
    elif where == "metadata":
        path, line = _csv(tmp_path, above=f"Sample,{huge}\n"), 1
    else:
        path, line = _csv(tmp_path, header=f"displacement [mm],force [N],{huge}"), 1
    _refused(lambda: read_curve(path, "displacement"),
             rf"line {line}: line of 200,0\d\d characters, longer than the {MAX_LINE_CHARS:,}")


def test_a_long_bad_cell_is_echoed_cut(tmp_path):
    rows = [f"{x},{f}" for x, f in zip(X, F)]
    rows[2] = f"{X[2]},{'q' * 60_000}"
    msg = _refused(lambda: read_curve(_csv(tmp_path, rows=rows), "displacement"),
                   r"line 4, column 'force \[N\]': 'qqq.*' \(60000 characters\) is not a number")
    assert "q" * 200 not in msg


def test_a_long_header_cell_is_echoed_cut(tmp_path):
    path = _csv(tmp_path, header=f"displacement [mm],{'F' * 60_000} [N]")
    msg = _refused(lambda: read_curve(path, "displacement"), "missing column 'force")
    assert "F" * 200 not in msg


def test_a_header_of_thousands_of_columns_is_summarised(tmp_path):
    header = "displacement [mm]," + ",".join(f"c{j}" for j in range(5000))
    rows = [f"{x}," + ",".join(["1"] * 5000) for x in X]
    msg = _refused(lambda: read_curve(_csv(tmp_path, header=header, rows=rows), "displacement"),
                   r"missing column 'force.*and 4989 more")
    assert "c4999" not in msg


# ---------------------------------------------------------------------------------------------
# scene files
SCENE = """[membrane]
radius = "2 mm"
prestretch = 2.0
[substrate]
radius = "1 mm"
[test]
control = "displacement"
pressure = "1.2 kPa"
"""


def _scene(tmp_path, text):
    path = tmp_path / "scene.toml"
    path.write_text(text, encoding="utf-8")
    return path


@pytest.mark.parametrize("nested", ["[" * 1000 + "]" * 1000, "{a = " * 1000 + "1" + "}" * 1000])
def test_toml_nested_1000_deep_is_a_named_error(tmp_path, nested):
    path = _scene(tmp_path, SCENE + f"[interface]\nslip = {nested}\n")
    _refused(lambda: load_scene(path), "scene.toml: tables or arrays nested too deeply")


def test_dotted_keys_1000_deep_are_a_named_error(tmp_path):
    path = _scene(tmp_path, SCENE.replace('radius = "2 mm"', "radius." + ".".join(["a"] * 1000) + " = 1"))
    _refused(lambda: load_scene(path), r"\[membrane\] radius must be a length")


def test_a_megabyte_scene_value_is_cut(tmp_path):
    path = _scene(tmp_path, SCENE.replace('"1.2 kPa"', '"1.2 ' + "k" * 500_000 + 'Pa"'))
    msg = _refused(lambda: load_scene(path), r"scene.toml, line 8: \[test\] pressure must be a pressure")
    assert "k" * 200 not in msg


@pytest.mark.parametrize("extra", ["[" + "s" * 500_000 + "]\nx = 1\n", "k" * 500_000 + " = 1\n",
                                   "[priors]\n" + "p" * 500_000 + " = {dist = 'uniform', min = 0, max = 1}\n"])
def test_a_long_section_key_or_prior_name_is_cut(tmp_path, extra):
    text = SCENE.replace("control =", extra + "control =") if extra.startswith("k") else SCENE + extra
    msg = _refused(lambda: load_scene(_scene(tmp_path, text)), "500000 characters")
    assert "k" * 200 not in msg and "s" * 200 not in msg and "p" * 200 not in msg


def test_a_huge_scene_file_is_refused(tmp_path):
    path = _scene(tmp_path, SCENE + "# " + "x" * 2_000_000 + "\n")
    _refused(lambda: load_scene(path), "is this the scene file")


@pytest.mark.parametrize("key, line, old, new", [
    ("[membrane] radius", 2, 'radius = "2 mm"\nprestretch', "radius = 2\nprestretch"),
    ("[substrate] radius", 5, 'radius = "1 mm"\n[test]', "radius = 1\n[test]"),
])
def test_a_bare_length_names_its_own_setting(tmp_path, key, line, old, new):
    """'radius = 2' is read as 2 m; the pressure's unit was blamed for it."""
    path = _scene(tmp_path, SCENE.replace(old, new))
    msg = _refused(lambda: load_scene(path), rf"scene.toml, line {line}: {re.escape(key)} = \d is a plain number, "
                                             "so it is read in metres")
    assert "pressure" not in msg and ("radius = '2 mm'" in msg or "radius = '1 mm'" in msg)


@pytest.mark.parametrize("old, new, expected", [
    ('radius = "2 mm"\nprestretch', "radius = 0.002\nprestretch", 0.002),  # SI plain numbers still work
    ('radius = "2 mm"\nprestretch', 'radius = "0.5 m"\nprestretch', 0.5),  # a unit says metres on purpose
])
def test_plain_si_lengths_and_explicit_metres_still_load(tmp_path, old, new, expected):
    scene = load_scene(_scene(tmp_path, SCENE.replace(old, new).replace('radius = "1 mm"', "radius = inf")))
    assert scene.membrane_radius == pytest.approx(expected)
    assert scene.substrate_radius == float("inf")
    assert PLAIN_LENGTH_MAX < 0.5
