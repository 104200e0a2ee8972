"""``adhfit fit`` end to end (docs/contracts.md A5) and its handling of malformed input (exit 2, one line)."""
from __future__ import annotations

import json
import math
from pathlib import Path

import pytest

from adhfit.cli import main

SAMPLES = Path(__file__).resolve().parents[1] / "sample_data"
CASE = SAMPLES / "flat_displacement_no-slip"   # the fastest sample to fit (~5 s)
SCENE = """[membrane]
radius = "2 mm"
prestretch = 2.0
model = "large-stretch"
[substrate]
radius = "1 mm"
[test]
control = "displacement"
pressure = "1.2 kPa"
[interface]
slip = "auto"
"""


def _no_nan(text: str):
    def refuse(token):
        raise AssertionError(f"{token} in report.json")
    return json.loads(text, parse_constant=refuse)


def _walk_numbers(d):
    if isinstance(d, dict):
        for v in d.values():
            yield from _walk_numbers(v)
    elif isinstance(d, list):
        for v in d:
            yield from _walk_numbers(v)
    elif isinstance(d, float):
        yield d


def test_fit_sample_end_to_end(tmp_path, capsys):
    out = tmp_path / "out"
    code = main(["fit", str(CASE / "curve.csv"), "--scene", str(CASE / "scene.toml"), "--seed", "3",
                 "-o", str(out)])
    assert code == 0, capsys.readouterr().err
    report = _no_nan((out / "report.json").read_text(encoding="utf-8"))
    assert all(math.isfinite(x) for x in _walk_numbers(report))
    truth = json.loads((CASE / "truth.json").read_text())
    assert report["method"] == "lsq"
    assert set(report["slip"]) >= {"selected", "verdict", "delta_aic", "delta_bic"}
    assert report["slip"]["selected"] == "no-slip"
    assert report["slip"]["verdict"].startswith("no-slip: very strong evidence")
    assert report["slip"]["evidence"] == "very strong"
    for name in ("work_of_adhesion", "mu_h"):
        p = report["parameters"][name]
        assert set(p) >= {"value", "stderr", "ci95", "unit", "status"}
        assert p["status"] == "determined"
        assert abs(p["value"] / truth[name] - 1) < 0.05
        assert p["ci95"][0] <= truth[name] <= p["ci95"][1]
    assert report["parameters"]["work_of_adhesion"]["unit"] == "J/m^2"
    assert report["parameters"]["mu_h"]["unit"] == "N/m"
    for slip in ("no-slip", "frictionless"):
        assert set(report["fits"][slip]) >= {"parameters", "aic", "bic", "redchi"}
    assert "force" in report["offsets"] and report["observables"] == ["force"]
    assert report["model"]["membrane"] == "large-stretch" and report["model"]["why"]
    assert isinstance(report["diagnostics"], list)
    off = report["offsets"]["displacement"]["value"]
    assert abs(off - truth["displacement_offset"]) < 5e-6
    assert report["provenance"]["seed"] == 3
    assert report["provenance"]["input_sha256"]
    assert report["n_points"] == truth["rows"] and report["model_evaluations"] > 0
    assert (out / "fit.png").stat().st_size > 10_000
    md = (out / "report.md").read_text(encoding="utf-8")
    assert "no-slip: very strong evidence" in md and "W_ad" in md and "95 %" in md


def _run(tmp_path, capsys, csv_text: str | None, scene_text: str = SCENE, extra=()):
    data = tmp_path / "curve.csv"
    if csv_text is not None:
        data.write_text(csv_text, encoding="utf-8")
    scene = tmp_path / "scene.toml"
    scene.write_text(scene_text, encoding="utf-8")
    code = main(["fit", str(data), "--scene", str(scene), "-o", str(tmp_path / "o"), *extra])
    err = capsys.readouterr().err
    return code, err


def _good_csv() -> str:
    return (CASE / "curve.csv").read_text(encoding="utf-8")


@pytest.mark.parametrize("label, mutate", [
    ("missing column", lambda t: "\n".join(",".join(r.split(",")[:2]) for r in t.splitlines()) + "\n"),
    ("text in a number", lambda t: t.replace(t.splitlines()[5].split(",")[2], "abc", 1)),
    ("force in kPa", lambda t: t.replace("force [mN]", "force [kPa]")),
    ("empty file", lambda t: ""),
])
def test_malformed_data_is_one_line_exit_2(tmp_path, capsys, label, mutate):
    code, err = _run(tmp_path, capsys, mutate(_good_csv()))
    assert code == 2, label
    assert len(err.strip().splitlines()) == 1 and "Traceback" not in err, err


def test_scene_without_the_fixed_pressure(tmp_path, capsys):
    code, err = _run(tmp_path, capsys, _good_csv(), SCENE.replace('pressure = "1.2 kPa"\n', ""))
    assert code == 2
    assert len(err.strip().splitlines()) == 1 and "pressure" in err and "Traceback" not in err


def test_missing_data_file(tmp_path, capsys):
    code, err = _run(tmp_path, capsys, None)
    assert code == 2 and len(err.strip().splitlines()) == 1


@pytest.mark.parametrize("extra, word", [
    (("--method", "bayes"), "method"),
    (("--sigma", "3 kPa"), "sigma"),
    (("--slip", "sticky"), "slip"),
    (("--seed", "-1"), "seed"),
])
def test_bad_options_are_one_line_exit_2(tmp_path, capsys, extra, word):
    code, err = _run(tmp_path, capsys, _good_csv(), extra=extra)
    assert code == 2
    assert len(err.strip().splitlines()) == 1 and word in err and "Traceback" not in err, err
