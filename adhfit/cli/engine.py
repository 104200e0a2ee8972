"""The command line's first minute: is the compiled engine cached, and load it before the real work.

The numba kernels of :mod:`adhfit.core` (the large-stretch membrane) and :mod:`adhfit.exact` (the exact
membrane) are compiled on the first call in a new environment and loaded from numba's on-disk cache
afterwards (about a second).  Every fit needs both parts (it searches with the first and weighs the
approximation with the second), and each part has one signature per kernel whatever the scene, so a
cold start compiles the two parts at once, in two processes (:func:`warm_up`); where the time goes:
``benchmarks/results/first_run.md``.  The CLI uses :func:`engine_cache_is_cold` to print a one-line
notice before a cold start (with an estimate from the machine's load, and on a terminal a running clock
of the seconds spent, the part and the kernel compiling now), and :func:`warm_up` to pay the one-off cost
before a fit starts its clock, so that the wall time a report gives is the fit's own.
:func:`start_engine` prints the notice on standard error.
"""
from __future__ import annotations

import sys
import threading
import time
from contextlib import contextmanager
from pathlib import Path

__all__ = ["engine_cache_is_cold", "warm_up", "warm_part", "part_is_cold", "compile_beside", "PARTS",
           "start_engine", "EngineLoader", "COMPILING_NOTICE", "elapsed", "compile_estimate", "compiling_notice"]

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
    :meth:`stop`, which closes the line with the time it took; after the seconds, what is compiling now
    (:meth:`part`: the engine's part, and the kernel numba is compiling).  In a pipe: the notice line only."""

    def __init__(self, *, enabled: bool | None = None) -> None:
        self._tty = sys.stderr.isatty() if enabled is None else enabled
        self._t0 = time.perf_counter()
        self._stop = threading.Event()
        self._text = compiling_notice()
        self._part = ""
        self._kernels = _KernelWatch()
        if not self._tty:
            print(self._text, file=sys.stderr, flush=True)
            self._thread = None
            return
        self._kernels.start()
        self._thread = threading.Thread(target=self._tick, daemon=True, name="adhfit-compile-clock")
        self._thread.start()

    def part(self, label: str) -> None:
        """Name the part of the engine that is compiling now (shown after the seconds)."""
        self._part = label

    def _line(self) -> str:
        line = f"{self._text} {time.perf_counter() - self._t0:.0f} s"
        now = self._part + (f": {self._kernels.current}" if self._part and self._kernels.current else "")
        if now:
            line += f" · {now}"
        import shutil  # noqa: PLC0415
        width = shutil.get_terminal_size((120, 24)).columns - 1  # one line, rewritten in place
        return line if len(line) <= width else line[:max(len(self._text) + 8, width - 1)] + "…"

    def _tick(self) -> None:
        while True:
            sys.stderr.write(f"\r{self._line()}\x1b[K")
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
        self._kernels.stop()
        sys.stderr.write(f"\r\x1b[K{self._text} done in {time.perf_counter() - self._t0:.0f} s\n")
        sys.stderr.flush()


class _KernelWatch:
    """The kernel numba is compiling now, for the running clock (:class:`adhfit.core.jit.CompileWatch`;
    nothing where numba cannot be imported)."""

    def __init__(self) -> None:
        self._watch = None
        self._stack: list[str] = []

    @property
    def current(self) -> str:
        if self._watch is not None:
            return self._watch.current
        return self._stack[-1] if self._stack else ""

    def start(self) -> None:
        try:
            from ..core.jit import CompileWatch  # noqa: PLC0415
        except ImportError:  # no numba: nothing compiles
            return
        self._watch = CompileWatch(prefix="adhfit.", stack=self._stack)
        self._watch.start()

    def stop(self) -> None:
        if self._watch is not None:
            self._watch.stop()
            self._watch = None


#: the engine's parts, in the order a fit needs them: the large-stretch kernels (``adhfit/core``: every
#: fit's search) and the exact membrane's (``adhfit/exact``: every fit weighs the approximation at its
#: optimum).  The two folders share no kernel, so the parts compile independently (in two processes on a
#: cold start, :class:`EngineLoader`).
PARTS = ("large-stretch", "exact")
#: how the running clock names each part
PART_LABELS = {"large-stretch": "large-stretch", "exact": "exact membrane"}
_PART_FOLDERS = {"large-stretch": "core", "exact": "exact"}


def _engines() -> Path:
    return Path(__file__).resolve().parent.parent


def _marker() -> Path:
    """The file that says the kernels of this exact ``adhfit/core`` and ``adhfit/exact`` were compiled
    and cached.

    The kernels are cached by numba under one key per engine folder, a hash of its ``*.py``
    (:func:`adhfit.core.jit.tree_hash`); :func:`warm_up` leaves this marker, named after both hashes,
    once they have been compiled or loaded.  Any edit of either engine changes the name.
    """
    import hashlib  # noqa: PLC0415
    from ..core.jit import core_hash, tree_hash  # noqa: PLC0415
    key = hashlib.sha256((core_hash() + tree_hash(_engines() / "exact")).encode()).hexdigest()
    return _engines() / "core" / "__pycache__" / f"engine-{key[:16]}.ready"


def _part_marker(part: str) -> Path:
    """The marker of one part (:data:`PARTS`): named after the hash of its own folder."""
    from ..core.jit import tree_hash  # noqa: PLC0415
    folder = _engines() / _PART_FOLDERS[part]
    return folder / "__pycache__" / f"engine-{part}-{tree_hash(folder)[:16]}.ready"


def _touch(marker: Path) -> None:
    try:  # a read-only install keeps printing the notice, which is harmless
        marker.parent.mkdir(exist_ok=True)
        marker.touch()
    except OSError:
        pass


def engine_cache_is_cold() -> bool:
    """True when the compiled kernels will have to be compiled (no cache for this ``core/`` tree)."""
    try:
        import importlib.util  # noqa: PLC0415
        if importlib.util.find_spec("numba") is None:
            return False
    except (ImportError, ValueError):
        return False
    return not _marker().exists()


def part_is_cold(part: str) -> bool:
    """True when the kernels of ``part`` (:data:`PARTS`) have not been compiled for this tree."""
    return not _part_marker(part).exists()


def warm_part(part: str, control: str = "displacement") -> float:
    """Compile or load the kernels of one part (:data:`PARTS`) by running tiny histories of it, both
    slip conditions; returns the seconds spent.

    Every kernel of a part has one signature whatever the control mode and the slip condition (they are
    run-time arguments), so one control mode compiles the part for all; ``control`` only picks the tiny
    histories that run (the pressure-control paths of the interpolation, for a pressure-control fit).
    """
    t0 = time.perf_counter()
    fixed = {"p": 0.6} if control == "displacement" else {"d": 0.0}
    if part == "large-stretch":
        from ..loading import history  # noqa: PLC0415
        from ..simulation import simulate  # noqa: PLC0415
        for slip in ("no-slip", "frictionless"):
            simulate(control, slip, **fixed, w=0.2, rs=0.5, a_max=0.25, points=40)
            _interpolate(history(control, slip, **fixed, w=0.2, rs=0.5, a_max=0.25, points=40), control)
    elif part == "exact":
        from ..exact import exact_history  # noqa: PLC0415
        # every fit weighs the exact membrane's effect at its optimum, with the loading end given as the
        # fits give it (delta_max or p_max), and simulate gives a_max
        end = {"delta_max": 0.05} if control == "displacement" else {"p_max": 0.9}
        for slip in ("no-slip", "frictionless"):
            exact_history(control, slip, **fixed, w=0.2, rs=0.5, lambda0=2.0, a_max=0.25, points=20)
            h = exact_history(control, slip, **fixed, w=0.2, rs=0.5, lambda0=2.0, points=20, **end)
        # the fit's interpolation kernels (adhfit/core) take any history: compiled here too, so that on
        # a cold start the second process takes them off the first one's path
        _interpolate(h, control)
    else:
        raise ValueError(f"unknown engine part {part!r}; one of {PARTS}")
    _touch(_part_marker(part))
    return time.perf_counter() - t0


def _interpolate(h, control: str) -> None:
    """A fit's interpolation kernels on the history ``h`` (force and contact radius, loading and
    retraction pieces)."""
    import numpy as np  # noqa: PLC0415
    from ..fitting.model import pieces_from_columns  # noqa: PLC0415
    pcs = pieces_from_columns(h.columns, control, h.counts)
    x = np.linspace(pcs.x_tp, pcs.x_max, 5)
    pcs.f_loading(x), pcs.f_unloading(x), pcs.a_loading(x), pcs.a_unloading(x)


def warm_up(control: str = "displacement", *, progress: _CompileClock | None = None) -> float:
    """Run tiny histories (both slip conditions, both membrane models) so that every kernel a fit uses is
    compiled or loaded before the fit's clock starts: :func:`warm_part` of every part, in the order a fit
    needs them.

    On a cold start (several parts to compile) and with two cores or more, the parts after the first
    compile at the same time in a second process (:func:`compile_beside`), which leaves them in numba's
    cache; this process compiles the first, then loads the others from the cache (or compiles them
    itself if the second process failed).

    Parameters
    ----------
    control : {"displacement", "pressure"}
        The control mode of the fit that follows.
    progress : optional
        The running clock of a cold start, told which part is compiling.

    Returns
    -------
    float
        Seconds spent (compile or cache load).
    """
    t0 = time.perf_counter()
    beside = compile_beside([p for p in PARTS if part_is_cold(p)][1:])
    try:
        for part in PARTS:
            label = PART_LABELS[part]
            if part in beside:
                if progress is not None:
                    progress.part(f"{label} (second process)")
                beside.pop(part).wait()
            if progress is not None:
                progress.part(label)
            warm_part(part, control)
    finally:
        for proc in beside.values():  # this process failed first: the second one is of no use now
            proc.kill()
            proc.wait()
    _touch(_marker())
    return time.perf_counter() - t0


#: run by the second process of a cold start (:func:`compile_beside`)
_BESIDE = ("import sys; from adhfit.cli.engine import _compile_parts; "
           "sys.exit(_compile_parts(sys.argv[1:]))")


def compile_beside(parts: list[str]) -> dict:
    """Start compiling ``parts`` in a second process (one per part, in the order given); returns
    ``{part: process}`` (empty with fewer than two cores, when nothing is to compile, or in a read-only
    install, where the parts can never be marked compiled).

    The process dies with this one (:func:`adhfit.cli.runners.parent_death_signal`); its failure only
    leaves the part for this process to compile."""
    from .runners import default_workers  # noqa: PLC0415
    import os  # noqa: PLC0415
    if not parts or default_workers() < 2:
        return {}
    if not all(os.access(_part_marker(p).parent.parent, os.W_OK) for p in parts):
        return {}  # a read-only install: no marker says 'compiled', so this would start on every run
    import subprocess  # noqa: PLC0415
    root = str(_engines().parent)  # where this adhfit is imported from, first in the second one's path
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(filter(None, [root, os.environ.get("PYTHONPATH")]))}
    try:
        proc = subprocess.Popen([sys.executable, "-c", _BESIDE, *parts], env=env, stdin=subprocess.DEVNULL,
                                stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    except OSError:
        return {}
    return {part: proc for part in parts}


def _compile_parts(parts: list[str]) -> int:
    """The second process of a cold start: compile ``parts`` and leave them in numba's cache."""
    import signal  # noqa: PLC0415
    from .runners import parent_death_signal  # noqa: PLC0415
    parent_death_signal(signal.SIGTERM)
    for part in parts:
        warm_part(part)
    return 0


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
            if self._clock is None:
                self._seconds = warm_up("displacement")
            else:
                self._seconds = warm_up("displacement", progress=self._clock)
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
        return warm_up(control) if clock is None else warm_up(control, progress=clock)
    finally:
        if clock is not None:
            clock.stop()
