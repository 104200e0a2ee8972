"""The first ``adhfit fit`` after ``pip install`` (issue 21): the README's sample fit, compile included.

Two ways to get a first run::

    python benchmarks/bench_first_run.py --venv [--repeat 1]        # a fresh virtual environment
    python benchmarks/bench_first_run.py --clear-cache [--repeat 3] # this environment, caches cleared

``--venv``: ``python -m venv`` in a temporary folder, ``pip install --quiet .`` of this checkout (pip's
own wheel cache makes the download part short; the install is timed apart and is not part of the
first run), then the README's command, twice, from a temporary folder holding the sample::

    adhfit fit sample_data/fea_displacement_no-slip/curve.csv --scene sample_data/fea_displacement_no-slip/scene.toml -o out

``--clear-cache``: the same command with this interpreter (``python -m adhfit.cli``) after deleting the
numba cache of this checkout (``adhfit/core/__pycache__`` and ``adhfit/exact/__pycache__``: ``*.nbi``,
``*.nbc`` and the ``engine-*.ready`` markers).  That is all the state a first run lacks that the
compile depends on: numba keeps nothing else between processes (the kernels' cache key is the hash of
their folder, :mod:`adhfit.core.jit`), and a fresh venv also has its ``.pyc`` files written by pip and
its files in the page cache, as here.  Not cleared in either mode: matplotlib's font cache (in the
user's home, shared by every environment; a machine that never ran matplotlib spends a few more
seconds once).

Each run: wall time, and the CPU time (user + system) of the command and every process it started
(the second process that compiles the exact membrane's kernels included), and the load average, on a
shared machine.  Standard error of the first run is kept (the notice); with ``--tty`` the first run has
a pseudo-terminal, so the running clock (seconds, part, kernel) is recorded as a user sees it.

Writes ``benchmarks/results/first_run.md`` and ``benchmarks/results/first_run.json``.
"""
from __future__ import annotations

import argparse
import json
import os
import platform
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "benchmarks" / "results"
SAMPLE = "sample_data/fea_displacement_no-slip"
FIT = ["fit", f"{SAMPLE}/curve.csv", "--scene", f"{SAMPLE}/scene.toml", "-o", "out"]


def _revision() -> str:
    def git(*args: str) -> str:
        return subprocess.run(["git", *args], cwd=ROOT, capture_output=True, text=True).stdout.strip()
    return git("rev-parse", "--short", "HEAD") + ("+dirty" if git("status", "--porcelain", "adhfit") else "")


def clear_numba_cache(package: Path) -> int:
    """Delete the numba cache and the engine markers of an adhfit package folder; returns files removed."""
    n = 0
    for folder in ("core", "exact"):
        cache = package / folder / "__pycache__"
        for pattern in ("*.nbi", "*.nbc", "engine-*.ready"):
            for f in cache.glob(pattern):
                f.unlink()
                n += 1
    return n


def _timed(cmd: list[str], cwd: Path, env: dict, tty: bool = False) -> dict:
    """Run ``cmd``; wall time, CPU time of it and its descendants (waited-for children; and per process
    from psutil, where installed: the command itself, the rest), its standard error."""
    import threading  # noqa: PLC0415
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    load = os.getloadavg()
    out = bytearray()
    t0 = time.perf_counter()
    if tty:
        import pty  # noqa: PLC0415
        master, slave = pty.openpty()
        proc = subprocess.Popen(cmd, cwd=cwd, env=env, stdin=slave, stdout=slave, stderr=slave)
        os.close(slave)

        def drain(fd=master):
            while True:
                try:
                    data = os.read(fd, 4096)
                except OSError:
                    return
                if not data:
                    return
                out.extend(data)
    else:
        proc = subprocess.Popen(cmd, cwd=cwd, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)

        def drain():
            out.extend(proc.stderr.read())
    reader = threading.Thread(target=drain, daemon=True)
    reader.start()
    seen: dict = {}
    while proc.poll() is None:
        _cpu_tree(proc.pid, seen)
        time.sleep(0.2)
    wall = time.perf_counter() - t0
    reader.join(timeout=5)
    if tty:
        os.close(master)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    err = out.decode(errors="replace")
    if proc.returncode != 0:
        raise SystemExit(f"{' '.join(cmd)} ended with {proc.returncode}:\n{err[-3000:]}")
    main = seen.pop(proc.pid, None)
    return {"wall_s": wall, "cpu_s": cpu, "main_cpu_s": main, "other_cpu_s": sorted(seen.values(), reverse=True),
            "load_1min": load[0], "stderr": err[-4000:]}


def _cpu_tree(pid: int, seen: dict) -> None:
    """The CPU time (user + system, s) of ``pid`` and of every descendant, by pid (last seen)."""
    try:
        import psutil  # noqa: PLC0415 - optional: only for the split between processes
        root = psutil.Process(pid)
        for p in [root, *root.children(recursive=True)]:
            try:
                t = p.cpu_times()
                seen[p.pid] = t.user + t.system
            except psutil.Error:
                pass
    except (ImportError, Exception):  # noqa: BLE001 - the process ended between two looks
        pass


def _workdir(tmp: Path) -> Path:
    work = tmp / "work"
    (work / SAMPLE).mkdir(parents=True)
    for name in ("curve.csv", "scene.toml"):
        shutil.copy(ROOT / SAMPLE / name, work / SAMPLE / name)
    return work


def _pair(adhfit: list[str], work: Path, env: dict, tty: bool) -> dict:
    shutil.rmtree(work / "out", ignore_errors=True)
    first = _timed([*adhfit, *FIT], work, env, tty)
    shutil.rmtree(work / "out", ignore_errors=True)
    second = _timed([*adhfit, *FIT], work, env)
    report = json.loads((work / "out" / "report.json").read_text())
    print(f"first {first['wall_s']:.1f} s wall / {first['cpu_s']:.1f} s CPU (the command {first['main_cpu_s']}, "
          f"the others {first['other_cpu_s']}; load {first['load_1min']:.1f}); "
          f"second {second['wall_s']:.1f} s / {second['cpu_s']:.1f} s CPU", flush=True)
    return {"first": first, "second": second,
            "work_of_adhesion": report["parameters"]["work_of_adhesion"]["value"]}


def run_venv(repeat: int, tty: bool) -> dict:
    runs, installs = [], []
    for _ in range(repeat):
        with tempfile.TemporaryDirectory(prefix="adhfit-first-run-") as tmp:
            tmp = Path(tmp)
            venv = tmp / "venv"
            t0 = time.perf_counter()
            subprocess.run([sys.executable, "-m", "venv", str(venv)], check=True)
            pip = subprocess.run([str(venv / "bin" / "pip"), "install", "--quiet", str(ROOT)], capture_output=True,
                                 text=True)
            if pip.returncode != 0:
                raise SystemExit(f"pip install failed:\n{pip.stderr[-3000:]}")
            installs.append(time.perf_counter() - t0)
            env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "VIRTUAL_ENV")}
            env["PATH"] = f"{venv / 'bin'}{os.pathsep}{env.get('PATH', '')}"
            site = subprocess.run([str(venv / "bin" / "python"), "-c", "import adhfit, pathlib; "
                                   "print(pathlib.Path(adhfit.__file__).parent)"], env=env, capture_output=True,
                                  text=True, check=True, cwd=tmp).stdout.strip()
            if not site.startswith(str(venv)):
                raise SystemExit(f"the fresh venv imports adhfit from {site}, not from itself")
            runs.append(_pair([str(venv / "bin" / "adhfit")], _workdir(tmp), env, tty))
    return {"mode": "venv", "install_s": installs, "runs": runs}


def run_clear(repeat: int, tty: bool) -> dict:
    runs = []
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    with tempfile.TemporaryDirectory(prefix="adhfit-first-run-") as tmp:
        work = _workdir(Path(tmp))
        for _ in range(repeat):
            removed = clear_numba_cache(ROOT / "adhfit")
            run = _pair([sys.executable, "-m", "adhfit.cli"], work, env, tty)
            run["cache_files_removed"] = removed
            runs.append(run)
    return {"mode": "clear-cache", "runs": runs}


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    mode = ap.add_mutually_exclusive_group(required=True)
    mode.add_argument("--venv", action="store_true", help="a fresh virtual environment per repeat")
    mode.add_argument("--clear-cache", action="store_true", help="this environment, numba cache deleted")
    ap.add_argument("--repeat", type=int, default=1)
    ap.add_argument("--tty", action="store_true", help="the first run on a pseudo-terminal (the running clock)")
    args = ap.parse_args(argv)
    command = " ".join(["python benchmarks/bench_first_run.py", *(sys.argv[1:] if argv is None else argv)])
    result = run_venv(args.repeat, args.tty) if args.venv else run_clear(args.repeat, args.tty)
    firsts = [r["first"] for r in result["runs"]]
    seconds = [r["second"] for r in result["runs"]]
    result.update({"command": command, "fit": "adhfit " + " ".join(FIT),
                   "median_first_wall_s": statistics.median(r["wall_s"] for r in firsts),
                   "median_first_cpu_s": statistics.median(r["cpu_s"] for r in firsts),
                   "median_second_wall_s": statistics.median(r["wall_s"] for r in seconds),
                   "median_second_cpu_s": statistics.median(r["cpu_s"] for r in seconds),
                   "nproc": os.cpu_count(), "python": platform.python_version(), "adhfit_revision": _revision()})
    RESULTS.mkdir(parents=True, exist_ok=True)
    tag = "first_run" if args.venv else "first_run_clear_cache"
    (RESULTS / f"{tag}.json").write_text(json.dumps(result, indent=2) + "\n")
    print(json.dumps({k: v for k, v in result.items() if k != "runs"}, indent=2))


if __name__ == "__main__":
    main()
