"""The command line's first minute: is the compiled engine cached, and load it before the real work.

The numba kernels of :mod:`adhfit.core` are compiled on the first call in a new environment
(about a minute on an idle 2-core machine, several on a busy one) and loaded from numba's on-disk cache afterwards (about a
second).  The CLI uses :func:`engine_cache_is_cold` to print a one-line notice before a cold start (with an estimate
from the machine's load, and on a terminal a running clock of the seconds spent), and
:func:`warm_up` to pay the one-off cost before a fit starts its clock, so that the wall time a report
gives is the fit's own.  :func:`start_engine` prints the notice on standard error.
"""
from __future__ import annotations

import sys
import threading
import time
from contextlib import contextmanager
from pathlib import Path

__all__ = ["engine_cache_is_cold", "warm_up", "start_engine", "EngineLoader", "COMPILING_NOTICE", "elapsed",
           "compile_estimate", "compiling_notice"]

#: what the first run prints before the kernels compile (the estimate is added: :func:`compile_estimate`)
COMPILING_NOTICE = "adhfit: compiling the engine (once"
#: seconds the first compile takes on an idle 2-core machine (measured: 79 s at load 2 on 2 cores, 330 s at
#: load 5-8); the estimate scales it by how busy the cores are
COMPILE_SECONDS_IDLE = 60.0


def compile_estimate(load: float | None = None, cores: int | None = None) -> str:
    """An honest estimate of the first compile, from the machine's load: ``"about 2 minutes"``.

    Parameters
    ----------
    load : float, optional
        The 1-minute load average (default: the machine's, where it can be read).
    cores : int, optional
        The cores this process may use (default: as counted by :func:`os.sched_getaffinity`).
    """
    import os  # noqa: PLC0415
    if load is None:
        try:
            load = os.getloadavg()[0]
        except (AttributeError, OSError):
            load = 0.0
    if cores is None:
        try:
            cores = len(os.sched_getaffinity(0))
        except (AttributeError, OSError):
            cores = os.cpu_count() or 1
    busy = max(1.0, (load + 1.0) / max(1, cores))  # this run shares the cores with ``load`` others
    low, high = COMPILE_SECONDS_IDLE * busy, 1.5 * COMPILE_SECONDS_IDLE * busy
    if high <= 100:
        return "about a minute"
    return f"{max(1, round(low / 60))}-{max(2, round(high / 60))} minutes at this machine's load"


def compiling_notice() -> str:
    """The one line printed before a cold start, with the estimate."""
    return f"{COMPILING_NOTICE}; {compile_estimate()})…"


class _CompileClock:
    """The notice, then (on a terminal) its elapsed seconds rewritten in place every second until
    :meth:`stop`, which closes the line with the time it took.  In a pipe: the notice line only."""

    def __init__(self, *, enabled: bool | None = None) -> None:
        self._tty = sys.stderr.isatty() if enabled is None else enabled
        self._t0 = time.perf_counter()
        self._stop = threading.Event()
        self._text = compiling_notice()
        if not self._tty:
            print(self._text, file=sys.stderr, flush=True)
            self._thread = None
            return
        self._thread = threading.Thread(target=self._tick, daemon=True, name="adhfit-compile-clock")
        self._thread.start()

    def _tick(self) -> None:
        while True:
            sys.stderr.write(f"\r{self._text} {time.perf_counter() - self._t0:.0f} s")
            sys.stderr.flush()
            if self._stop.wait(1.0):
                return

    def stop(self) -> None:
        """End the clock; on a terminal, the line ends with the seconds the compile took."""
        if self._thread is None:
            return
        self._stop.set()
        self._thread.join()
        self._thread = None
        sys.stderr.write(f"\r\x1b[K{self._text} done in {time.perf_counter() - self._t0:.0f} s\n")
        sys.stderr.flush()


def _marker() -> Path:
    """The file that says the kernels of this exact ``adhfit/core`` and ``adhfit/exact`` were compiled
    and cached.

    The kernels are cached by numba under one key per engine folder, a hash of its ``*.py``
    (:func:`adhfit.core.jit.tree_hash`); :func:`warm_up` leaves this marker, named after both hashes,
    once they have been compiled or loaded.  Any edit of either engine changes the name.
    """
    import hashlib  # noqa: PLC0415
    from ..core.jit import core_hash, tree_hash  # noqa: PLC0415
    engines = Path(__file__).resolve().parent.parent
    key = hashlib.sha256((core_hash() + tree_hash(engines / "exact")).encode()).hexdigest()
    return engines / "core" / "__pycache__" / f"engine-{key[:16]}.ready"


def engine_cache_is_cold() -> bool:
    """True when the compiled kernels will have to be compiled (no cache for this ``core/`` tree)."""
    try:
        import importlib.util  # noqa: PLC0415
        if importlib.util.find_spec("numba") is None:
            return False
    except (ImportError, ValueError):
        return False
    return not _marker().exists()


def warm_up(control: str = "displacement") -> float:
    """Run tiny histories (both slip conditions, both membrane models) so that every kernel a fit uses is
    compiled or loaded before the fit's clock starts.

    Parameters
    ----------
    control : {"displacement", "pressure"}
        The control mode of the fit that follows.

    Returns
    -------
    float
        Seconds spent (compile or cache load).
    """
    from ..exact import exact_history  # noqa: PLC0415
    from ..simulation import simulate  # noqa: PLC0415
    t0 = time.perf_counter()
    fixed = {"p": 0.6} if control == "displacement" else {"d": 0.0}
    import numpy as np  # noqa: PLC0415
    from ..fitting.model import pieces_from_columns  # noqa: PLC0415
    from ..loading import history  # noqa: PLC0415
    for slip in ("no-slip", "frictionless"):
        simulate(control, slip, **fixed, w=0.2, rs=0.5, a_max=0.25, points=40)
        # a fit's interpolation kernels (force and contact radius, loading and retraction pieces)
        h = history(control, slip, **fixed, w=0.2, rs=0.5, a_max=0.25, points=40)
        pcs = pieces_from_columns(h.columns, control, h.counts)
        x = np.linspace(pcs.x_tp, pcs.x_max, 5)
        pcs.f_loading(x), pcs.f_unloading(x), pcs.a_loading(x), pcs.a_unloading(x)
        # every fit weighs the exact membrane's effect at its optimum (its kernels compile once too),
        # with the loading end given as the fits give it (delta_max or p_max: kernels of their own)
        exact_history(control, slip, **fixed, w=0.2, rs=0.5, lambda0=2.0, a_max=0.25, points=20)
        end = {"delta_max": 0.05} if control == "displacement" else {"p_max": 0.9}
        exact_history(control, slip, **fixed, w=0.2, rs=0.5, lambda0=2.0, points=20, **end)
    try:  # a read-only install keeps printing the notice, which is harmless
        marker = _marker()
        marker.parent.mkdir(exist_ok=True)
        marker.touch()
    except OSError:
        pass
    return time.perf_counter() - t0


@contextmanager
def elapsed(desc: str, *, enabled: bool | None = None):
    """A one-line running clock (tqdm) on standard error while a long step runs; nothing in a pipe.

    Parameters
    ----------
    desc : str
        What is running, e.g. ``"fitting curve.csv"``.
    enabled : bool, optional
        Default: only when standard error is a terminal.  The line is removed when the step ends.
    """
    show = sys.stderr.isatty() if enabled is None else enabled
    if not show:
        yield
        return
    from tqdm import tqdm  # noqa: PLC0415
    bar = tqdm(total=None, desc=desc, bar_format="{desc}: {elapsed}", leave=False, file=sys.stderr)
    stop = threading.Event()

    def tick() -> None:
        while not stop.wait(0.5):
            bar.refresh()
    thread = threading.Thread(target=tick, daemon=True)
    thread.start()
    try:
        yield
    finally:
        stop.set()
        thread.join()
        bar.close()


class EngineLoader:
    """:func:`warm_up` in a thread, started at once: the compiled kernels load while the main thread
    imports the fitting libraries and reads the data (numba's code loading runs largely outside the
    GIL, in LLVM).  On a cold cache the notice is printed first (not with ``quiet``)."""

    def __init__(self, *, quiet: bool = False) -> None:
        self._clock = _CompileClock() if not quiet and engine_cache_is_cold() else None
        self._seconds = 0.0
        self._error: BaseException | None = None
        self._thread = threading.Thread(target=self._run, daemon=True)
        self._thread.start()

    def _run(self) -> None:
        try:
            self._seconds = warm_up("displacement")
        except BaseException as err:  # noqa: BLE001 - raised again in the main thread by wait()
            self._error = err
        finally:
            if self._clock is not None:
                self._clock.stop()

    def wait(self, control: str) -> float:
        """Block until the kernels are loaded (those of ``control`` too); returns the seconds it took."""
        t0 = time.perf_counter()
        self._thread.join()
        if self._error is not None:
            raise self._error
        if control != "displacement":
            warm_up(control)
        return self._seconds + (time.perf_counter() - t0 if control != "displacement" else 0.0)


def start_engine(control: str, *, quiet: bool = False) -> float:
    """Compile or load the engine before a fit starts its clock; returns the seconds it took.

    On a cold numba cache, prints the one-line notice on standard error first (not with ``quiet``).
    """
    clock = _CompileClock() if not quiet and engine_cache_is_cold() else None
    try:
        return warm_up(control)
    finally:
        if clock is not None:
            clock.stop()
