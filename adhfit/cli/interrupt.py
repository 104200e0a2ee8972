"""Ctrl-C on the command line: one line, exit status 130, no process left behind (docs/contracts.md A7b).

While a command runs, :func:`interruptible` installs a SIGINT handler that

- in the process that runs the command: either kills every process it started (worker processes, the
  MCMC samplers, the figure painter, and theirs) and raises :class:`KeyboardInterrupt` (inside
  :func:`raising`: code of the command line that stops its own workers and reports, e.g. a batch's
  runner loop), or runs the command's *finish* (:func:`on_interrupt`; default: print
  :data:`INTERRUPTED_LINE`), kills every process it started and ends the process with its status.  Library code is never unwound by a
  Ctrl-C: a process pool's clean-up waits for ever on workers that were killed holding its locks;
- in a process forked from it (the handler is inherited by ``fork``): exits at once and silently, since
  the terminal sends Ctrl-C to every process of the foreground group and only the parent speaks;
- on a second Ctrl-C: exits at once.
"""
from __future__ import annotations

import functools
import os
import signal
import sys
import threading
import time
from contextlib import contextmanager
from typing import Callable, Iterator

__all__ = ["EXIT_INTERRUPTED", "interruptible", "raising", "on_interrupt", "descendants", "kill_descendants",
           "INTERRUPTED_LINE"]

#: the customary status of a program stopped by SIGINT (128 + 2)
EXIT_INTERRUPTED = 128 + signal.SIGINT
#: what a single-curve command prints when Ctrl-C stops it
INTERRUPTED_LINE = "adhfit: interrupted (Ctrl-C); stopped before the reports were complete"

_state: dict = {"pid": None, "hits": 0, "raise": False, "finish": None, "stopping": False}


def _children_map() -> dict[int, list[int]] | None:
    """parent pid -> child pids, from /proc (None where there is no /proc)."""
    if not os.path.isdir("/proc/self"):
        return None
    children: dict[int, list[int]] = {}
    for entry in os.listdir("/proc"):
        if not entry.isdigit():
            continue
        try:
            with open(f"/proc/{entry}/stat", encoding="ascii", errors="replace") as fh:
                stat = fh.read()
        except OSError:  # the process ended while we looked
            continue
        try:  # "pid (comm) state ppid ...": comm may hold spaces and parentheses
            ppid = int(stat.rsplit(")", 1)[1].split()[1])
        except (IndexError, ValueError):
            continue
        children.setdefault(ppid, []).append(int(entry))
    return children


def descendants(pid: int | None = None) -> list[int]:
    """Every live process below ``pid`` (default: this one), children first.

    Linux: the whole tree, from /proc.  Elsewhere: the processes this one started with
    :mod:`multiprocessing` (their own children die with them, see :mod:`.runners`).
    """
    pid = os.getpid() if pid is None else pid
    tree = _children_map()
    if tree is None:
        import multiprocessing  # noqa: PLC0415
        return [p.pid for p in multiprocessing.active_children() if p.pid] if pid == os.getpid() else []
    found, todo = [], [pid]
    while todo:
        kids = tree.get(todo.pop(), [])
        found += kids
        todo += kids
    return found


def kill_descendants() -> None:
    """SIGKILL every process below this one, again until none is left (a child may fork while we look)."""
    for _ in range(5):
        pids = descendants()
        for pid in pids:
            try:
                os.kill(pid, signal.SIGKILL)
            except OSError:  # gone already, or not ours
                pass
        if not pids:
            return
        time.sleep(0.01)


def _no_child_after_ctrl_c() -> None:
    """Registered to run in every forked child: a process forked after Ctrl-C was pressed (a process
    pool replacing a worker that died) ends at once, so that none escapes the kill and outlives this
    process holding its output pipes open.  (Blocking the fork instead would deadlock: other fork
    hooks, logging's, take locks first.)"""
    if _state["stopping"]:
        os._exit(EXIT_INTERRUPTED)


def _default_finish() -> int:
    print(INTERRUPTED_LINE, file=sys.stderr, flush=True)
    return EXIT_INTERRUPTED


def _on_sigint(signum: int, frame) -> None:  # noqa: ARG001 - the signal module's signature
    if os.getpid() != _state["pid"]:
        os._exit(EXIT_INTERRUPTED)  # a forked helper: leave quietly, the parent reports
    _state["hits"] += 1
    _state["stopping"] = True
    if _state["hits"] > 1:
        _exit_now("adhfit: interrupted again; stopped at once", EXIT_INTERRUPTED)
    if _state["raise"]:
        kill_descendants()
        raise KeyboardInterrupt
    status, line = EXIT_INTERRUPTED, None
    try:
        status = (_state["finish"] or _default_finish)()
    except BaseException as err:  # noqa: BLE001 - the process ends here; say why in one line
        line = f"adhfit: interrupted (Ctrl-C); what finished could not be written ({type(err).__name__}: {err})"
    finally:
        _exit_now(line, status)


def _exit_now(line: str | None, status: int) -> None:
    """Print ``line`` (if any), kill every process below this one and end without unwinding.

    The kill comes last: a process pool replaces a worker that died (a Ctrl-C from the terminal
    reaches its workers too) within a tenth of a second, and a replacement forked after the kill
    would outlive this process, holding its output pipes open.
    """
    try:
        if line:
            sys.stderr.write(line + "\n")
        for stream in (sys.stdout, sys.stderr):
            stream.flush()
    except (OSError, ValueError, RuntimeError):  # a closed pipe, a re-entered buffer: end anyway
        pass
    finally:
        kill_descendants()
        os._exit(status)


@contextmanager
def raising() -> Iterator[None]:
    """Within: a Ctrl-C raises :class:`KeyboardInterrupt` here (the caller handles it in its own code)."""
    before = _state["raise"]
    _state["raise"] = True
    try:
        yield
    finally:
        _state["raise"] = before


@contextmanager
def on_interrupt(finish: Callable[[], int]) -> Iterator[None]:
    """Within: a Ctrl-C ends the process with ``finish()`` (it reports and returns the exit status)."""
    before = _state["finish"]
    _state["finish"] = finish
    try:
        yield
    finally:
        _state["finish"] = before


def interruptible(command: Callable[..., int]) -> Callable[..., int]:
    """``command`` (a sub-command: parsed arguments -> exit status) with Ctrl-C handled as the module
    docstring says.  A :class:`KeyboardInterrupt` that reaches this wrapper prints
    :data:`INTERRUPTED_LINE` and returns :data:`EXIT_INTERRUPTED`; a command that reports its own
    interruption (a batch) returns that status itself."""
    @functools.wraps(command)
    def run(*args, **kwargs) -> int:
        if threading.current_thread() is not threading.main_thread():
            return command(*args, **kwargs)  # signal handlers belong to the main thread
        _state.update({"pid": os.getpid(), "hits": 0, "finish": None, "raise": False, "stopping": False})
        if not _state.get("hooked") and hasattr(os, "register_at_fork"):
            os.register_at_fork(after_in_child=_no_child_after_ctrl_c)
            _state["hooked"] = True
        previous = signal.signal(signal.SIGINT, _on_sigint)
        try:
            return command(*args, **kwargs)
        except KeyboardInterrupt:
            print(INTERRUPTED_LINE, file=sys.stderr, flush=True)
            return EXIT_INTERRUPTED
        finally:
            signal.signal(signal.SIGINT, previous)
    return run
