"""``adhfit fit`` over several curves (adhfit.cli.batch): which files, which scene, the summary
table, and a bad file that is reported, never fatal."""
from __future__ import annotations

import csv
import json
import shutil
from argparse import Namespace
from pathlib import Path

import pytest

from adhfit.cli import main
from adhfit.cli import batch

SAMPLES = Path(__file__).resolve().parents[1] / "sample_data"
GOOD = SAMPLES / "fea_displacement_no-slip"


def _rows(path: Path) -> list[dict]:
    with path.open(newline="", encoding="utf-8") as fh:
        return list(csv.DictReader(fh))


@pytest.fixture
def folder(tmp_path) -> Path:
    """A folder of sample subfolders: one good curve, one corrupt file, one curve without a scene."""
    root = tmp_path / "runs"
    shutil.copytree(GOOD, root / "good")
    (root / "corrupt").mkdir()
    shutil.copy(GOOD / "scene.toml", root / "corrupt" / "scene.toml")
    (root / "corrupt" / "curve.csv").write_text("time [s],displacement [um],force [mN]\n0,1,abc\n1,2,3\n")
    (root / "orphan").mkdir()
    shutil.copy(GOOD / "curve.csv", root / "orphan" / "curve.csv")
    (root / ".hidden").mkdir()
    (root / ".hidden" / "x.csv").write_text("not data\n")
    return root


def test_discover_uses_the_nearest_scene_and_skips_hidden_and_output(folder, tmp_path):
    out = folder / "out"
    out.mkdir()
    (out / "summary.csv").write_text("file\n")
    jobs = batch.discover([folder], outdir=out)
    assert [j.data.relative_to(folder).as_posix() for j in jobs] == [
        "corrupt/curve.csv", "good/curve.csv", "orphan/curve.csv"]
    scenes = {j.data.parent.name: j.scene for j in jobs}
    assert scenes["good"] == folder / "good" / "scene.toml"
    assert scenes["orphan"] is None  # no scene.toml up to the folder given: a failed row, not a guess
    assert {j.out.relative_to(out).as_posix() for j in jobs} == {"corrupt/curve", "good/curve", "orphan/curve"}
    # a scene.toml at the top serves every curve below that has none of its own
    shutil.copy(GOOD / "scene.toml", folder / "scene.toml")
    assert batch.discover([folder])[2].scene == folder / "scene.toml"
    # --scene wins everywhere
    assert {j.scene for j in batch.discover([folder], scene=GOOD / "scene.toml")} == {GOOD / "scene.toml"}


def test_discover_rejects_missing_paths_and_empty_folders(tmp_path):
    with pytest.raises(ValueError, match="DATA"):
        batch.discover([tmp_path / "nope.csv"])
    with pytest.raises(ValueError, match=r"\*\.csv"):
        batch.discover([tmp_path])
    assert batch.is_batch([tmp_path]) and batch.is_batch([GOOD / "curve.csv"] * 2)
    assert not batch.is_batch([GOOD / "curve.csv"])


def _fake_fit(args: Namespace) -> int:
    """Stand-in for the single-curve fit: a minimal A5 report, or a failure for 'corrupt'."""
    if "corrupt" in str(args.data):
        raise ValueError("line 2: 'abc' is not a number")
    Path(args.output).mkdir(parents=True, exist_ok=True)
    est = {"value": 0.4, "stderr": 0.01, "ci95": [0.38, 0.42], "unit": "J/m^2"}
    report = {"method": args.method,
              "slip": {"selected": None, "verdict": "undecided", "delta_aic": 1.0, "delta_bic": 1.0,
                       "parameters_from": "no-slip"},
              "parameters": {"work_of_adhesion": est, "mu_h": {**est, "value": 2.0, "ci95": None}},
              "fits": {"no-slip": {"redchi": 1.1}, "frictionless": {"redchi": 1.2}},
              "warnings": ["w1", "w2"], "wall_time_s": 0.1,
              "provenance": {"input_sha256": "ab" * 32, "adhfit_version": "x", "seed": args.seed}}
    (Path(args.output) / "report.json").write_text(json.dumps(report))
    return 0


def test_run_batch_keeps_going_and_lists_failures(folder, tmp_path, capsys):
    args = Namespace(data=[folder], scene=None, output=tmp_path / "o", method="lsq", seed=7)
    status = batch.run_batch(args, _fake_fit)
    assert status == batch.EXIT_SOME_FAILED
    rows = {Path(r["file"]).parent.name: r for r in _rows(tmp_path / "o" / "summary.csv")}
    assert list(_rows(tmp_path / "o" / "summary.csv")[0]) == batch.COLUMNS
    assert rows["good"]["status"] == "ok" and float(rows["good"]["work_of_adhesion_ci95_high"]) == 0.42
    assert rows["good"]["mu_h_ci95_low"] == ""  # missing interval: an empty cell, never a made-up number
    assert rows["good"]["slip_selected"] == "" and rows["good"]["slip_reported"] == "no-slip"
    assert float(rows["good"]["redchi"]) == 1.1 and rows["good"]["seed"] == "7"
    assert rows["corrupt"]["status"] == "failed" and "abc" in rows["corrupt"]["error"]
    assert rows["orphan"]["status"] == "failed" and "scene" in rows["orphan"]["error"]
    assert len(rows["corrupt"]["sha256"]) == 64
    err = capsys.readouterr().err
    assert "2 of 3 curves failed" in err and "corrupt" in err.splitlines()[-2] + err.splitlines()[-1]


def test_folder_with_a_corrupt_file_fits_in_one_command(folder, tmp_path, capsys):
    """End to end through the CLI: real fit of the good curve, the bad ones reported, exit 1."""
    shutil.rmtree(folder / "orphan")
    out = tmp_path / "fits"
    status = main(["fit", str(folder), "--no-profile", "--slip", "no-slip", "-o", str(out)])
    captured = capsys.readouterr()
    assert status == 1, captured.err
    rows = _rows(out / "summary.csv")
    assert [r["status"] for r in rows] == ["failed", "ok"]
    good = rows[1]
    assert abs(float(good["work_of_adhesion"]) - 0.4) < 0.02 and abs(float(good["mu_h"]) - 2.0) < 0.05
    assert float(good["work_of_adhesion_ci95_low"]) < float(good["work_of_adhesion"]) < float(
        good["work_of_adhesion_ci95_high"])
    assert good["method"] == "lsq" and good["adhfit_version"] and len(good["sha256"]) == 64
    for name in ("report.json", "report.md", "report.html", "fit.png", "thumbnail.png"):
        assert (out / "good" / "curve" / name).is_file(), name
    assert not (out / "corrupt" / "curve" / "thumbnail.png").exists()  # a failed curve draws nothing
    page = (out / "summary.html").read_text(encoding="utf-8")
    # the small figure the job drew is the one on the summary page
    import base64
    assert base64.b64encode((out / "good" / "curve" / "thumbnail.png").read_bytes()).decode("ascii") in page
    assert "1 of 2 curves failed" in captured.err and "Traceback" not in captured.err


def test_single_file_without_scene_uses_scene_toml_beside_it_or_says_so(tmp_path, capsys):
    shutil.copy(GOOD / "curve.csv", tmp_path / "curve.csv")
    assert main(["fit", str(tmp_path / "curve.csv"), "-o", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert "--scene" in err and len(err.strip().splitlines()) == 1
