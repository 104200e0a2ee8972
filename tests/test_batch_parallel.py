"""A batch run by local worker processes or by a Dask cluster gives the summary a serial run gives
(docs/contracts.md A7); a failing curve, or a worker process that dies, stops no other curve."""
from __future__ import annotations

import csv
import json
import os
import shutil
from argparse import Namespace
from pathlib import Path

import pytest

from adhfit.cli import main
from adhfit.cli import batch

SAMPLES = Path(__file__).resolve().parents[1] / "sample_data"
CURVES = ("fea_displacement_no-slip", "flat_displacement_no-slip", "fea_pressure_no-slip")
#: small and fast: one slip condition, covariance intervals, no figure, short histories
FAST = ["--slip", "no-slip", "--no-profile", "--no-plot", "--points", "60"]
#: a measurement, and the run's own id: the columns that differ between two runs of the same batch
PER_RUN = ("wall_time_s", "run_id")


@pytest.fixture(scope="module")
def folder(tmp_path_factory) -> Path:
    """Three sample curves and one corrupt file, each in its folder with its scene."""
    root = tmp_path_factory.mktemp("batch") / "runs"
    for name in CURVES:
        shutil.copytree(SAMPLES / name, root / name)
    (root / "corrupt").mkdir()
    shutil.copy(SAMPLES / CURVES[0] / "scene.toml", root / "corrupt" / "scene.toml")
    (root / "corrupt" / "curve.csv").write_text("time [s],displacement [um],force [mN]\n0,1,abc\n1,2,3\n")
    return root


def _rows(out: Path) -> list[dict]:
    with (out / "summary.csv").open(newline="", encoding="utf-8") as fh:
        rows = list(csv.DictReader(fh))
    for r in rows:  # the output folder differs between runs by construction
        r["report_dir"] = str(Path(r["report_dir"]).relative_to(out))
        for key in PER_RUN:
            r.pop(key)
    return rows


@pytest.fixture(scope="module")
def serial(folder, tmp_path_factory) -> list[dict]:
    out = tmp_path_factory.mktemp("serial") / "fits"
    assert main(["fit", str(folder), *FAST, "--workers", "1", "-o", str(out)]) == 1
    return _rows(out)


def test_serial_run_has_the_failure_in_place_and_the_fits(serial):
    assert [Path(r["file"]).parent.name for r in serial] == sorted(["corrupt", *CURVES])
    assert [r["status"] for r in serial] == ["failed", "ok", "ok", "ok"]
    assert "only 2 data rows" in serial[0]["error"]
    for r in serial[1:]:  # near the samples' truth (5 %: 0.5 % noise, 60-row histories)
        truth = json.loads((SAMPLES / Path(r["file"]).parent.name / "truth.json").read_text())
        for key in ("work_of_adhesion", "mu_h"):
            assert float(r[key]) == pytest.approx(truth[key], rel=0.05)


def test_two_workers_give_the_serial_rows(folder, serial, tmp_path, capsys):
    out = tmp_path / "fits"
    assert main(["fit", str(folder), *FAST, "--workers", "2", "-o", str(out)]) == 1
    assert _rows(out) == serial
    err = capsys.readouterr().err
    assert "1 of 4 curves failed" in err and "Traceback" not in err
    for name in CURVES:  # each worker wrote its curve's reports
        assert json.loads((out / name / "curve" / "report.json").read_text())["method"] == "lsq"


def test_a_dask_cluster_gives_the_serial_rows(folder, serial, tmp_path):
    distributed = pytest.importorskip("distributed")
    out = tmp_path / "fits"
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None,
                                  silence_logs=40) as cluster:
        status = main(["fit", str(folder), *FAST, "--scheduler", cluster.scheduler_address, "-o", str(out)])
    assert status == 1
    assert _rows(out) == serial


def test_a_scheduler_that_does_not_answer_is_one_line(folder, tmp_path, capsys, monkeypatch):
    pytest.importorskip("distributed")
    from adhfit.cli import runners
    monkeypatch.setattr(runners, "CONNECT_TIMEOUT", "1s")
    status = main(["fit", str(folder), "--scheduler", "tcp://127.0.0.1:9", "-o", str(tmp_path / "o")])
    err = capsys.readouterr().err
    assert status == 2 and "--scheduler" in err and "Traceback" not in err


def test_workers_and_scheduler_together_are_refused(folder, tmp_path, capsys):
    status = main(["fit", str(folder), "--workers", "2", "--scheduler", "tcp://127.0.0.1:9", "-o",
                   str(tmp_path / "o")])
    assert status == 2 and "--workers" in capsys.readouterr().err


def _dying_fit(args: Namespace) -> int:
    """Stand-in fit: the process dies on the 'crash' curve, a minimal report elsewhere."""
    if "crash" in str(args.data):
        os._exit(3)
    Path(args.output).mkdir(parents=True, exist_ok=True)
    (Path(args.output) / "report.json").write_text(json.dumps({"method": "lsq", "warnings": []}))
    return 0


def test_a_worker_process_that_dies_fails_its_curve_only(tmp_path):
    for name in ("a", "crash", "b", "c"):
        (tmp_path / "in" / name).mkdir(parents=True)
        (tmp_path / "in" / name / "curve.csv").write_text("x\n")
        (tmp_path / "in" / name / "scene.toml").write_text("")
    args = Namespace(data=[tmp_path / "in"], scene=None, output=tmp_path / "o", method="lsq", seed=None,
                     workers=2, scheduler=None)
    assert batch.run_batch(args, _dying_fit) == batch.EXIT_SOME_FAILED
    with (tmp_path / "o" / "summary.csv").open(newline="") as fh:
        rows = list(csv.DictReader(fh))
    assert [(Path(r["file"]).parent.name, r["status"]) for r in rows] == [
        ("a", "ok"), ("b", "ok"), ("c", "ok"), ("crash", "failed")]
    assert "died" in rows[3]["error"]


def test_workers_must_be_a_positive_integer(folder, tmp_path, capsys):
    assert main(["fit", str(folder), "--workers", "0", "-o", str(tmp_path / "o")]) == 2
    assert "--workers must be a positive integer" in capsys.readouterr().err
    assert batch._runner(Namespace(workers=None, scheduler=None), 4)[0] == "local" or os.cpu_count() == 1
    assert batch._runner(Namespace(workers=3, scheduler=None), 1) == ("serial", None)  # one curve: no pool
    assert batch._runner(Namespace(), 4) == ("serial", None)  # a Namespace from Python code: this process
