"""``adhfit fit`` over several curves: one summary table, and a bad file never stops the run.

Which files (:mod:`.discovery`)
    Every argument is a curve file or a folder.  A folder stands for every curve file below it
    (:func:`adhfit.readers.folder_patterns`)
    (recursively, sorted; hidden files and folders and the output directory are skipped).  A file
    there that cannot be fitted (unreadable, a pipe, a broken link, a link pointing outside the folder)
    is a failed row that says why.  The run is a
    *batch* when there are several files or any folder; a single file is an ordinary fit.

Which scene (when ``--scene`` is not given)
    Each curve uses the nearest ``scene.toml``: in its own folder, else in the parent folders up to the
    folder given on the command line (for a file argument: its own folder only).  So a folder of sample
    subfolders, each with its ``curve.csv`` and ``scene.toml``, fits in one command, and one
    ``scene.toml`` at the top of a folder serves every curve below it that has none of its own.
    ``--scene`` given: that scene for every curve.  A curve without a scene is a failed row.

Outputs (batch)
    ``OUTDIR/summary.csv``: one row per curve (:data:`COLUMNS`; values in SI: W_ad in J/m², μh in N/m),
    written even when fits fail; each curve's own reports (report.json, report.md, report.html,
    fit.png) in ``OUTDIR/<path of the curve relative to the common folder, without .csv>/``.

Who runs the curves
    ``--workers N``: N local processes (default: one per core); ``--scheduler ADDRESS``: the workers of a
    Dask distributed cluster (``pip install 'adhfit[dask]'``; paths must be reachable from the workers;
    for long batches, workers started without Dask's statistical profiler, which otherwise holds ~1 MiB
    per second of fitting: docs/contracts.md A7, :func:`.runners.profiling_workers`).
    Each job (:func:`run_job`: curve, scene, options) fits one curve, writes its reports and returns its
    summary row; the rows are put back in job order, so ``summary.csv`` is the same whichever runs it
    (only ``wall_time_s``, a measurement, changes from run to run).  One failing curve never stops the
    others, nor does a worker process that dies.

Interruptions and re-runs (docs/contracts.md A7b, :mod:`.runs`, :mod:`.interrupt`)
    A Ctrl-C writes the summary of what finished (the rest ``interrupted``) and ends with status 130;
    each curve's reports are moved into its folder whole; a curve that fails loses its older reports;
    the output folder is locked for the run; ``--resume`` keeps the reports of curves already fitted
    from the same bytes, scene and settings.

Exit status
    0 when every curve was fitted; 1 when at least one failed (the table lists it with its error, the
    other curves' reports are written, and standard error ends with the list of failures); 2 for
    invalid command-line input (nothing found to fit, unreadable ``--scene``, an output folder that
    cannot be written or that another run is writing to); 130 after a Ctrl-C.
"""
from __future__ import annotations

import contextlib
import csv
import dataclasses
import io
import json
import os
import shutil
import sys
import threading
import time
from argparse import Namespace
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Mapping

from ..errors import AdhfitError, InputError
from .discovery import CURVE_PATTERNS, SCENE_NAME, Job, discover, is_batch, single_scene  # noqa: F401
from .interrupt import EXIT_INTERRUPTED, on_interrupt, raising
from .runs import RunInfo, RunLock, clear_staging, file_sha256, new_run, publish, retire, reusable_report
from .writing import writable_folder

#: modules a local worker needs, imported once before the workers start (by this process, where they
#: fork from it; else by the fork server)
PRELOAD = ("adhfit.cli.fit", "adhfit.fitting.api", "adhfit.fitting.stage", "adhfit.fitting.assemble",
           "adhfit.fitting.plausibility", "adhfit.data", "adhfit.scene", "adhfit.units", "pint",
           "adhfit.report.json_report", "adhfit.report.markdown", "adhfit.report.html", "adhfit.report.fit_plot",
           "adhfit.report.thumbnails", "matplotlib")

__all__ = ["COLUMNS", "Job", "discover", "is_batch", "summary_row", "failed_row", "write_summary",
           "run_batch", "run_job", "Outcome", "single_scene", "SCENE_NAME", "EXIT_SOME_FAILED",
           "EXIT_INTERRUPTED", "INTERRUPTED"]

EXIT_SOME_FAILED = 1
#: the status of a curve a Ctrl-C left unfinished
INTERRUPTED = "interrupted"
_PARAMS = ("work_of_adhesion", "mu_h")

#: summary.csv columns, in order
COLUMNS = (["file", "status", "error"]
           + [f"{p}{s}" for p in _PARAMS for s in ("", "_stderr", "_ci95_low", "_ci95_high")]
           + ["slip_selected", "slip_verdict", "slip_reported", "delta_bic", "redchi", "n_warnings", "warnings",
              "report_dir", "scene", "sha256", "adhfit_version", "method", "seed", "wall_time_s", "run_id"])



def _ci(e: Mapping[str, Any]) -> tuple[Any, Any]:
    ci = e.get("ci95") or (None, None)
    return ci[0], ci[1]


def summary_row(job: Job, report: Mapping[str, Any]) -> dict[str, Any]:
    """The summary.csv row of a fitted curve, from its report.json dictionary (docs/contracts.md A5)."""
    slip = report.get("slip", {}) or {}
    prov = report.get("provenance", {}) or {}
    row: dict[str, Any] = {"file": str(job.data), "status": "ok", "error": ""}
    for name in _PARAMS:
        e = report.get("parameters", {}).get(name, {}) or {}
        lo, hi = _ci(e)
        row.update({name: e.get("value"), f"{name}_stderr": e.get("stderr"), f"{name}_ci95_low": lo,
                    f"{name}_ci95_high": hi})
    fits = report.get("fits", {}) or {}
    reported = slip.get("parameters_from") or slip.get("selected") or next(iter(fits), None)
    warnings = list(report.get("warnings", []) or [])
    row.update({"slip_selected": slip.get("selected") or "", "slip_verdict": slip.get("verdict", ""),
                "slip_reported": reported or "", "delta_bic": slip.get("delta_bic"),
                "redchi": (fits.get(reported) or {}).get("redchi") if reported else None,
                "n_warnings": len(warnings), "warnings": " | ".join(warnings), "report_dir": str(job.out),
                "scene": str(job.scene), "sha256": prov.get("input_sha256", ""),
                "adhfit_version": prov.get("adhfit_version", ""), "method": report.get("method", ""),
                "seed": prov.get("seed"), "wall_time_s": report.get("wall_time_s")})
    return row


def failed_row(job: Job, error: BaseException | str, *, method: str = "", seed: Any = None) -> dict[str, Any]:
    """The summary.csv row of a curve that could not be fitted."""
    from .. import __version__  # noqa: PLC0415
    sha = file_sha256(job.data)  # "" for a pipe (never opened: it would wait) or an unreadable file
    if isinstance(error, (str, AdhfitError)):  # adhfit's own errors already say what and where
        message = str(error)
    else:
        message = f"{type(error).__name__}: {error}"
    return {"file": str(job.data), "status": "failed", "error": " ".join(str(message).split()),
            "report_dir": str(job.out), "scene": "" if job.scene is None else str(job.scene), "sha256": sha,
            "adhfit_version": __version__, "method": method, "seed": seed}


def _cell(v: Any) -> Any:
    if v is None:
        return ""
    if isinstance(v, float):
        return repr(v)
    return v


def write_summary(rows: list[Mapping[str, Any]], path: str | Path) -> Path:
    """Write summary.csv (:data:`COLUMNS`; empty cells where a value is missing), atomically: a reader
    sees the old table or the new one, never half of one."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    try:
        with tmp.open("w", newline="", encoding="utf-8") as fh:
            w = csv.DictWriter(fh, fieldnames=COLUMNS, extrasaction="ignore")
            w.writeheader()
            for r in rows:
                w.writerow({k: _cell(r.get(k)) for k in COLUMNS})
        os.replace(tmp, path)
    finally:
        tmp.unlink(missing_ok=True)
    return path


def _default_outdir(data: list[Path]) -> Path:
    if len(data) == 1 and data[0].is_dir():
        return Path(f"{data[0].resolve().name}_fit")
    return Path("adhfit_fit")


@dataclass(frozen=True)
class Outcome:
    """What one job returns: its place in the batch, its summary row, what the fit printed, and the
    error message when it failed (``None`` when it was fitted)."""

    index: int
    row: dict[str, Any]
    output: str = ""
    error: str | None = None
    #: re-used from an earlier run's reports (``--resume``), not fitted now
    resumed: bool = False


#: one fit at a time per process: a Dask worker may run tasks in threads, and a fit redirects standard
#: output and draws with matplotlib, neither of which is thread-safe
_ONE_AT_A_TIME = threading.Lock()


def _absolute(job: Job, base: str) -> Job:
    """The job with relative paths resolved against ``base`` (the submitting process's folder)."""
    def fix(p: Path | None) -> Path | None:
        return p if p is None or Path(p).is_absolute() else Path(base) / p
    return dataclasses.replace(job, data=fix(job.data), scene=fix(job.scene), out=fix(job.out))


def _failed(index: int, job: Job, base: str, error: BaseException | str, args: Namespace,
            output: str = "") -> Outcome:
    row = failed_row(_absolute(job, base), error, method=getattr(args, "method", ""),
                     seed=getattr(args, "seed", None))
    row.update(file=str(job.data), report_dir=str(job.out), scene="" if job.scene is None else str(job.scene))
    return Outcome(index, row, output, row["error"])


def _fit_into(folder: Path, here: Job, args: Namespace, fit_one: Callable[[Namespace], int],
              buf: io.StringIO) -> None:
    """The single-curve fit of ``here`` with its reports (and the thumbnail) written into ``folder``."""
    if here.problem:
        raise InputError("DATA", str(here.data), "a readable curve file", here.problem)
    if here.scene is None:
        raise InputError("scene", None, f"a scene file ({here.scene_note})")
    # one curve per process at a time: every core already fits, so no second process draws
    one = Namespace(**{**vars(args), "data": here.data, "scene": here.scene, "output": folder, "painter": False})
    with contextlib.redirect_stdout(buf):
        status = fit_one(one)
    if status != 0:
        raise RuntimeError(f"the fit ended with exit status {status}")
    if not getattr(args, "no_plot", False):  # summary.html's small figure, drawn here on every core
        from ..report.thumbnails import write_thumbnail  # noqa: PLC0415
        write_thumbnail(folder)


def run_job(index: int, job: Job, args: Namespace, fit_one: Callable[[Namespace], int], base: str,
            run: RunInfo | None = None) -> Outcome:
    """Fit one curve of a batch, in whichever process runs it; never raises for a bad curve.

    Paths are resolved against ``base`` (the working folder of the process that made the jobs); the
    summary row keeps them as given, so it does not depend on where the job ran.  With ``run`` (a batch
    run, :mod:`.runs`), the reports are written into a staging folder and moved into the curve's folder
    only when complete; a failure removes the curve's older reports.
    """
    here = _absolute(job, base)
    buf = io.StringIO()
    with _ONE_AT_A_TIME:
        stage = None if run is None else run.stage(index)
        try:
            if stage is not None:  # made here: the fit's own check of its folder then creates nothing
                shutil.rmtree(stage, ignore_errors=True)
                stage.mkdir(parents=True)
            _fit_into(here.out if stage is None else stage, here, args, fit_one, buf)
            if stage is not None:
                publish(stage, here.out, {"run_id": run.run_id, "scene_sha256": file_sha256(here.scene),
                                          "settings_sha256": run.settings_sha256})
            report = json.loads((here.out / "report.json").read_text(encoding="utf-8"))
            row = {**summary_row(job, report), "run_id": "" if run is None else run.run_id}
            return Outcome(index, row, _printed(buf, stage, here.out))
        except KeyboardInterrupt:
            raise
        except Exception as err:  # noqa: BLE001 - one bad curve must not stop the batch; it is listed
            if stage is not None:
                shutil.rmtree(stage, ignore_errors=True)
                retire(here.out)  # an older report must not pass for this run's
            out = _failed(index, job, base, err, args, _printed(buf, stage, here.out))
            out.row["run_id"] = "" if run is None else run.run_id
            return out


def _printed(buf: io.StringIO, stage: Path | None, dest: Path) -> str:
    """What the fit printed, naming the curve's folder rather than the staging one."""
    text = buf.getvalue()
    return text if stage is None else text.replace(str(stage), str(dest))


def _runner(args: Namespace, n_jobs: int) -> tuple[str, Any]:
    """("serial", None), ("local", workers) or ("dask", address) from ``--workers`` / ``--scheduler``.

    ``args.workers`` is ``None`` for one process per core; a Namespace without it runs in this process.
    """
    from .runners import default_workers  # noqa: PLC0415
    address = getattr(args, "scheduler", None)
    workers = getattr(args, "workers", 1)
    if address is not None:
        if getattr(args, "workers", None) is not None:
            raise InputError("--workers", workers, "absent when --scheduler is given (the cluster's workers "
                                                   "run the curves)")
        return "dask", str(address)
    workers = default_workers() if workers is None else workers
    if isinstance(workers, bool) or not (isinstance(workers, int) and workers >= 1):
        raise InputError("--workers", workers, "a positive integer (local processes)")
    return ("serial", None) if workers == 1 or n_jobs == 1 else ("local", workers)


def _resume(jobs: list[Job], run: RunInfo, base: str, args: Namespace) -> dict[int, Outcome]:
    """``--resume``: the curves whose reports a batch wrote from the same bytes, scene and settings."""
    found = {}
    for i, job in enumerate(jobs):
        here = _absolute(job, base)
        if job.problem or here.scene is None:
            continue
        report = reusable_report(here.out, file_sha256(here.data), file_sha256(here.scene), run.settings_sha256)
        if report is not None:
            row = {**summary_row(job, report), "run_id": report["batch"].get("run_id", "")}
            found[i] = Outcome(i, row, "", None, resumed=True)
    return found


def _interrupted(index: int, job: Job, run: RunInfo) -> Outcome:
    """The row of a curve a Ctrl-C left unfinished (running or queued)."""
    row = {"file": str(job.data), "status": INTERRUPTED, "report_dir": str(job.out),
           "scene": "" if job.scene is None else str(job.scene), "run_id": run.run_id,
           "error": "not fitted: the batch was interrupted (Ctrl-C) before this curve finished; "
                    "re-run with --resume to fit only the curves left"}
    return Outcome(index, row, "", row["error"])


def _run_jobs(jobs: list[Job], todo: list[int], args: Namespace, fit_one: Callable[[Namespace], int],
              base: str, run: RunInfo, report: Callable[[Outcome], None]) -> None:
    """Fit the jobs ``todo`` with the runner ``args`` ask for.  A Ctrl-C raises KeyboardInterrupt out of
    the local and Dask runners (they stop their workers first); in this process (serial) it ends the
    process through the finish :func:`run_batch` set (:mod:`.interrupt`)."""
    kind, how = _runner(args, len(todo))
    job_args = Namespace(**{k: v for k, v in vars(args).items() if k != "run"})  # what a worker needs
    calls = [(i, jobs[i], job_args, fit_one, base, run) for i in todo]
    if kind == "serial":
        for call in calls:
            report(run_job(*call))
        return
    from . import runners  # noqa: PLC0415

    def crashed(pos: int, message: str) -> Outcome:
        i = calls[pos][0]
        out = _failed(i, jobs[i], base, message, args)
        out.row["run_id"] = run.run_id
        return out
    if kind == "local":
        # compiled (a cold cache, with the clock) or loaded once here: where the workers fork from this
        # process they start with the kernels in memory, instead of each loading them (a second of CPU
        # each); elsewhere they load them from the cache this leaves
        from .engine import engine_cache_is_cold, start_engine  # noqa: PLC0415
        if runners.forks_here() or engine_cache_is_cold():
            start_engine("displacement", quiet=getattr(args, "quiet", False))
        if runners.forks_here():  # pint's unit registry too (every fit parses units): built once
            from ..units import registry  # noqa: PLC0415
            registry()
    with raising():
        if kind == "local":
            runners.run_local(run_job, calls, how, report, crashed, preload=PRELOAD)
        else:
            runners.run_dask(run_job, calls, how, report, crashed)


def run_batch(args: Namespace, fit_one: Callable[[Namespace], int]) -> int:
    """Fit every curve of ``args.data`` with ``fit_one`` (the single-curve ``adhfit fit``); returns the exit
    status.  ``args.workers`` local processes (``None``: one per core; absent: this process) or the Dask
    scheduler at ``args.scheduler`` run the curves; the summary is the same whichever does.  Prints one
    line per curve as it finishes and, at the end, the failures, on standard error.  The output folder is
    locked for the run, and a Ctrl-C ends it with the summary of what finished (:mod:`.runs`)."""
    data = [Path(p) for p in args.data]
    outdir = Path(args.output if args.output is not None else _default_outdir(data))
    if args.scene is not None and not Path(args.scene).is_file():
        raise InputError("--scene", str(args.scene), "an existing scene file (TOML)")
    jobs = discover(data, scene=args.scene, outdir=outdir)
    _runner(args, len(jobs))  # invalid --workers / --scheduler: said before anything is written
    run = new_run(outdir, args)
    lock = RunLock(writable_folder(outdir), run.run_id)
    lock.acquire()
    try:
        clear_staging(outdir)  # what dead runs left half-written
        return _Batch(jobs, args, outdir, run, lock).run(fit_one)
    finally:
        clear_staging(outdir)  # an interrupted run's half-written curves
        lock.release()


class _Batch:
    """The outcomes of one batch run as they arrive, and its conclusion (summary, last lines, status)."""

    def __init__(self, jobs: list[Job], args: Namespace, outdir: Path, run: RunInfo, lock: RunLock) -> None:
        self.jobs, self.args, self.outdir, self.run_info, self.lock = jobs, args, outdir, run, lock
        self.outcomes: dict[int, Outcome] = {}
        self.t0 = time.perf_counter()

    def report(self, out: Outcome) -> None:
        """One curve done: remember it, and say so on standard error."""
        self.outcomes[out.index] = out
        note = f" (resumed: reports of run {out.row.get('run_id')})" if out.resumed else ""
        print(f"[{len(self.outcomes)}/{len(self.jobs)}] {self.jobs[out.index].data}{note}", file=sys.stderr,
              flush=True)
        if out.output:
            print(out.output, end="", flush=True)
        if out.error is not None:
            print(f"    failed: {out.error}", file=sys.stderr, flush=True)

    def run(self, fit_one: Callable[[Namespace], int]) -> int:
        base = os.getcwd()
        if getattr(self.args, "resume", False):
            for out in _resume(self.jobs, self.run_info, base, self.args).values():
                self.report(out)
        todo = [i for i in range(len(self.jobs)) if i not in self.outcomes]
        try:
            with on_interrupt(self.interrupted):
                _run_jobs(self.jobs, todo, self.args, fit_one, base, self.run_info, self.report)
        except KeyboardInterrupt:
            return self.interrupted()
        return self.finished()

    def _summaries(self) -> Path:
        for i, job in enumerate(self.jobs):
            if i not in self.outcomes:
                self.outcomes[i] = _interrupted(i, job, self.run_info)
        return _write_summaries([self.outcomes[i].row for i in range(len(self.jobs))], self.outdir)

    def interrupted(self) -> int:
        """Ctrl-C: the summary of what finished, one line, :data:`EXIT_INTERRUPTED`."""
        n = len(self.jobs)
        done = len(self.outcomes)
        table = self._summaries()
        clear_staging(self.outdir)
        self.lock.release()
        print(f"adhfit: interrupted (Ctrl-C) after {done} of {n} curves; wrote {table} and summary.html (the "
              f"other {n - done} listed as interrupted); --resume fits only those", file=sys.stderr, flush=True)
        return EXIT_INTERRUPTED

    def finished(self) -> int:
        """Every curve done: the summary, the failures, the exit status."""
        table = self._summaries()
        jobs, outcomes = self.jobs, self.outcomes
        failures = [(jobs[i], outcomes[i].error) for i in range(len(jobs)) if outcomes[i].error is not None]
        ok = len(jobs) - len(failures)
        print(f"{ok} of {len(jobs)} curves fitted in {time.perf_counter() - self.t0:.1f} s; wrote {table} and "
              "summary.html")
        if failures:
            print(f"adhfit: {len(failures)} of {len(jobs)} curves failed (listed in {table}):", file=sys.stderr)
            for job, message in failures:
                print(f"  {job.data}: {message}", file=sys.stderr)
            return EXIT_SOME_FAILED
        return 0


def _write_summaries(rows: list[dict[str, Any]], outdir: Path) -> Path:
    """summary.csv, and summary.html linking only the reports this summary vouches for (status ok)."""
    table = write_summary(rows, outdir / "summary.csv")
    from ..report.summary_html import write_summary_html  # noqa: PLC0415 - a page to look at, next to the table
    write_summary_html([r if r.get("status") == "ok" else {**r, "report_dir": ""} for r in rows], outdir)
    return table
