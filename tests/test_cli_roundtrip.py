"""simulate -> fit through the command line, and the CLI's first minute (output folder, compile notice)."""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from adhfit.cli import engine as cli_engine
from adhfit.cli import main

SCENE = """\
[membrane]
radius = "2 mm"
prestretch = 2.0

[substrate]
radius = "1 mm"

[test]
control = "{control}"
{fixed}

[interface]
slip = "auto"
"""
FIXED = {"displacement": 'pressure = "1.2 kPa"', "pressure": 'gap = "0 mm"'}


def _scene(tmp_path: Path, control: str = "displacement") -> Path:
    path = tmp_path / "scene.toml"
    path.write_text(SCENE.format(control=control, fixed=FIXED[control]))
    return path


def _simulate(capsys, scene: Path, out: Path, *extra: str) -> str:
    code = main(["simulate", "--scene", str(scene), "--mu-h", "2 N/m", "--work-of-adhesion", "0.4 J/m^2",
                 "--slip", "no-slip", *extra, "-o", str(out)])
    _, err = capsys.readouterr()
    assert code == 0, err
    return err


def test_simulate_scene_writes_a_measured_style_curve(tmp_path, capsys):
    scene = _scene(tmp_path)
    _simulate(capsys, scene, tmp_path / "c.csv", "--delta-max", "0.6 mm", "--points", "120")
    df = pd.read_csv(tmp_path / "c.csv")
    assert list(df.columns) == ["displacement [um]", "force [mN]"]
    x, f = df["displacement [um]"].to_numpy(), df["force [mN]"].to_numpy()
    assert np.isfinite(x).all() and np.isfinite(f).all()
    i = int(np.argmax(x))
    # loading up to the 0.6 mm asked for, at a constant step, then unloading at the same step
    assert x[i] == pytest.approx(600.0, rel=1e-9)
    assert np.all(np.diff(x[: i + 1]) > 0) and np.all(np.diff(x[i:]) < 0)
    # the force at the end of loading, from an independent route: the dimensionless run scaled by 2 mu h b
    code = main(["simulate", "--control", "displacement", "--slip", "no-slip", "--p", "0.6", "--w", "0.2",
                 "--rs", "0.5", "--delta-max", "0.3", "--json"])
    out, _ = capsys.readouterr()
    assert code == 0
    f_max_mN = json.loads(out)["f_max"] * 2 * 2.0 * 2e-3 * 1e3
    assert f[i] == pytest.approx(f_max_mN, rel=1e-6)
    # rows after the jump off the substrate are the free membrane: exactly zero force without noise
    assert f[-1] == 0.0 and np.min(f) < 0


def test_noise_is_seeded(tmp_path, capsys):
    scene = _scene(tmp_path)
    for name in ("a.csv", "b.csv"):
        _simulate(capsys, scene, tmp_path / name, "--delta-max", "0.6 mm", "--noise", "0.01", "--seed", "4",
                  "--points", "60")
    a, b = pd.read_csv(tmp_path / "a.csv"), pd.read_csv(tmp_path / "b.csv")
    pd.testing.assert_frame_equal(a, b)
    assert a["force [mN]"].iloc[-1] != 0.0  # noise on the detached rows too


@pytest.mark.parametrize("control,end", [("displacement", ("--delta-max", "0.6 mm")),
                                         ("pressure", ("--p-max", "1.6 kPa"))])
def test_round_trip_recovers_the_parameters(tmp_path, capsys, control, end):
    # 0.5 % force noise, 200 rows: the fit's standard errors are ~0.3 % (sample_data/README.md); 3 % is
    # ten of them, so the test fails on a bias, never on noise (seeded anyway)
    scene = _scene(tmp_path, control)
    _simulate(capsys, scene, tmp_path / "curve.csv", *end, "--noise", "0.005", "--seed", "2")
    code = main(["fit", str(tmp_path / "curve.csv"), "--scene", str(scene), "-o", str(tmp_path / "out"),
                 "--slip", "no-slip", "--no-profile", "--no-plot", "--quiet"])
    _, err = capsys.readouterr()
    assert code == 0, err
    rep = json.loads((tmp_path / "out" / "report.json").read_text())
    assert rep["parameters"]["work_of_adhesion"]["value"] == pytest.approx(0.4, rel=0.03)
    assert rep["parameters"]["mu_h"]["value"] == pytest.approx(2.0, rel=0.03)
    assert rep["engine_startup_s"] >= 0  # the one-off start-up is measured apart from wall_time_s
    assert (tmp_path / "out" / "report.html").is_file()


def test_unit_values_need_a_scene(capsys):
    code = main(["simulate", "--control", "displacement", "--slip", "no-slip", "--p", "0.6", "--w", "0.2",
                 "--rs", "0.5", "--delta-max", "0.6 mm"])
    _, err = capsys.readouterr()
    assert code == 2 and len(err.strip().splitlines()) == 1 and "--delta-max" in err and "--scene" in err
    code = main(["simulate", "--control", "displacement", "--slip", "no-slip", "--p", "0.6", "--w", "0.2",
                 "--rs", "0.5", "--a-max", "0.25", "--mu-h", "2 N/m"])
    _, err = capsys.readouterr()
    assert code == 2 and "--mu-h" in err and "--scene" in err


# ------------------------------------------------------------------------------------------------
# the output folder is checked before any work
# ------------------------------------------------------------------------------------------------
SAMPLE = Path(__file__).resolve().parents[1] / "sample_data" / "fea_displacement_no-slip"


@pytest.fixture
def no_fit(monkeypatch):
    """Fail loudly if a fit starts: the output folder must be refused before."""
    import adhfit.fitting.stage as stage

    def boom(*a, **k):
        raise AssertionError("the fit ran before the output folder was checked")
    monkeypatch.setattr(stage, "least_squares", boom)


@pytest.mark.parametrize("make", ["file", "under_file"])
def test_bad_output_folder_is_one_line_before_the_fit(tmp_path, capsys, no_fit, make):
    blocker = tmp_path / "taken"
    blocker.write_text("not a folder")
    out = blocker if make == "file" else blocker / "sub"
    code = main(["fit", str(SAMPLE / "curve.csv"), "--scene", str(SAMPLE / "scene.toml"), "-o", str(out)])
    _, err = capsys.readouterr()
    assert code == 2 and len(err.strip().splitlines()) == 1, err
    assert "-o/--output" in err and "Errno" not in err and str(blocker) in err


# ------------------------------------------------------------------------------------------------
# the compile notice
# ------------------------------------------------------------------------------------------------
def test_cold_cache_detection(tmp_path, monkeypatch):
    marker = tmp_path / "__pycache__" / "engine-0123.ready"
    monkeypatch.setattr(cli_engine, "_marker", lambda: marker)
    assert cli_engine.engine_cache_is_cold()  # no marker for this core/ tree: numba will compile
    cli_engine.warm_up("displacement")
    assert marker.exists()
    assert not cli_engine.engine_cache_is_cold()  # compiled (or loaded) once: nothing to compile


@pytest.mark.parametrize("quiet", [False, True])
def test_notice_is_printed_once_on_a_cold_start(tmp_path, capsys, monkeypatch, quiet):
    monkeypatch.setattr(cli_engine, "engine_cache_is_cold", lambda: True)
    args = ["--quiet"] if quiet else []
    code = main(["fit", str(SAMPLE / "curve.csv"), "--scene", str(SAMPLE / "scene.toml"), "-o",
                 str(tmp_path / "o"), "--slip", "no-slip", "--no-profile", "--no-plot", *args])
    _, err = capsys.readouterr()
    assert code == 0
    assert err.count("compiling the engine") == (0 if quiet else 1)
    assert "fitting curve.csv" not in err  # the running clock is drawn on a terminal only, never in a pipe


def test_running_clock_only_when_asked(capsys):
    import time as _time
    with cli_engine.elapsed("fitting x", enabled=False):
        _time.sleep(0.01)
    assert capsys.readouterr().err == ""
    with cli_engine.elapsed("fitting x", enabled=True):
        _time.sleep(0.7)
    assert "fitting x: 00:0" in capsys.readouterr().err


def test_scene_plot_in_physical_units(tmp_path, capsys):
    # the scene's stiffness comes from --mu-h only: the plot must use it (it once asked the scene for it)
    _simulate(capsys, _scene(tmp_path), tmp_path / "c.csv", "--delta-max", "0.6 mm", "--points", "60",
              "--plot", str(tmp_path / "h.png"))
    assert (tmp_path / "h.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_scene_result_plot_is_callable(tmp_path):
    import adhfit
    s = adhfit.simulate_scene(adhfit.load_scene(_scene(tmp_path)), mu_h="2 N/m", work_of_adhesion="0.4 J/m^2",
                              slip="no-slip", a_max=0.25, points=60)
    ax = s.plot()  # raised "'Scales' object is not callable"
    assert ax.get_xlabel() == "displacement δ (µm)" and ax.get_ylabel() == "force F (mN)"
    labels = ax.get_legend_handles_labels()[1]
    assert any(lbl.startswith("turning point") for lbl in labels) and any(lbl.startswith("f_min") for lbl in labels)


def test_a_bad_input_leaves_no_output_folder(tmp_path, capsys):
    out = tmp_path / "never"
    code = main(["fit", str(tmp_path / "missing.csv"), "--scene", str(SAMPLE / "scene.toml"), "-o", str(out)])
    _, err = capsys.readouterr()
    assert code == 2 and len(err.strip().splitlines()) == 1
    assert not out.exists()


def test_engine_loaded_in_a_thread_reports_its_failure(tmp_path, capsys, monkeypatch):
    """The kernels load in a thread while the fit's libraries import; a failure there ends the run with
    the CLI's one line, as it would in the main thread."""
    from adhfit.errors import ConvergenceError

    def broken(control="displacement"):
        raise ConvergenceError("warm-up history", {"control": control})
    monkeypatch.setattr(cli_engine, "warm_up", broken)
    code = main(["fit", str(SAMPLE / "curve.csv"), "--scene", str(SAMPLE / "scene.toml"), "-o",
                 str(tmp_path / "o"), "--no-plot", "--quiet"])
    err = capsys.readouterr().err
    assert code != 0 and len(err.strip().splitlines()) == 1 and "warm-up history" in err


def test_console_script_flushes_and_returns_the_status(tmp_path):
    """The console script leaves through os._exit after main(): output complete, status kept."""
    import json as _json
    import subprocess
    import sys
    bad = subprocess.run([sys.executable, "-m", "adhfit.cli", "fit", str(tmp_path / "missing.csv"), "--scene",
                          str(SAMPLE / "scene.toml")], capture_output=True, text=True, timeout=300)
    assert bad.returncode == 2 and len(bad.stderr.strip().splitlines()) == 1 and "missing.csv" in bad.stderr
    ok = subprocess.run([sys.executable, "-m", "adhfit.cli", "simulate", "--control", "displacement", "--slip",
                         "no-slip", "--p", "0.6", "--w", "0.2", "--rs", "0.5", "--a-max", "0.25", "--json"],
                        capture_output=True, text=True, timeout=300)
    assert ok.returncode == 0 and _json.loads(ok.stdout)["f_max"] > 0
