"""Data that are not what they seem (adhfit.fitting.plausibility): each check fires on a constructed bad
curve, names the column, the value and the fix in one sentence, and stays silent on the clean samples."""
from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from adhfit.data import read_curve
from adhfit.errors import DataError
from adhfit.fitting.api import fit as fit_curve
from adhfit.fitting.plausibility import check_curve, compress_lines
from adhfit.scene import load_scene

SAMPLES = Path(__file__).resolve().parents[1] / "sample_data"
ALL = sorted(p.name for p in SAMPLES.iterdir() if (p / "curve.csv").is_file())
DISP = SAMPLES / "fea_displacement_no-slip"
PRES = SAMPLES / "fea_pressure_no-slip"


def _load(folder: Path, csv: Path | None = None, scene: Path | None = None):
    sc = load_scene(scene or folder / "scene.toml")
    return read_curve(csv or folder / "curve.csv", sc.control), sc


def _rewrite(tmp_path: Path, folder: Path, old: str, new: str) -> Path:
    out = tmp_path / f"{folder.name}.csv"
    out.write_text((folder / "curve.csv").read_text().replace(old, new))
    return out


@pytest.mark.parametrize("name", ALL)
def test_clean_samples_pass_unchanged_and_without_warnings(name):
    curve, scene = _load(SAMPLES / name)
    checked, warnings = check_curve(curve, scene)
    assert warnings == []
    assert checked is curve  # nothing left out


def test_compress_lines_writes_runs_as_ranges():
    assert compress_lines([3, 5, 7, 9, 20]) == "3–9 (every 2nd line), 20"
    assert compress_lines([4, 5, 6, 10, 12]) == "4–6, 10, 12"
    assert compress_lines([8]) == "8"


def test_every_row_twice_is_left_out_named_and_fits_as_the_clean_file(tmp_path):
    lines = (DISP / "curve.csv").read_text().splitlines()
    twice = tmp_path / "twice.csv"
    twice.write_text("\n".join([lines[0]] + [row for row in lines[1:] for _ in (0, 1)]) + "\n")
    curve, scene = _load(DISP, csv=twice)
    checked, warnings = check_curve(curve, scene)
    n = len(lines) - 1
    # the header is line 1, row k is written on lines 2k and 2k + 1: the odd lines 3 .. 2n + 1 repeat
    assert [ln for ln, _ in checked.excluded] == list(range(3, 2 * n + 2, 2))
    assert checked.excluded[0][1] == "repeats line 2 in every column"
    assert len(warnings) == 1 and f"lines 3–{2 * n + 1} (every 2nd line)" in warnings[0]
    clean, _ = _load(DISP)
    np.testing.assert_array_equal(checked.force, clean.force)
    assert checked.i_turn == clean.i_turn
    # end to end: the same estimates and the same (not √2 narrower) intervals as the clean file
    kw = dict(slip="no-slip", profile=False)
    a, b = fit_curve(clean, scene, **kw), fit_curve(curve, scene, **kw)
    for key in ("work_of_adhesion", "mu_h"):
        assert b.parameters[key].value == pytest.approx(a.parameters[key].value, rel=1e-9)
        assert b.parameters[key].stderr == pytest.approx(a.parameters[key].stderr, rel=1e-6)
    assert b.n_points == a.n_points and b.n_excluded == n
    assert any("every 2nd line" in w for w in b.warnings)


def test_a_single_repeated_row_is_left_out_and_the_rest_kept():
    curve, scene = _load(DISP)
    k = 30
    idx = np.insert(np.arange(len(curve)), k + 1, k)  # row k written again right after itself
    line = np.arange(2, len(idx) + 2)
    twice = dataclasses.replace(curve, x=curve.x[idx], force=curve.force[idx], time=curve.time[idx], line=line,
                                i_turn=int(np.argmax(curve.x[idx])))
    checked, warnings = check_curve(twice, scene)
    assert checked.excluded == ((k + 3, f"repeats line {k + 2} in every column"),)
    assert len(checked) == len(curve) and warnings[0].startswith(f"line {k + 3} repeats")


def test_a_row_repeated_in_some_columns_only_is_kept():
    curve, scene = _load(DISP)
    force = curve.force.copy()
    force[11] = force[10]  # same force, but the displacement moved on: a real reading
    checked, warnings = check_curve(dataclasses.replace(curve, force=force), scene)
    assert len(checked) == len(curve) and warnings == []


@pytest.mark.parametrize("folder", [DISP, PRES])
def test_a_force_zero_far_off_is_named_but_a_small_one_is_not(folder):
    curve, scene = _load(folder)
    span = float(np.ptp(curve.force))
    _, small = check_curve(dataclasses.replace(curve, force=curve.force + 0.015 * curve.force.max()), scene)
    assert small == []  # an un-tared cell at 1.5 % of the peak is the fitted offset's job
    _, warnings = check_curve(dataclasses.replace(curve, force=curve.force + 0.6 * span), scene)
    assert len(warnings) == 1
    assert "'force [mN]'" in warnings[0] and "tare" in warnings[0]
    # the zero, in the column's unit (mN): the shift, up to the median of the noisy baseline rows
    said = float(warnings[0].split(" reads ")[1].split(" mN")[0])
    assert said == pytest.approx(0.6 * span / 1e-3, abs=0.05 * span / 1e-3)


@pytest.mark.parametrize("folder", [DISP, PRES])
def test_a_reversed_force_sign_is_an_error_naming_the_option(folder):
    curve, scene = _load(folder)
    with pytest.raises(DataError, match=r"column 'force \[mN\]'.*--force-sign tensile-positive"):
        check_curve(dataclasses.replace(curve, force=-curve.force), scene)


def test_a_reversed_displacement_sign_is_an_error_naming_the_option():
    curve, scene = _load(DISP)
    x = -curve.x
    turn = int(np.argmax(x[:-1]))  # a Curve needs a row after its turn; the reader's own checks aside
    with pytest.raises(DataError, match=r"column 'displacement \[um\]'.*--displacement-sign away-positive"):
        check_curve(dataclasses.replace(curve, x=x, i_turn=turn), scene)


def test_a_displacement_in_furlong_names_the_column_unit_and_span(tmp_path):
    csv = _rewrite(tmp_path, DISP, "displacement [um]", "displacement [furlong]")
    curve, scene = _load(DISP, csv=csv)
    span_um = np.ptp(np.loadtxt(DISP / "curve.csv", delimiter=",", skiprows=1)[:, 1])
    span_km = span_um * 201.168 / 1e3  # one furlong is 201.168 m
    with pytest.raises(DataError) as err:
        check_curve(curve, scene)
    msg = str(err.value)
    assert "'displacement [furlong]'" in msg and f"{span_um:.3g} furlong" in msg and f"{span_km:.3g} km" in msg
    assert "b = 2 mm" in msg and "unit" in msg
    with pytest.raises(DataError, match="furlong"):  # the fit stops there, before any history is computed
        fit_curve(csv, DISP / "scene.toml")


def test_a_scene_pressure_in_the_wrong_unit_is_named(tmp_path):
    scene_file = tmp_path / "scene.toml"
    scene_file.write_text((DISP / "scene.toml").read_text().replace('"1.2 kPa"', '"1200 kPa"'))
    curve, scene = _load(DISP, scene=scene_file)
    with pytest.raises(DataError) as err:
        check_curve(curve, scene)
    msg = str(err.value)
    # |P|b/2 = 1.2e6 Pa * 2e-3 m / 2 = 1200 N/m
    assert str(scene_file) in msg and "[test] pressure" in msg and "1.2 MPa" in msg and "1.2e+03 N/m" in msg
    # the 1.2 kPa of the sample is inside the plausible range the message states
    bound_kpa = float(msg.split("below about ")[1].split(" kPa")[0])
    assert 1.2 < bound_kpa < 1200


def test_pressure_control_forces_in_the_wrong_unit_are_named(tmp_path):
    csv = _rewrite(tmp_path, PRES, "force [mN]", "force [N]")
    curve, scene = _load(PRES, csv=csv)
    with pytest.raises(DataError, match=r"column 'force \[N\]'.*π b²"):
        check_curve(curve, scene)
