"""A batch's memory stays bounded (issue 21): a job leaves nothing behind in the process that runs it,
and the command says when a Dask cluster's workers keep the statistical profile that made their memory
grow (~1 MiB per second of fitting: benchmarks/results/batch_dask_before.md)."""
from __future__ import annotations

import gc
import importlib
import os
import shutil
import tracemalloc
from argparse import Namespace
from pathlib import Path

import pytest

from adhfit.cli import batch, runners
from adhfit.cli.fit import run_fit
from adhfit.cli.runs import new_run

SAMPLES = Path(__file__).resolve().parents[1] / "sample_data"
CURVE = SAMPLES / "fea_displacement_no-slip"
#: figures and reports as a batch writes them; one slip condition, covariance intervals, short curve
OPTIONS = ["--slip", "no-slip", "--no-profile", "--points", "60"]
#: Python memory a curve may leave behind in the process that fitted it (bytes): allocated by adhfit, the
#: fitting libraries or Python itself (measured: 4.5 KiB; each curve's report kept, as a cache keyed by the
#: curve would, makes it 29 KiB) ...
PER_CURVE_BYTES = 12 * 1024
#: ... and allocated by matplotlib (measured: 19-24 KiB, flat over 1,000 curves on Dask workers:
#: benchmarks/results/batch_dask.md; figures are made without pyplot, so none can stay open)
PER_CURVE_MATPLOTLIB_BYTES = 128 * 1024


def _jobs(tmp_path: Path, n: int):
    """``n`` copies of one sample curve under different names (a cache keyed by the file would grow)."""
    data = tmp_path / "data"
    data.mkdir()
    shutil.copy(CURVE / "scene.toml", data / "scene.toml")
    for k in range(n):
        shutil.copy(CURVE / "curve.csv", data / f"curve_{k:03d}.csv")
    out = tmp_path / "out"
    cli = importlib.import_module("adhfit.cli.main")
    args = cli._build_parser().parse_args(["fit", str(data), *OPTIONS, "-o", str(out)])
    job_args = Namespace(**{k: v for k, v in vars(args).items() if k != "run"})
    return batch.discover([data], outdir=out), job_args, new_run(out, args)


def test_a_curve_leaves_no_python_memory_behind(tmp_path):
    warm, measured = 3, 6
    jobs, args, run = _jobs(tmp_path, warm + measured)
    assert len(jobs) == warm + measured

    def fit(i: int) -> None:
        out = batch.run_job(i, jobs[i], args, run_fit, os.getcwd(), run)
        assert out.error is None, out.error

    for i in range(warm):  # imports, compiled kernels, matplotlib's fonts: once per process
        fit(i)
    gc.collect()
    tracemalloc.start()
    try:
        before = tracemalloc.take_snapshot()
        for i in range(warm, warm + measured):
            fit(i)
        gc.collect()
        after = tracemalloc.take_snapshot()
    finally:
        tracemalloc.stop()
    mine = [tracemalloc.Filter(False, tracemalloc.__file__)]  # the first snapshot, held while taking the second
    before, after = before.filter_traces(mine), after.filter_traces(mine)
    growth = after.compare_to(before, "filename")
    mpl = sum(s.size_diff for s in growth if f"{os.sep}matplotlib{os.sep}" in s.traceback[0].filename)
    rest = sum(s.size_diff for s in growth) - mpl
    top = "\n".join(str(s) for s in after.compare_to(before, "lineno")[:8])
    assert rest / measured < PER_CURVE_BYTES, f"{rest / measured / 1024:.1f} KiB per curve; most:\n{top}"
    assert mpl / measured < PER_CURVE_MATPLOTLIB_BYTES, f"matplotlib: {mpl / measured / 1024:.1f} KiB per curve"


def _square(i: int) -> int:
    return i * i


@pytest.mark.parametrize("profiler", [True, False])
def test_the_command_says_when_the_workers_keep_a_profile(profiler, capsys):
    distributed = pytest.importorskip("distributed")
    import dask  # noqa: PLC0415

    with dask.config.set({"distributed.worker.profile.enabled": profiler}):
        with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=False,
                                      dashboard_address=None) as cl:
            with distributed.Client(cl.scheduler_address) as client:
                assert runners.profiling_workers(client) == (2 if profiler else 0)
            got = []
            runners.run_dask(_square, [(i,) for i in range(5)], cl.scheduler_address, got.append,
                             lambda i, msg: pytest.fail(msg))
    assert sorted(got) == [0, 1, 4, 9, 16]
    err = capsys.readouterr().err
    note = runners.PROFILER_NOTE.format(n=2)
    assert (note in err) == profiler
    assert "DASK_DISTRIBUTED__WORKER__PROFILE__ENABLED=False" in note
