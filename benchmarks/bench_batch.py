"""Batch fitting on every core (issues 10 and 21): 16 curves serial against ``--workers N``.

The 8 sample curves (``sample_data/*``: both controls, both slips, curved and flat substrates), copied
into a temporary folder as many times as ``--curves`` asks (16: each twice, ``set0/`` and ``set1/``), are
fitted as one batch through the command line, in a fresh process each time, exactly as a user runs it::

    python -m adhfit.cli fit DATA --workers 1 -o OUT      # serial
    python -m adhfit.cli fit DATA --workers 2 -o OUT      # two local processes

with the default fit options (both slips compared, profile intervals, figures), or the options given
after ``--``.  Runs alternate (serial, parallel, serial, ...) so that the shared machine's load hits both
alike; the result is the ratio of the medians, with the load average at the start and the end.  Each
pair of summaries is checked to be identical (every column but ``wall_time_s``).

Usage::

    python benchmarks/bench_batch.py [--repeat 3] [--workers 2] [--curves 16] [-- FIT OPTIONS]

Writes ``benchmarks/results/batch.md`` and ``benchmarks/results/batch.json``.

A long batch on a local Dask cluster (memory, not speed)::

    python benchmarks/bench_batch.py --dask 1000 [--dask-workers 2] [--time-limit 2400] [--dask-profiler]
                                     [-- FIT OPTIONS]

makes ``--dask`` small synthetic curves (``adhfit simulate --scene`` of the sample's displacement-control
scene, 60 rows, 0.5 % noise, W_ad, μh and the slip condition varied, one seed each; run in one process),
starts a ``distributed.LocalCluster`` (``--dask-workers`` processes, one thread each; Dask's statistical
profiler off in the workers, as docs/contracts.md A7 advises for long batches, unless ``--dask-profiler``),
and runs::

    python -m adhfit.cli fit DATA --scheduler ADDRESS -o OUT

with the default fit options (or those after ``--``), sampling every second the resident memory (RSS)
of each Dask worker, of the command and of the scheduler (this process), and the curves done (the
command's ``[k/N]`` progress lines).  The result says how much each worker's RSS grew over the second
half of the curves (:data:`BOUNDED_MIB` or less: bounded).  After ``--time-limit`` seconds the command gets a Ctrl-C (it then
writes the summary of what finished), and the result says how many curves were fitted.  Writes
``benchmarks/results/batch_dask.md`` and ``benchmarks/results/batch_dask.json`` (``batch_dask_profiler.*``
with ``--dask-profiler``).
"""
from __future__ import annotations

import argparse
import csv
import json
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "benchmarks" / "results"
DATA = ROOT / "sample_data"


def _revision() -> str:
    def git(*args: str) -> str:
        return subprocess.run(["git", *args], cwd=ROOT, capture_output=True, text=True).stdout.strip()
    return git("rev-parse", "--short", "HEAD") + ("+dirty" if git("status", "--porcelain", "adhfit") else "")


def _summary(out: Path) -> list[dict]:
    with (out / "summary.csv").open(newline="", encoding="utf-8") as fh:
        rows = list(csv.DictReader(fh))
    for r in rows:
        r.pop("wall_time_s")
        r.pop("run_id", None)  # names the run: differs from run to run by design
        r["report_dir"] = str(Path(r["report_dir"]).relative_to(out))
    return rows


def _cpu_tree(proc, seen: dict) -> None:
    """Record the CPU time (user + system, s) of ``proc`` and of every descendant, by pid."""
    try:
        import psutil  # noqa: PLC0415 - optional: only for the CPU accounting
    except ImportError:
        return
    try:
        root = psutil.Process(proc.pid)
        for p in [root, *root.children(recursive=True)]:
            try:
                t = p.cpu_times()
                seen[p.pid] = (p.ppid(), t.user + t.system)
            except psutil.Error:
                pass
    except psutil.Error:
        pass


def make_data(tmp: Path, n: int) -> Path:
    """A folder of ``n`` curves: the sample folders (curve.csv and scene.toml) copied set after set."""
    import shutil  # noqa: PLC0415
    samples = sorted(p.parent for p in DATA.glob("*/curve.csv"))
    data = tmp / "data"
    for k in range(n):
        src = samples[k % len(samples)]
        dest = data / f"set{k // len(samples)}" / src.name
        dest.mkdir(parents=True)
        for f in ("curve.csv", "scene.toml"):
            shutil.copy(src / f, dest / f)
    return data


def _run(workers: int, extra: list[str], tmp: Path, tag: str, ok: tuple = (0,)) -> tuple[float, list[dict], dict]:
    out = tmp / tag
    cmd = [sys.executable, "-m", "adhfit.cli", "fit", str(tmp / "data"), "--workers", str(workers), "-o", str(out),
           *extra]
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    seen: dict = {}
    t0 = time.perf_counter()
    proc = subprocess.Popen(cmd, cwd=ROOT, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    while proc.poll() is None:
        _cpu_tree(proc, seen)
        time.sleep(0.1)
    wall = time.perf_counter() - t0
    _, err = proc.communicate()
    if proc.returncode not in ok:
        raise SystemExit(f"{' '.join(cmd)} ended with {proc.returncode}:\n{err[-2000:]}")
    return wall, _summary(out), _cpu_split(seen, proc.pid)


def _cpu_split(seen: dict, parent: int) -> dict:
    """CPU seconds of the main process, of a fork server (when the workers fork from one: the main
    process's children that have children) and of each worker."""
    children = {pid for pid, (ppid, _) in seen.items() if ppid == parent}
    servers = {pid for pid in children if any(ppid == pid for ppid, _ in seen.values())}
    workers = [c for pid, (ppid, c) in seen.items() if ppid in servers or (ppid == parent and pid not in servers)]
    return {"main": seen.get(parent, (0, 0.0))[1], "server": sum(seen[pid][1] for pid in servers),
            "workers": sorted(workers, reverse=True)}


def make_synthetic(data: Path, n: int) -> Path:
    """``n`` small curves made by ``adhfit simulate --scene`` in this process, under one scene.toml."""
    import contextlib  # noqa: PLC0415
    import io  # noqa: PLC0415
    import numpy as np  # noqa: PLC0415
    from adhfit.cli.main import main as adhfit_main  # noqa: PLC0415
    data.mkdir(parents=True)
    scene = data / "scene.toml"
    scene.write_text((DATA / "fea_displacement_no-slip" / "scene.toml").read_text())
    rng = np.random.default_rng(21)
    for k in range(n):
        w, mu = rng.uniform(0.3, 0.5), rng.uniform(1.5, 2.5)
        slip = ("no-slip", "frictionless")[k % 2]
        with contextlib.redirect_stderr(io.StringIO()):
            code = adhfit_main(["simulate", "--scene", str(scene), "--mu-h", f"{mu:.4f} N/m", "--work-of-adhesion",
                                f"{w:.4f} J/m^2", "--slip", slip, "--delta-max", "0.6 mm", "--points", "60",
                                "--noise", "0.005", "--seed", str(k), "-o", str(data / f"curve_{k:04d}.csv")])
        if code != 0:
            raise SystemExit(f"adhfit simulate failed for curve {k}")
    return data


#: a worker's RSS may grow by this much (MiB) over the second half of the curves and still count as bounded
#: (the run-to-run wobble of a worker's RSS between curves is ~15 MiB; Dask's profiler added ~1 MiB per second)
BOUNDED_MIB = 30.0
#: Dask's statistical profiler in the workers (distributed.worker.profile.enabled), as an environment variable
PROFILER_ENV = "DASK_DISTRIBUTED__WORKER__PROFILE__ENABLED"


def _worker_profile(dask_worker) -> dict:
    """Whether a Dask worker runs its statistical profiler, and how much profile it holds (cycles, nodes)."""
    import dask  # noqa: PLC0415

    def nodes(tree: dict) -> int:
        return 1 + sum(nodes(c) for c in tree.get("children", {}).values())
    history = list(getattr(dask_worker, "profile_history", ()))
    return {"enabled": bool(dask.config.get("distributed.worker.profile.enabled")), "cycles": len(history),
            "nodes": sum(nodes(tree) for _, tree in history)}


def run_dask_batch(n: int, n_workers: int, extra: list[str], time_limit: float, argv: list[str],
                   profiler: bool = False) -> dict:
    import psutil  # noqa: PLC0415
    import signal  # noqa: PLC0415
    revision = _revision()  # what runs, before anything else can change
    if not profiler:  # the workers are processes started from this one: they inherit its environment
        os.environ[PROFILER_ENV] = "False"
    import dask  # noqa: PLC0415
    from distributed import Client, LocalCluster  # noqa: PLC0415
    dask.config.refresh()
    me = psutil.Process()
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        t0 = time.perf_counter()
        data = make_synthetic(tmp / "data", n)
        made = time.perf_counter() - t0
        print(f"{n} curves made in {made:.0f} s", flush=True)
        load0 = os.getloadavg()
        with LocalCluster(n_workers=n_workers, threads_per_worker=1, processes=True, dashboard_address=None) as cl, \
                Client(cl.scheduler_address) as client:
            pids = client.run(os.getpid)
            workers = {addr: psutil.Process(pid) for addr, pid in pids.items()}
            profile_on = sorted({p["enabled"] for p in client.run(_worker_profile).values()})
            if profile_on != [profiler]:
                raise SystemExit(f"the workers' profiler is {profile_on}, not {profiler} as asked")
            limit = cl.workers[next(iter(cl.workers))].memory_manager.memory_limit if cl.workers else None
            cmd = [sys.executable, "-m", "adhfit.cli", "fit", str(data), "--scheduler", cl.scheduler_address,
                   "-o", str(tmp / "out"), *extra]
            err_path = tmp / "stderr.txt"
            samples = []
            t1 = time.perf_counter()
            with err_path.open("w") as err:
                proc = subprocess.Popen(cmd, cwd=ROOT, env={**os.environ, "PYTHONPATH": str(ROOT)},
                                        stdout=subprocess.DEVNULL, stderr=err)
                cli = psutil.Process(proc.pid)
                interrupted = False
                while proc.poll() is None:
                    elapsed = time.perf_counter() - t1
                    if elapsed > time_limit and not interrupted:
                        proc.send_signal(signal.SIGINT)
                        interrupted = True
                    done = sum(1 for line in err_path.read_text(errors="replace").splitlines()
                               if line.startswith("["))
                    row = {"t": round(elapsed, 1), "done": done,
                           "workers_mib": [_rss(p) for p in workers.values()],
                           "cli_mib": _rss(cli), "scheduler_mib": _rss(me)}
                    samples.append(row)
                    if len(samples) % 60 == 0:
                        print(f"{row['t']:.0f} s: {done}/{n} curves; worker RSS {row['workers_mib']} MiB", flush=True)
                    time.sleep(1.0)
            wall = time.perf_counter() - t1
            worker_cpu = [sum(p.cpu_times()[:2]) for p in workers.values()]
            profiles = [client.run(_worker_profile).get(addr) for addr in workers]
        load1 = os.getloadavg()
        text = err_path.read_text(errors="replace")
        done = sum(1 for line in text.splitlines() if line.startswith("["))
        rows = list(csv.DictReader((tmp / "out" / "summary.csv").open(newline="", encoding="utf-8")))
        ok = sum(1 for r in rows if r["status"] == "ok")
    peak = [max(s["workers_mib"][i] for s in samples if s["workers_mib"][i] is not None) for i in range(n_workers)]
    half = next((s for s in samples if s["done"] >= n // 2), None)
    end = next((s for s in samples if s["done"] >= n), samples[-1] if samples else None)
    growth = None if half is None or end is None else \
        [round(b - a, 1) for a, b in zip(half["workers_mib"], end["workers_mib"]) if a is not None and b is not None]
    return {"command": " ".join(["python benchmarks/bench_batch.py", *argv]), "curves": n, "dask_workers": n_workers,
            "fit_options": extra, "curves_made_s": made, "wall_s": wall, "time_limit_s": time_limit,
            "interrupted_at_time_limit": interrupted, "reported": done, "fitted_ok": ok, "summary_rows": len(rows),
            "exit_status": proc.returncode, "worker_cpu_s": worker_cpu, "worker_memory_limit_bytes": limit,
            "peak_worker_rss_mib": peak, "peak_cli_rss_mib": max(s["cli_mib"] or 0 for s in samples),
            "peak_scheduler_rss_mib": max(s["scheduler_mib"] or 0 for s in samples),
            "rss_by_progress": _by_progress(samples, n), "load_average_start": load0, "load_average_end": load1,
            "worker_profiler": profiler, "worker_profiles_at_end": profiles,
            "second_half_growth_mib": growth, "bounded_mib": BOUNDED_MIB,
            "bounded": growth is not None and max(growth) <= BOUNDED_MIB,
            "nproc": os.cpu_count(), "python": platform.python_version(), "adhfit_revision": revision,
            "last_lines": text.strip().splitlines()[-3:],
            "notes": [line for line in text.splitlines() if line.startswith("adhfit:")]}


def _rss(p) -> float | None:
    try:
        return round(p.memory_info().rss / 2**20, 1)
    except Exception:  # noqa: BLE001 - a process that ended
        return None


def _by_progress(samples: list[dict], n: int) -> list[dict]:
    """The first sample at or after each tenth of the curves done (and the last): memory against progress."""
    out, marks = [], [max(1, round(n * k / 10)) for k in range(1, 11)]
    for m in marks:
        hit = next((s for s in samples if s["done"] >= m), None)
        if hit is not None and (not out or out[-1] is not hit):
            out.append(hit)
    if samples and (not out or out[-1] is not samples[-1]):
        out.append(samples[-1])
    return out


def _dask_markdown(r: dict) -> str:
    opts = " ".join(r["fit_options"]) or "(defaults: both slips compared, profile intervals, figures)"
    rows = "\n".join(f"| {s['done']} | {s['t']:.0f} | {' / '.join(str(w) for w in s['workers_mib'])} | {s['cli_mib']} | "
                     f"{s['scheduler_mib']} |" for s in r["rss_by_progress"])
    stop = (f"stopped by a Ctrl-C at the time limit ({r['time_limit_s']:.0f} s) after **{r['reported']} of "
            f"{r['curves']} curves**" if r["interrupted_at_time_limit"] else f"all {r['curves']} curves reported")
    limit = r["worker_memory_limit_bytes"]
    prof = ("on (Dask's default)" if r.get("worker_profiler") else
            f"off (`{PROFILER_ENV}=False` in the workers' environment, as docs/contracts.md A7 advises)")
    held = "; ".join(f"{p['cycles']} cycles, {p['nodes']} nodes" for p in r.get("worker_profiles_at_end") or [] if p)
    growth = r.get("second_half_growth_mib")
    verdict = ("not measured (the second half did not finish)" if growth is None else
               f"{', '.join(f'{g:+.1f}' for g in growth)} MiB per worker: "
               + ("**bounded**" if r["bounded"] else "**not bounded**")
               + f" (bounded here means at most {r['bounded_mib']:.0f} MiB)")
    return f"""# Batch of {r['curves']} curves on a local Dask cluster: memory

Command: `{r['command']}`  
Machine: python {r['python']}, nproc {r['nproc']}, adhfit revision {r['adhfit_revision']}, load average
(1, 5, 15 min) at start {', '.join(f'{x:.2f}' for x in r['load_average_start'])}, at end
{', '.join(f'{x:.2f}' for x in r['load_average_end'])} (the machine is shared by four engineers).  
{r['curves']} synthetic curves (`adhfit simulate --scene`, 60 rows, 0.5 % noise; made in {r['curves_made_s']:.0f} s),
`distributed.LocalCluster` of {r['dask_workers']} worker processes with one thread each (memory limit per
worker {limit / 2**30 if limit else float('nan'):.1f} GiB, Dask's default; statistical profiler {prof}), then
`python -m adhfit.cli fit DATA --scheduler ADDRESS -o OUT`, fit options: {opts}.

Result: {stop}; {r['fitted_ok']} fitted (`status` ok), summary.csv with {r['summary_rows']} rows, exit status
{r['exit_status']}, {r['wall_s']:.0f} s wall; CPU of the workers {', '.join(f'{c:.0f}' for c in r['worker_cpu_s'])} s.

**Peak RSS per worker: {', '.join(f'{m:.0f}' for m in r['peak_worker_rss_mib'])} MiB**; the command (client):
{r['peak_cli_rss_mib']:.0f} MiB; the scheduler (the benchmark's process): {r['peak_scheduler_rss_mib']:.0f} MiB.

Growth of each worker's RSS over the second half of the curves (from the first sample with {r['curves'] // 2}
done to the first with {r['curves']} done): {verdict}.  Profile held by each worker at the end: {held or 'not asked'}.

Resident memory (MiB) against the curves done (the first sample once each tenth was reached):

| curves done | s | workers | command | scheduler |
|---:|---:|---|---:|---:|
{rows}

The progress display is the command's own: one `[k/N] file` line on standard error per finished curve.
Last lines: {' / '.join('`' + line + '`' for line in r['last_lines'])}
{_notes_text(r)}"""


def _notes_text(r: dict) -> str:
    notes = r.get("notes")
    if notes is None:
        return ""
    return ("\nThe command's notes on standard error: " + (" / ".join(f"`{n}`" for n in notes) if notes else "none")
            + ".\n")


def main(argv: list[str] | None = None) -> None:
    argv = sys.argv[1:] if argv is None else argv
    extra = argv[argv.index("--") + 1:] if "--" in argv else []
    own = argv[: argv.index("--")] if "--" in argv else argv
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--curves", type=int, default=16)
    ap.add_argument("--dask", type=int, default=None, metavar="CURVES", help="a long batch on a local Dask cluster")
    ap.add_argument("--dask-workers", type=int, default=2)
    ap.add_argument("--time-limit", type=float, default=2400.0)
    ap.add_argument("--dask-profiler", action="store_true",
                    help="keep Dask's statistical profiler on in the workers (its default; ~1 MiB per second each)")
    args = ap.parse_args(own)
    if args.dask is not None:
        result = run_dask_batch(args.dask, args.dask_workers, extra, args.time_limit, argv, args.dask_profiler)
        RESULTS.mkdir(parents=True, exist_ok=True)
        name = "batch_dask_profiler" if args.dask_profiler else "batch_dask"
        (RESULTS / f"{name}.json").write_text(json.dumps(result, indent=2) + "\n")
        (RESULTS / f"{name}.md").write_text(_dask_markdown(result))
        print(_dask_markdown(result))
        return
    n_curves = args.curves
    load0 = os.getloadavg()
    times: dict[str, list[float]] = {"serial": [], "parallel": []}
    cpu: dict[str, list[dict]] = {"serial": [], "parallel": []}
    with tempfile.TemporaryDirectory() as tmp:
        make_data(Path(tmp), n_curves)
        _run(1, extra + ["--slip", "no-slip", "--no-profile", "--no-plot"], Path(tmp), "warm",
             ok=(0, 1))  # numba cache (a frictionless curve may fail to fit as no-slip: no matter)
        for k in range(args.repeat):
            t_s, rows_s, c_s = _run(1, extra, Path(tmp), f"s{k}")
            t_p, rows_p, c_p = _run(args.workers, extra, Path(tmp), f"p{k}")
            if rows_s != rows_p:
                diff = sorted({k for a, b in zip(rows_s, rows_p) for k in a if a[k] != b.get(k)})
                raise SystemExit(f"serial and parallel summaries differ in {diff}: "
                                 f"{[(a['file'], {k: (a[k], b[k]) for k in diff}) for a, b in zip(rows_s, rows_p)][:3]}")
            times["serial"].append(t_s)
            times["parallel"].append(t_p)
            cpu["serial"].append(c_s)
            cpu["parallel"].append(c_p)
            print(f"run {k + 1}: serial {t_s:.1f} s, --workers {args.workers} {t_p:.1f} s; cpu {c_s} / {c_p}",
                  flush=True)
    load1 = os.getloadavg()
    med = {k: statistics.median(v) for k, v in times.items()}
    result = {"command": " ".join(["python benchmarks/bench_batch.py", *argv]), "curves": n_curves,
              "workers": args.workers, "repeat": args.repeat, "fit_options": extra, "times_s": times,
              "median_s": med, "cpu_s": cpu, **_projection(cpu), "ratio_of_medians": med["parallel"] / med["serial"],
              "ratio_of_mins": min(times["parallel"]) / min(times["serial"]), "summaries_identical": True,
              "autogroup": _autogroup(), "load_average_start": load0, "load_average_end": load1, "nproc": os.cpu_count(),
              "python": platform.python_version(), "adhfit_revision": _revision()}
    RESULTS.mkdir(parents=True, exist_ok=True)
    (RESULTS / "batch.json").write_text(json.dumps(result, indent=2) + "\n")
    (RESULTS / "batch.md").write_text(_markdown(result))
    print(_markdown(result))


def _autogroup() -> bool | None:
    """Whether Linux autogroup scheduling is on (``None``: not Linux, or not known)."""
    try:
        return Path("/proc/sys/kernel/sched_autogroup_enabled").read_text().strip() == "1"
    except OSError:
        return None


def _projection(cpu: dict) -> dict:
    """Wall time on an idle machine from the CPU times: serial = its CPU time; parallel = the main
    process + the server's imports + the busiest worker (the workers run side by side on their cores).
    A model, not a measurement; it needs psutil to see the worker processes."""
    if not all(c["workers"] for c in cpu["parallel"]):
        return {}
    serial = statistics.median(c["main"] for c in cpu["serial"])
    parallel = statistics.median(c["main"] + c["server"] + c["workers"][0] for c in cpu["parallel"])
    return {"idle_projection": {"serial_cpu_s": serial, "parallel_critical_path_cpu_s": parallel,
                                "ratio": parallel / serial}}


def _markdown(r: dict) -> str:
    opts = " ".join(r["fit_options"]) or "(defaults: both slips compared, profile intervals, figures)"
    rows = "\n".join(f"| {i + 1} | {s:.1f} | {p:.1f} |"
                     for i, (s, p) in enumerate(zip(r["times_s"]["serial"], r["times_s"]["parallel"])))
    return f"""# Batch of {r['curves']} curves: serial against `--workers {r['workers']}`

Command: `{r['command']}`  
Machine: python {r['python']}, nproc {r['nproc']}, adhfit revision {r['adhfit_revision']}, load average
(1, 5, 15 min) at start {', '.join(f'{x:.2f}' for x in r['load_average_start'])}, at end
{', '.join(f'{x:.2f}' for x in r['load_average_end'])} (the machine is shared).  
Each run: `python -m adhfit.cli fit DATA --workers N -o OUT` ({r['curves']} curves: the 8 sample curves copied
set after set into DATA) in a fresh process (imports, numba
cache load, fits, reports, summary.csv), fit options: {opts}. Runs alternate serial / parallel; the two
summary.csv files of every pair are identical in every column but `wall_time_s` and `run_id`.

| run | serial (s) | --workers {r['workers']} (s) |
|---:|---:|---:|
{rows}

- median: serial **{r['median_s']['serial']:.1f} s**, `--workers {r['workers']}` **{r['median_s']['parallel']:.1f} s**
- ratio of the medians: **{r['ratio_of_medians']:.2f}** (target ≤ 0.65); ratio of the mins: {r['ratio_of_mins']:.2f}
{_projection_text(r)}{_autogroup_text(r)}"""


def _autogroup_text(r: dict) -> str:
    if not r.get("autogroup"):
        return ""
    return """
Linux autogroup scheduling is on here: when the machine is saturated, all processes of one session share
one session's CPU share, so extra worker processes cannot shorten the wall time of a run on a busy
machine; the wall-time ratio above then measures the load, and the CPU-time projection is the figure to
read.
"""


def _projection_text(r: dict) -> str:
    p = r.get("idle_projection")
    if not p:
        return ""
    split = "; ".join(f"main {c['main']:.1f}, server {c['server']:.1f}, workers "
                      + ", ".join(f"{w:.1f}" for w in c["workers"]) for c in r["cpu_s"]["parallel"])
    return f"""
CPU time (user + system, s, from psutil; less sensitive to the load than wall time, though shared
caches still inflate it on a busy machine): serial
{', '.join(f"{c['main']:.1f}" for c in r['cpu_s']['serial'])}; `--workers {r['workers']}` per run: {split}.
On an idle machine the serial run would take its CPU time and the parallel run the main process + the
fork server's imports (if any) + the busiest worker: median **{p['serial_cpu_s']:.1f} s** against
**{p['parallel_critical_path_cpu_s']:.1f} s**, a projected ratio of **{p['ratio']:.2f}** (a model, not a
measurement).
"""


if __name__ == "__main__":
    main()
