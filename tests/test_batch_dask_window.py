"""The Dask runner keeps a bounded number of jobs on the cluster (adhfit/cli/runners.py run_dask): every
job is reported once, a failing one through ``crashed``, however small the window."""
from __future__ import annotations

import pytest

from adhfit.cli import runners

distributed = pytest.importorskip("distributed")


def _square(i: int) -> int:
    if i == 7:
        raise ValueError("seven")
    return i * i


@pytest.mark.parametrize("window", [1, 3, None])
def test_every_job_is_reported_once_through_a_small_window(window):
    calls = [(i,) for i in range(20)]
    got, failed = [], []

    def crashed(i, msg):
        failed.append((i, msg))
        return -1
    with distributed.LocalCluster(n_workers=1, threads_per_worker=2, processes=False, dashboard_address=None) as cl:
        runners.run_dask(_square, calls, cl.scheduler_address, got.append,
                         crashed, window=window)
    assert sorted(got) == sorted([-1] + [i * i for i in range(20) if i != 7])
    assert failed == [(7, "ValueError: seven")]


def test_the_window_counts_the_cluster_threads():
    with distributed.LocalCluster(n_workers=1, threads_per_worker=3, processes=False, dashboard_address=None) as cl:
        with distributed.Client(cl.scheduler_address) as client:
            assert runners._dask_threads(client) == 3
