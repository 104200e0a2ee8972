"""``adhfit simulate`` on the command line (docs/contracts.md A2): files, JSON, errors, scene input."""
from __future__ import annotations

import csv
import json
import math
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

import adhfit
from adhfit.cli import main

REPO = Path(__file__).resolve().parents[1]
COLUMNS = ["stage", "a", "alpha", "p", "d", "delta", "f", "G", "stable"]
STAGES = ["making_contact", "pinning", "delamination"]
SUMMARY_KEYS = {"f_max", "onset", "f_min", "turning_point"}
POINT_KEYS = {"f", "delta", "p", "a"}

DC = ["--control", "displacement", "--slip", "no-slip", "--p", "0.6", "--w", "0.2", "--rs", "0.5",
      "--a-max", "0.25"]
CASES = {
    "dc-curved-noslip": DC,
    "dc-flat-frictionless": ["--control", "displacement", "--slip", "frictionless", "--p", "0.6", "--w", "0.2",
                             "--rs", "inf", "--a-max", "0.25"],
    "pc-curved-noslip": ["--control", "pressure", "--slip", "no-slip", "--d", "0", "--w", "0.2", "--rs", "0.5",
                         "--a-max", "0.25"],
    "pc-flat-frictionless": ["--control", "pressure", "--slip", "frictionless", "--d", "0.2", "--w", "0.2",
                             "--rs", "inf", "--a-max", "0.25"],
    # reaches |p| > 1 (delta undefined) in no-slip pinning beyond theta_a = pi/2
    "pc-strong-adhesion": ["--control", "pressure", "--slip", "no-slip", "--d", "0.3", "--w", "3.0",
                           "--rs", "inf", "--a-max", "0.3"],
    "dc-delta-max": ["--control", "displacement", "--slip", "frictionless", "--p", "0.3", "--w", "0.5",
                     "--rs", "1", "--delta-max", "0.1"],
}


def _no_nan(text: str):
    def bad(c):
        raise AssertionError(f"non-finite constant {c} in JSON output")
    return json.loads(text, parse_constant=bad)


def _run(capsys, argv):
    code = main(["simulate", *argv])
    out, err = capsys.readouterr()
    return code, out, err


def _read_rows(path: Path):
    with path.open(newline="") as fh:
        rows = list(csv.reader(fh))
    return rows[0], rows[1:]


@pytest.mark.parametrize("case", list(CASES))
def test_csv_and_json(case, tmp_path, capsys):
    argv = CASES[case]
    out_csv = tmp_path / "sub" / "curve.csv"
    code, out, err = _run(capsys, [*argv, "-o", str(out_csv), "--json"])
    assert code == 0 and err == ""
    header, rows = _read_rows(out_csv)
    assert header == COLUMNS
    assert len(rows) >= 100

    # stage: only the three names, in history order
    stage_rank = [STAGES.index(r[0]) for r in rows]
    assert stage_rank[0] == 0 and stage_rank[-1] == 2 and set(stage_rank) == {0, 1, 2}
    assert all(b >= a for a, b in zip(stage_rank, stage_rank[1:]))
    # stable: true ... false, never back to true
    stable = [r[8] for r in rows]
    assert set(stable) <= {"true", "false"}
    k = stable.index("false")
    assert all(s == "true" for s in stable[:k]) and all(s == "false" for s in stable[k:])
    # numbers: every cell parses to a finite float, except delta, empty exactly where |p| > 1
    for r in rows:
        vals = [float(x) for i, x in enumerate(r[1:8]) if i != 4]
        assert all(math.isfinite(v) for v in vals), r
        p = float(r[3])
        assert (r[5] == "") == (abs(p) > 1), r
        if r[5] != "":
            assert math.isfinite(float(r[5]))
    # the CSV is the library's frame, to the last digit
    frame = pd.read_csv(out_csv, keep_default_na=True)
    control = argv[argv.index("--control") + 1]
    summary = _no_nan(out)
    assert isinstance(summary, dict) and set(summary) == SUMMARY_KEYS
    assert isinstance(summary["f_max"], float) and math.isfinite(summary["f_max"])
    for key in ("onset", "f_min", "turning_point"):
        assert set(summary[key]) == POINT_KEYS
        for q, v in summary[key].items():
            assert v is None and q == "delta" and abs(summary[key]["p"]) > 1 or math.isfinite(v), (key, q, v)
    f = frame.f.to_numpy()
    assert np.all(summary["f_min"]["f"] <= f + 1e-12)
    assert summary["f_min"]["f"] == pytest.approx(f.min(), abs=1e-8)
    ctrl = frame.delta.to_numpy() if control == "displacement" else frame.p.to_numpy()
    tp = summary["turning_point"]["delta" if control == "displacement" else "p"]
    # the least control value of the whole history (NaN delta rows, |p| > 1, carry no delta)
    ctrl = ctrl[~np.isnan(ctrl)]
    assert np.all(tp <= ctrl + 1e-12)
    assert tp == pytest.approx(ctrl.min(), abs=1e-8)
    assert summary["f_max"] == pytest.approx(frame.f[frame.stage == "making_contact"].iloc[-1], abs=1e-15)
    # the turning point is the last stable row
    last_stable = frame[frame.stable].iloc[-1]
    assert last_stable[("delta" if control == "displacement" else "p")] == pytest.approx(tp, abs=1e-12)


def test_csv_matches_python_api(tmp_path, capsys):
    out_csv = tmp_path / "c.csv"
    assert _run(capsys, [*DC, "-o", str(out_csv)])[0] == 0
    got = pd.read_csv(out_csv)
    want = adhfit.simulate("displacement", "no-slip", p=0.6, w=0.2, rs=0.5, a_max=0.25).frame
    assert list(got.stage) == list(want.stage) and list(got.stable) == list(want.stable)
    for col in ("a", "alpha", "p", "d", "delta", "f", "G"):
        np.testing.assert_array_equal(got[col].to_numpy(float), want[col].to_numpy(float))


@pytest.mark.parametrize("n", [10, 37, 200, 501])
def test_points_gives_about_n_rows(n, tmp_path, capsys):
    out_csv = tmp_path / "c.csv"
    assert _run(capsys, [*CASES["pc-flat-frictionless"], "--points", str(n), "-o", str(out_csv)])[0] == 0
    _, rows = _read_rows(out_csv)
    assert n <= len(rows) <= n + 5


def test_plot_writes_png(tmp_path, capsys):
    png = tmp_path / "out.png"
    code, out, err = _run(capsys, [*DC, "--plot", str(png)])
    assert code == 0 and err == ""
    data = png.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n" and len(data) > 2000


# ---------------------------------------------------------------------------------------------
# invalid input: exit 2, one line on stderr naming the parameter, no traceback
# ---------------------------------------------------------------------------------------------
def _replace(argv, opt, value):
    argv = list(argv)
    argv[argv.index(opt) + 1] = value
    return argv


def _drop(argv, opt):
    argv = list(argv)
    i = argv.index(opt)
    del argv[i:i + 2]
    return argv


PC_ARGS = CASES["pc-curved-noslip"]
BAD = {
    "p-above-one": (_replace(DC, "--p", "1.5"), "p", "1.5"),
    "p-not-a-number": (_replace(DC, "--p", "abc"), "--p", "abc"),
    "p-nan": (_replace(DC, "--p", "nan"), "--p", "nan"),
    "rs-negative": (_replace(DC, "--rs", "-1"), "rs", "-1"),
    "rs-zero": (_replace(DC, "--rs", "0"), "rs", "0"),
    "w-zero": (_replace(DC, "--w", "0"), "w", "0"),
    "w-missing": (_drop(DC, "--w"), "--w", None),
    "rs-missing": (_drop(DC, "--rs"), "--rs", None),
    "a-max-too-large": (_replace(DC, "--a-max", "0.48"), "a_max", "0.48"),
    "delta-max-under-pressure": ([*_drop(PC_ARGS, "--a-max"), "--delta-max", "0.1"], "delta_max", "0.1"),
    "p-max-under-displacement": ([*_drop(DC, "--a-max"), "--p-max", "0.7"], "p_max", "0.7"),
    "two-ends": ([*DC, "--delta-max", "0.1"], "--delta-max", None),
    "no-end": (_drop(DC, "--a-max"), "a_max", None),
    "p-under-pressure": ([*PC_ARGS, "--p", "0.5"], "--p", None),
    "missing-p": (_drop(DC, "--p"), "p", None),
    "bad-control": (_replace(DC, "--control", "force"), "--control", "force"),
    "bad-slip": (_replace(DC, "--slip", "sticky"), "--slip", "sticky"),
    "points-float": ([*DC, "--points", "12.5"], "--points", "12.5"),
    "points-small": ([*DC, "--points", "3"], "points", "3"),
    "lambda0-one": ([*DC, "--lambda0", "1"], "lambda0", "1"),
    "p-concave": (_replace(_replace(DC, "--p", "-0.1"), "--rs", "inf"), "p", "-0.1"),
}


@pytest.mark.parametrize("case", list(BAD))
def test_invalid_input_exit_2_one_line(case, capsys, tmp_path):
    argv, name, value = BAD[case]
    out_csv = tmp_path / "never.csv"
    code, out, err = _run(capsys, [*argv, "-o", str(out_csv), "--json"])
    assert code == 2, (code, err)
    assert out == "" and not out_csv.exists()
    lines = err.strip("\n").split("\n")
    assert len(lines) == 1 and lines[0].strip(), err
    assert "Traceback" not in err
    assert name in err, err
    if value is not None:
        assert value in err, err


# ---------------------------------------------------------------------------------------------
# scene input (docs/contracts.md A3) and the installed entry point
# ---------------------------------------------------------------------------------------------
SCENE = """\
[membrane]
radius = "2 mm"
prestretch = 2.0
mu_h = "2 N/m"

[substrate]
radius = "1 mm"

[test]
control = "displacement"
pressure = "1.2 kPa"
contact_radius_max = "0.5 mm"

[interface]
slip = "auto"
work_of_adhesion = "0.4 J/m^2"
"""


def test_scene_matches_dimensionless_run(tmp_path, capsys):
    # b = 2 mm, mu h = 2 N/m: p = 1.2 kPa * 2 mm / (4 N/m) = 0.6, w = 0.4/2 = 0.2, rs = 1/2, a_max = 0.5/2
    scene = tmp_path / "scene.toml"
    scene.write_text(SCENE)
    for slip in ("no-slip", "frictionless"):
        code, out, err = _run(capsys, ["--scene", str(scene), "--slip", slip, "--json", "--history",
                                        "-o", str(tmp_path / "s.csv")])
        assert code == 0, err
        code2, out2, err2 = _run(capsys, [*_replace(DC, "--slip", slip), "--json", "-o", str(tmp_path / "d.csv")])
        assert code2 == 0, err2
        a, b = _no_nan(out), _no_nan(out2)
        assert a["f_max"] == pytest.approx(b["f_max"], rel=1e-12)
        for k in ("onset", "f_min", "turning_point"):
            for q in POINT_KEYS:
                assert a[k][q] == pytest.approx(b[k][q], rel=1e-10, abs=1e-12), (k, q)
        s, d = pd.read_csv(tmp_path / "s.csv"), pd.read_csv(tmp_path / "d.csv")
        assert len(s) == len(d)
        np.testing.assert_allclose(s.f, d.f, rtol=1e-10, atol=1e-13)
        np.testing.assert_allclose(s.delta, d.delta, rtol=1e-10, atol=1e-13)


def test_scene_conflicting_option_is_one_line(tmp_path, capsys):
    scene = tmp_path / "scene.toml"
    scene.write_text(SCENE)
    code, out, err = _run(capsys, ["--scene", str(scene), "--slip", "no-slip", "--p", "0.5"])
    assert code == 2 and len(err.strip().split("\n")) == 1 and "--p" in err and "Traceback" not in err


def test_console_entry_point_subprocess(tmp_path):
    env = {**os.environ, "PYTHONPATH": str(REPO) + os.pathsep + os.environ.get("PYTHONPATH", "")}
    out_csv = tmp_path / "c.csv"
    ok = subprocess.run([sys.executable, "-m", "adhfit.cli", "simulate", *DC, "--points", "50", "--json",
                         "-o", str(out_csv)], capture_output=True, text=True, env=env, cwd=tmp_path, timeout=120)
    assert ok.returncode == 0, ok.stderr
    summary = _no_nan(ok.stdout)
    assert set(summary) == SUMMARY_KEYS
    assert summary["f_max"] == pytest.approx(math.pi * (0.6 + 2.0) * 0.25 ** 2, rel=1e-13)   # eq. (26)
    header, rows = _read_rows(out_csv)
    assert header == COLUMNS and 50 <= len(rows) <= 55
