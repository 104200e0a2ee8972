"""Where the jobs of a batch run (docs/contracts.md A7): local worker processes, or a Dask distributed cluster.

Generic: a job is a call ``fn(*call)`` of a module-level function with picklable arguments that returns
its own result and never raises for a bad input (see :func:`adhfit.cli.batch.run_job`).  Results are
handed to ``report`` as they finish; the caller puts them back in job order.  A job whose process dies
(a crash, not an error) or whose task is lost is handed to ``crashed(index, message)`` instead, and the
other jobs go on.

Stopping (docs/contracts.md A7b).  A :class:`KeyboardInterrupt` in the caller (Ctrl-C) cancels the
queued jobs, kills the running ones and is raised again at once; the results reported before it stand.
A local worker process leads its own process group (so that the terminal's Ctrl-C reaches only the
parent, which decides) and dies, with every process it started, when its parent dies, however it dies
(a SIGKILL included): on Linux the kernel tells it (``PR_SET_PDEATHSIG``), everywhere a watchdog thread
polls the parent's pid.
"""
from __future__ import annotations

import gc
import os
import signal
import sys
import threading
import time
from typing import Any, Callable, Sequence

from ..errors import InputError

__all__ = ["default_workers", "run_local", "run_dask", "forks_here", "parent_death_signal", "WATCHDOG_PERIOD_S",
           "profiling_workers", "PROFILER_NOTE"]

#: how long to wait for a Dask scheduler to answer
CONNECT_TIMEOUT = "10s"
#: how often a local worker checks that its parent is alive (seconds; the kernel's notice is immediate)
WATCHDOG_PERIOD_S = 0.5

Report = Callable[[Any], None]
Crashed = Callable[[int, str], Any]

_worker = {"pid": None}


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


def forks_here() -> bool:
    """Whether local workers are forked from this process (Linux), so start with what it has loaded."""
    return _context().get_start_method() == "fork"


def _import_all(modules: Sequence[str]) -> None:
    """Import ``modules`` in this process (one that is not there is skipped, as a fork server does)."""
    import importlib  # noqa: PLC0415
    for name in modules:
        try:
            importlib.import_module(name)
        except ImportError:
            pass


def _die_with_group() -> None:
    """End this worker and every process it started (its process group)."""
    try:
        os.killpg(0, signal.SIGKILL)
    finally:
        os._exit(128 + signal.SIGKILL)


def _on_sigterm(signum: int, frame) -> None:  # noqa: ARG001 - the signal module's signature
    if os.getpid() == _worker["pid"]:
        _die_with_group()  # the parent died (the kernel's notice) or stopped the pool
    os._exit(128 + signal.SIGTERM)  # a process a fit forked inherited this handler: die as SIGTERM would


def parent_death_signal(sig: int) -> bool:
    """Ask Linux to send ``sig`` to this process when its parent dies (prctl PR_SET_PDEATHSIG)."""
    if not sys.platform.startswith("linux"):
        return False
    try:
        import ctypes  # noqa: PLC0415
        libc = ctypes.CDLL(None, use_errno=True)
        return libc.prctl(1, sig, 0, 0, 0) == 0  # 1 = PR_SET_PDEATHSIG
    except (OSError, AttributeError):
        return False


def _watch(parent: int) -> None:
    while True:
        time.sleep(WATCHDOG_PERIOD_S)
        if os.getppid() != parent:
            _die_with_group()


def _worker_init(parent: int) -> None:
    """Run first in every local worker: its own process group, Ctrl-C left to the parent, and death
    with the parent (module docstring)."""
    _worker["pid"] = os.getpid()
    os.setpgrp()
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, _on_sigterm)
    parent_death_signal(signal.SIGTERM)
    if os.getppid() != parent:  # the parent died before the notice was armed
        _die_with_group()
    threading.Thread(target=_watch, args=(parent,), daemon=True, name="adhfit-parent-watchdog").start()


def _stop(pool) -> None:
    """Cancel the queued jobs and kill every worker with the processes it started; returns at once."""
    procs = list((getattr(pool, "_processes", None) or {}).values())  # the pool's own, not every child
    pool.shutdown(wait=False, cancel_futures=True)
    for proc in procs:
        for kill in (os.killpg, os.kill):  # its group; the process alone if it has no group of its own yet
            try:
                kill(proc.pid, signal.SIGKILL)
                break
            except OSError:
                continue
    for proc in procs:
        proc.join(timeout=2.0)


def _pass(fn: Callable, calls: Sequence[tuple], indices: list[int], workers: int, report: Report,
          crashed: Crashed, ctx) -> list[int]:
    """One pool over ``indices``; returns the indices a dead worker process took down."""
    from concurrent.futures import ProcessPoolExecutor, as_completed  # noqa: PLC0415
    from concurrent.futures.process import BrokenProcessPool  # noqa: PLC0415
    broken = []
    pool = ProcessPoolExecutor(max_workers=max(1, min(workers, len(indices))), mp_context=ctx,
                               initializer=_worker_init, initargs=(os.getpid(),))
    try:
        futures = {pool.submit(fn, *calls[i]): i for i in indices}
        for fut in as_completed(futures):
            i = futures[fut]
            try:
                report(fut.result())
            except BrokenProcessPool:
                broken.append(i)
            except Exception as err:  # noqa: BLE001 - e.g. an argument that does not pickle
                report(crashed(i, f"{type(err).__name__}: {err}"))
    except BaseException:  # Ctrl-C (KeyboardInterrupt): stop everything now, say so above
        _stop(pool)
        raise
    pool.shutdown(wait=True)
    return sorted(broken)


def run_local(fn: Callable, calls: Sequence[tuple], workers: int, report: Report, crashed: Crashed,
              preload: Sequence[str] = ()) -> None:
    """Run ``fn(*call)`` for every call in ``workers`` local processes.

    A worker process that dies breaks its pool: the jobs it took down are run again one by one, each in
    a fresh process, so that only the job that crashes is reported to ``crashed``.  ``preload``: modules
    imported once before the workers start, here where they fork from this process (Linux), else by
    the fork server they fork from.
    """
    ctx = _context(preload)
    if ctx.get_start_method() == "fork":  # imported here once, each worker starts with them
        _import_all(preload)
        # what this process holds goes to the collector's permanent generation: a worker's collections
        # then skip it and leave its pages shared (measured: 0.25 s of system time less per worker)
        gc.collect()
        gc.freeze()
    try:
        for i in _pass(fn, calls, list(range(len(calls))), workers, report, crashed, ctx):
            if _pass(fn, calls, [i], 1, report, crashed, ctx):
                report(crashed(i, "the worker process died while running this job"))
    finally:
        gc.unfreeze()


def run_dask(fn: Callable, calls: Sequence[tuple], address: str, report: Report, crashed: Crashed,
             window: int | None = None) -> None:
    """Run ``fn(*call)`` for every call on the Dask distributed cluster at ``address``.

    At most ``window`` jobs are on the cluster at a time (default: :data:`DASK_WINDOW_PER_THREAD` per
    worker thread, at least :data:`DASK_WINDOW_MIN`); the next is submitted as one finishes, and a
    finished job's result is released once reported.  So the scheduler, the workers and this process
    hold a bounded number of jobs and results whatever the length of the batch (a batch of 1,000 curves
    costs what one of a few dozen does: ``benchmarks/results/batch_dask.md``).  Workers that run Dask's
    statistical profiler hold ~1 MiB per second of fitting on top (:func:`profiling_workers`): the
    command says so once, on standard error.

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
    if window is None:
        window = max(DASK_WINDOW_MIN, DASK_WINDOW_PER_THREAD * _dask_threads(client))
    profiling = profiling_workers(client)
    if profiling:
        print(PROFILER_NOTE.format(n=profiling), file=sys.stderr, flush=True)
    running: dict = {}  # future -> index of its call
    try:
        queue = iter(range(len(calls)))

        def submit_next(pool) -> None:
            i = next(queue, None)
            if i is not None:
                fut = client.submit(fn, *calls[i], pure=False)
                running[fut] = i
                pool.add(fut)
        done = as_completed()
        for _ in range(window):
            submit_next(done)
        for fut in done:
            i = running.pop(fut)
            try:
                report(fut.result())
            except Exception as err:  # noqa: BLE001 - a lost worker or a task error: that job only
                report(crashed(i, f"{type(err).__name__}: {err}"))
            fut.release()
            submit_next(done)
    except BaseException:  # Ctrl-C: the cluster drops the queued and running jobs of this batch
        try:
            client.cancel(list(running), force=True)
        except Exception:  # noqa: BLE001 - the cluster may be gone; nothing of ours keeps running here
            pass
        raise
    finally:
        client.close(timeout=5)


#: jobs on a Dask cluster at a time, per worker thread (enough to keep each busy while results travel)
DASK_WINDOW_PER_THREAD = 4
#: ... and at least this many
DASK_WINDOW_MIN = 8


#: said once on standard error when the cluster's workers run Dask's statistical profiler (issue 21)
PROFILER_NOTE = ("adhfit: {n} Dask worker(s) run the statistical profiler, which keeps ~1 MiB of profile per "
                 "second of fitting for its last 1,000 s; for long batches start them with "
                 "DASK_DISTRIBUTED__WORKER__PROFILE__ENABLED=False (docs/contracts.md A7)")


def _runs_profiler(dask_worker) -> bool:
    """Run on a Dask worker: whether its statistical profiler samples the running tasks."""
    return "profile" in getattr(dask_worker, "periodic_callbacks", {})


def profiling_workers(client) -> int:
    """How many of the cluster's workers run Dask's statistical profiler (0 where it cannot be asked).

    The profiler samples every running task's stack each 10 ms and keeps one tree of the sampled frames
    per second, twice (``profile_history`` and ``profile_keys_history``), for the last
    ``distributed.admin.low-level-log-length`` (1,000) seconds.  A fit's stacks are deep and varied: a
    worker's memory grows by ~1 MiB per second of fitting until that history is full
    (benchmarks/results/batch_dask_before.md), and is flat with the profiler off (batch_dask.md).
    """
    try:
        return sum(1 for on in client.run(_runs_profiler).values() if on)
    except Exception:  # noqa: BLE001 - an older distributed, or a worker that cannot be asked: say nothing
        return 0


def _dask_threads(client) -> int:
    """The worker threads of the cluster (1 where it cannot be asked)."""
    try:
        return max(1, sum(client.nthreads().values()))
    except Exception:  # noqa: BLE001 - an older distributed, or a cluster still starting
        return 1
