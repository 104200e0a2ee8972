"""One batch run in its output folder: its id, its lock, each curve's reports put in place whole, and
``--resume`` (docs/contracts.md A7b).

- **Run id.** Every batch run has an id (``20261204T171500Z-4242-9f3a``: UTC start, pid, a random tag).  ``summary.csv``
  names, for each curve, the run that wrote its reports (``run_id``), and each ``report.json`` a batch
  writes carries ``batch: {"run_id", "scene_sha256", "settings_sha256"}``.
- **Lock.** ``OUTDIR/.adhfit-run.lock`` holds the pid of the run writing there.  A second run into the
  same folder is refused in words while that process lives; a lock left by a process that is gone
  (a SIGKILL, a power cut) is taken over.
- **Whole reports.** A curve is fitted into a staging folder (``OUTDIR/.adhfit-partial/RUN/N``); its
  files are moved into the curve's folder only when all of them are written (``report.json`` last).
  An interrupted fit leaves the folder as it was; a failed fit removes the curve's older reports, so
  that nothing left there looks like the result of this run.
- **Resume.** With ``--resume``, a curve whose ``report.json`` was written by a batch from the same
  input bytes (SHA-256), the same scene file and the same fit settings is not fitted again: its row is
  rebuilt from that report and keeps the id of the run that wrote it.
"""
from __future__ import annotations

import datetime as _dt
import hashlib
import json
import os
import shutil
import socket
from argparse import Namespace
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ..errors import InputError

__all__ = ["RunInfo", "new_run", "RunLock", "REPORT_FILES", "LOCK_NAME", "STAGING", "file_sha256",
           "publish", "retire", "reusable_report", "settings_sha256"]

LOCK_NAME = ".adhfit-run.lock"
STAGING = ".adhfit-partial"
#: every file a curve's fit may leave in its folder (a failed re-run removes them)
REPORT_FILES = ("report.json", "report.md", "report.html", "fit.png", "plot_data.json", "thumbnail.png",
                "fit_mcmc.png", "corner.png", "chain.h5")
#: arguments that say where and how a batch runs, not what a fit computes (left out of the settings hash)
_NOT_SETTINGS = frozenset({"data", "scene", "output", "workers", "scheduler", "resume", "quiet", "run", "command",
                           "painter", "global_fit"})


@dataclass(frozen=True)
class RunInfo:
    """What a job needs to know about its batch run (picklable: it travels to the workers)."""

    run_id: str
    outdir: Path
    settings_sha256: str

    def stage(self, index: int) -> Path:
        """The staging folder of job ``index``."""
        return self.outdir / STAGING / self.run_id / str(index)


def settings_sha256(args: Namespace) -> str:
    """A hash of the fit settings of a run (method, slip, seed, options: what changes a report)."""
    items = {k: str(v) for k, v in sorted(vars(args).items()) if k not in _NOT_SETTINGS}
    return hashlib.sha256(json.dumps(items, sort_keys=True).encode()).hexdigest()


def new_run(outdir: Path, args: Namespace) -> RunInfo:
    """A fresh run id for ``outdir`` (absolute) and the settings of ``args``."""
    import secrets  # noqa: PLC0415
    now = _dt.datetime.now(_dt.timezone.utc).strftime("%Y%m%dT%H%M%SZ")
    # the pid and a random tag: two runs of one process in one second (Python callers) differ too
    return RunInfo(f"{now}-{os.getpid()}-{secrets.token_hex(2)}", Path(outdir).resolve(), settings_sha256(args))


def file_sha256(path: str | Path) -> str:
    """SHA-256 of a regular file's bytes; ``""`` when it cannot be read (or is a pipe: never opened)."""
    if not Path(path).is_file():
        return ""
    digest = hashlib.sha256()
    try:
        with open(path, "rb") as fh:
            for block in iter(lambda: fh.read(1 << 20), b""):
                digest.update(block)
    except OSError:
        return ""
    return digest.hexdigest()


# --------------------------------------------------------------------------------------------- the lock
def _start_time(pid: int) -> str | None:
    """The kernel's start time of ``pid`` (Linux; tells a reused pid from the run that took the lock)."""
    try:
        with open(f"/proc/{pid}/stat", encoding="ascii", errors="replace") as fh:
            return fh.read().rsplit(")", 1)[1].split()[19]
    except (OSError, IndexError):
        return None


def _alive(holder: dict[str, Any]) -> bool:
    """Is the process that wrote ``holder`` (a lock's content) still running?"""
    pid = holder.get("pid")
    if not isinstance(pid, int) or pid <= 0:
        return False
    if holder.get("host") not in (None, socket.gethostname()):
        return True  # another machine's run on a shared disk: we cannot tell, so we do not take it over
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # another user's live process
        return True
    started = holder.get("start_time")
    return started is None or _start_time(pid) in (None, started)


class RunLock:
    """``OUTDIR/.adhfit-run.lock``: one batch run writes into a folder at a time (module docstring)."""

    def __init__(self, outdir: Path, run_id: str) -> None:
        self.path = Path(outdir) / LOCK_NAME
        self.run_id = run_id
        self._held = False

    def acquire(self) -> None:
        """Take the lock, or take over a dead run's.

        Raises
        ------
        InputError
            Another live adhfit run holds it (its pid and start are named).
        """
        self.path.parent.mkdir(parents=True, exist_ok=True)
        me = {"pid": os.getpid(), "run_id": self.run_id, "host": socket.gethostname(),
              "start_time": _start_time(os.getpid())}
        for _ in range(10):
            try:
                fd = os.open(self.path, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o644)
            except FileExistsError:
                holder = self._holder()
                if holder is not None and _alive(holder):
                    raise InputError("-o/--output", str(self.path.parent), "a folder no other adhfit run is "
                                     "writing to", f"adhfit run {holder.get('run_id')} (pid {holder.get('pid')}) is "
                                     "writing there now; wait for it to end, or give another -o.") from None
                self._take_over()
                continue
            with os.fdopen(fd, "w", encoding="utf-8") as fh:
                json.dump(me, fh)
            self._held = True
            return
        raise InputError("-o/--output", str(self.path.parent), "a folder no other adhfit run is writing to",
                         f"could not take {self.path}; remove it if no adhfit run is writing there.")

    def _holder(self) -> dict[str, Any] | None:
        try:
            holder = json.loads(self.path.read_text(encoding="utf-8"))
        except (OSError, ValueError):  # being written this instant, or garbage: judged on the next try
            return None
        return holder if isinstance(holder, dict) else None

    def _take_over(self) -> None:
        """Move a dead run's lock aside (one of two racing runs wins the rename) and drop it."""
        aside = self.path.with_name(f"{LOCK_NAME}.stale-{os.getpid()}")
        try:
            os.rename(self.path, aside)
            aside.unlink()
        except OSError:
            pass

    def release(self) -> None:
        """Drop the lock if this run holds it."""
        if self._held:
            self._held = False
            try:
                os.unlink(self.path)
            except OSError:
                pass

    def __enter__(self) -> "RunLock":
        self.acquire()
        return self

    def __exit__(self, *exc) -> None:
        self.release()


def clear_staging(outdir: Path) -> None:
    """Remove what dead runs left half-written (call with the lock held: no live run is writing)."""
    shutil.rmtree(Path(outdir) / STAGING, ignore_errors=True)


# ------------------------------------------------------------------------------------- a curve's files
def publish(stage: Path, dest: Path, batch: dict[str, Any]) -> None:
    """Move a finished fit's files from ``stage`` into ``dest``, ``report.json`` last (with ``batch``
    added), and remove report files an older run left there that this one did not write."""
    dest.mkdir(parents=True, exist_ok=True)
    _name_the_destination(stage, dest)
    report = stage / "report.json"
    d = json.loads(report.read_text(encoding="utf-8"))
    d["batch"] = batch
    tmp = stage / "report.json.tmp"
    tmp.write_text(json.dumps(d, indent=2, allow_nan=False, ensure_ascii=False) + "\n", encoding="utf-8")
    os.replace(tmp, report)
    names = sorted(p.name for p in stage.iterdir() if p.name != "report.json")
    for name in names:
        target = dest / name
        if target.is_dir() and not (stage / name).is_dir():
            shutil.rmtree(target)
        os.replace(stage / name, target)
    for name in REPORT_FILES:
        if name not in names and name != "report.json":
            _unlink(dest / name)
    os.replace(report, dest / "report.json")
    shutil.rmtree(stage, ignore_errors=True)


def _name_the_destination(stage: Path, dest: Path) -> None:
    """Reports that name a file of their own folder (an MCMC fit's ``chain.h5``) name it where it will be."""
    import html  # noqa: PLC0415
    for name, quote in (("report.json", lambda t: json.dumps(t)[1:-1]), ("report.md", str), ("report.html", html.escape)):
        path = stage / name
        if not path.is_file():
            continue
        text = path.read_text(encoding="utf-8")
        old, new = quote(str(stage)), quote(str(dest))
        if old in text:
            path.write_text(text.replace(old, new), encoding="utf-8")


def retire(dest: Path) -> None:
    """Remove a curve's reports (its re-run failed: they no longer describe the curve of this run).
    ``report.json`` goes first, so that a half-removed folder never looks complete."""
    for name in REPORT_FILES:
        _unlink(Path(dest) / name)


def _unlink(path: Path) -> None:
    try:
        path.unlink()
    except FileNotFoundError:
        pass


def reusable_report(dest: Path, data_sha256: str, scene_sha256: str, settings: str) -> dict[str, Any] | None:
    """The report.json in ``dest`` when a batch wrote it from these input bytes, this scene file and these
    settings (``--resume``), else None."""
    try:
        d = json.loads((Path(dest) / "report.json").read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    batch = d.get("batch") if isinstance(d, dict) else None
    prov = d.get("provenance") if isinstance(d, dict) else None
    if not isinstance(batch, dict) or not isinstance(prov, dict) or not data_sha256:
        return None
    same = (prov.get("input_sha256") == data_sha256 and batch.get("scene_sha256") == scene_sha256
            and batch.get("settings_sha256") == settings)
    return d if same and (Path(dest) / "report.html").is_file() else None
