"""Where the jobs of a batch run (docs/contracts.md A7): local worker processes, or a Dask distributed cluster.

Generic: a job is a call ``fn(*call)`` of a module-level function with picklable arguments that returns
its own result and never raises for a bad input (see :func:`adhfit.cli.batch.run_job`).  Results are
handed to ``report`` as they finish; the caller puts them back in job order.  A job whose process dies
(a crash, not an error) or whose task is lost is handed to ``crashed(index, message)`` instead, and the
other jobs go on.
"""
from __future__ import annotations

import os
import sys
from typing import Any, Callable, Sequence

from ..errors import InputError

__all__ = ["default_workers", "run_local", "run_dask"]

#: how long to wait for a Dask scheduler to answer
CONNECT_TIMEOUT = "10s"

Report = Callable[[Any], None]
Crashed = Callable[[int, str], Any]


def default_workers() -> int:
    """The cores this process may use (``os.process_cpu_count`` on Python >= 3.13)."""
    count = getattr(os, "process_cpu_count", None)
    if count is not None:
        return max(1, count() or 1)
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except (AttributeError, OSError):
        return max(1, os.cpu_count() or 1)


def _context(preload: Sequence[str] = ()):
    """Linux: fork this process (it has imported half of what a fit needs; a separate server would import
    it all again, 1-2 s on the critical path).  Elsewhere (fork is unsafe on macOS, absent on Windows):
    a fork server that imports the modules ``preload`` names once, else spawn."""
    import multiprocessing  # noqa: PLC0415
    methods = multiprocessing.get_all_start_methods()
    if sys.platform.startswith("linux") and "fork" in methods:
        return multiprocessing.get_context("fork")
    if "forkserver" in methods:
        ctx = multiprocessing.get_context("forkserver")
        ctx.set_forkserver_preload(list(preload))  # a module that is not there is skipped by the server
        return ctx
    return multiprocessing.get_context("spawn")


def _pass(fn: Callable, calls: Sequence[tuple], indices: list[int], workers: int, report: Report,
          crashed: Crashed, ctx) -> list[int]:
    """One pool over ``indices``; returns the indices a dead worker process took down."""
    from concurrent.futures import ProcessPoolExecutor, as_completed  # noqa: PLC0415
    from concurrent.futures.process import BrokenProcessPool  # noqa: PLC0415
    broken = []
    with ProcessPoolExecutor(max_workers=max(1, min(workers, len(indices))), mp_context=ctx) as pool:
        futures = {pool.submit(fn, *calls[i]): i for i in indices}
        for fut in as_completed(futures):
            i = futures[fut]
            try:
                report(fut.result())
            except BrokenProcessPool:
                broken.append(i)
            except Exception as err:  # noqa: BLE001 - e.g. an argument that does not pickle
                report(crashed(i, f"{type(err).__name__}: {err}"))
    return sorted(broken)


def run_local(fn: Callable, calls: Sequence[tuple], workers: int, report: Report, crashed: Crashed,
              preload: Sequence[str] = ()) -> None:
    """Run ``fn(*call)`` for every call in ``workers`` local processes.

    A worker process that dies breaks its pool: the jobs it took down are run again one by one, each in
    a fresh process, so that only the job that crashes is reported to ``crashed``.  ``preload``: modules
    a fork server imports once, where processes are not forked from this one (not on Linux).
    """
    ctx = _context(preload)
    for i in _pass(fn, calls, list(range(len(calls))), workers, report, crashed, ctx):
        if _pass(fn, calls, [i], 1, report, crashed, ctx):
            report(crashed(i, "the worker process died while running this job"))


def run_dask(fn: Callable, calls: Sequence[tuple], address: str, report: Report, crashed: Crashed) -> None:
    """Run ``fn(*call)`` for every call on the Dask distributed cluster at ``address``.

    Raises
    ------
    InputError
        Dask is not installed (``pip install 'adhfit[dask]'``), or no scheduler answers at ``address``.
    """
    try:
        from distributed import Client, as_completed  # noqa: PLC0415
    except ImportError:
        raise InputError("--scheduler", address, "used with Dask installed: pip install 'adhfit[dask]'") from None
    try:
        client = Client(address, timeout=CONNECT_TIMEOUT)
    except (OSError, TimeoutError, ValueError) as err:
        raise InputError("--scheduler", address, "the address of a running Dask scheduler, e.g. "
                         "tcp://127.0.0.1:8786", reason=f"({' '.join(str(err).split())})") from None
    with client:
        futures = [client.submit(fn, *call, pure=False) for call in calls]
        index = {f.key: i for i, f in enumerate(futures)}
        for fut in as_completed(futures):
            i = index[fut.key]
            try:
                report(fut.result())
            except Exception as err:  # noqa: BLE001 - a lost worker or a task error: that job only
                report(crashed(i, f"{type(err).__name__}: {err}"))
