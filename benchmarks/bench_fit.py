"""Fit speed: one model evaluation against the bare history, least squares warm, a one-file CLI fit,
an MCMC fit, and start-up; optionally the same against an older revision, side by side.

    python benchmarks/bench_fit.py [--repeat 7] [--before REV]

Every figure is a median of ``--repeat`` runs (MCMC: of ``max(3, repeat // 2)``).  With ``--before``,
REV is checked out in a temporary git worktree and each measurement alternates between the two trees
(after, before, after, ...), so that a drift of the machine's speed hits both alike; the in-process
measurements run in a fresh interpreter per tree (``PYTHONPATH`` = that tree).  Writes
``benchmarks/results/fit_speed.md`` and ``fit_speed.json``.

Measurements (the sample curve ``sample_data/fea_displacement_no-slip``: 200 rows, displacement
control; the 300-row curve is the same scene made by ``adhfit simulate --scene``):

* ``eval``: ``CurveModel.predict`` at a new W_ad each call (so that no cached history is reused),
  against ``adhfit.loading.history`` with the same groups (the bare history): medians and their ratio;
* ``lsq``: ``fit_curve`` on the 300-row curve, both slip conditions, warm (after one fit in the same
  process), with and without profile intervals; and the model evaluations of one such fit without
  profiles (a count, the same on a busy machine as on a quiet one);
* ``cli``: ``python -m adhfit.cli fit CURVE --scene SCENE -o OUT --quiet`` wall time (a warm numba cache:
  one unmeasured run first), and ``--method mcmc``;
* ``startup``: ``python -c "import adhfit"`` and ``python -m adhfit.cli --help`` wall time.
"""
from __future__ import annotations

import argparse
import json
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
SAMPLE = ROOT / "sample_data" / "fea_displacement_no-slip"
OUT = ROOT / "benchmarks" / "results"

#: run inside each tree: model evaluation against the bare history, and warm least squares
_INPROCESS = r'''
import json, statistics, sys, time
from adhfit.data import read_curve
from adhfit.scene import load_scene
from adhfit.fitting.model import CurveModel
from adhfit.fitting.api import fit as fit_curve
from adhfit.loading import history
sample, c300, repeat = sys.argv[1], sys.argv[2], int(sys.argv[3])
scene = load_scene(sample + "/scene.toml")
curve = read_curve(sample + "/curve.csv", scene.control)
out = {}
for slip in ("no-slip", "frictionless"):
    m = CurveModel(curve, scene, slip, points=150)
    kw = m.groups(0.4, 2.0, 0.0)
    def med(fn, n=400):
        fn()
        ts = []
        for k in range(n):
            t = time.perf_counter(); fn(k); ts.append(time.perf_counter() - t)
        return statistics.median(ts)
    pred = med(lambda k=0: m.predict(0.4 * (1 + 1e-9 * (k + 1)), 2.0, 0.0, 0.0))
    bare = med(lambda k=0: history(**kw, points=150))
    out[f"eval_{slip}_ms"] = pred * 1e3
    out[f"history_{slip}_ms"] = bare * 1e3
curve300 = read_curve(c300, scene.control)
fit_curve(curve300, scene, profile=False)
for profile in (True, False):
    ts = []
    for _ in range(repeat):
        t = time.perf_counter(); fit_curve(curve300, scene, profile=profile); ts.append(time.perf_counter() - t)
    out[f"lsq_300_{'profile' if profile else 'no_profile'}_s"] = statistics.median(ts)
# the work itself, whatever the machine's load: model evaluations of one warm fit without profiles
calls = []
real = CurveModel.predict
def counted(self, *a, **kw):
    calls.append(1)
    return real(self, *a, **kw)
CurveModel.predict = counted
fit_curve(curve300, scene, profile=False)
CurveModel.predict = real
out["lsq_300_no_profile_evals"] = len(calls)
print(json.dumps(out))
'''


def _env(tree: Path) -> dict:
    return os.environ | {"PYTHONPATH": str(tree), "MPLBACKEND": "Agg"}


def _wall(cmd: list[str], tree: Path) -> float:
    """Wall seconds of ``cmd`` run from ``tree`` (``python -m`` puts the working folder first on
    sys.path: run elsewhere, it would import that folder's adhfit, whatever PYTHONPATH says)."""
    t = time.perf_counter()
    run = subprocess.run(cmd, env=_env(tree), cwd=tree, capture_output=True, text=True)
    wall = time.perf_counter() - t
    if run.returncode != 0:
        raise RuntimeError(f"{' '.join(cmd)} failed in {tree}: {run.stderr[-500:]}")
    return wall


def _commands(work: Path) -> dict[str, list[str]]:
    py = sys.executable
    fit = [py, "-m", "adhfit.cli", "fit", str(SAMPLE / "curve.csv"), "--scene", str(SAMPLE / "scene.toml"),
           "--quiet"]
    return {"cli_fit_s": fit + ["-o", str(work / "lsq")],
            "cli_mcmc_s": fit + ["-o", str(work / "mcmc"), "--method", "mcmc", "--seed", "1"],
            "import_adhfit_s": [py, "-c", "import adhfit"],
            "cli_help_s": [py, "-m", "adhfit.cli", "--help"]}


def _curve300(work: Path) -> Path:
    path = work / "curve300.csv"
    subprocess.run([sys.executable, "-m", "adhfit.cli", "simulate", "--scene", str(SAMPLE / "scene.toml"),
                    "--slip", "no-slip", "--mu-h", "2 N/m", "--work-of-adhesion", "0.4 J/m^2",
                    "--a-max", "0.3", "--noise", "0.01", "--seed", "7", "--points", "300", "-o", str(path)],
                   env=_env(ROOT), cwd=ROOT, check=True, capture_output=True)
    return path


def measure(trees: dict[str, Path], repeat: int, work: Path) -> dict[str, dict[str, float]]:
    """Every measurement of every tree (alternating trees within each measurement)."""
    c300 = _curve300(work)
    res: dict[str, dict[str, list[float]]] = {name: {} for name in trees}
    for name, tree in trees.items():  # warm each tree's numba cache (not timed)
        _wall(_commands(work / name)["cli_fit_s"], tree)
    for _ in range(max(1, repeat // 3)):
        for name, tree in trees.items():
            run = subprocess.run([sys.executable, "-c", _INPROCESS, str(SAMPLE), str(c300), "3"], env=_env(tree),
                                 capture_output=True, text=True, check=True, cwd=work)
            for k, v in json.loads(run.stdout.strip().splitlines()[-1]).items():
                res[name].setdefault(k, []).append(v)
    for key in ("cli_fit_s", "import_adhfit_s", "cli_help_s", "cli_mcmc_s"):
        n = repeat if key != "cli_mcmc_s" else max(3, repeat // 2)
        for _ in range(n):
            for name, tree in trees.items():
                res[name].setdefault(key, []).append(_wall(_commands(work / name)[key], tree))
    return {name: {k: statistics.median(v) for k, v in d.items()} for name, d in res.items()}


def _machine() -> dict:
    def git(*a):
        return subprocess.run(["git", *a], cwd=ROOT, capture_output=True, text=True).stdout.strip()
    dirty = bool(git("status", "--porcelain", "adhfit"))
    return {"commit": git("rev-parse", "--short", "HEAD") + ("+dirty" if dirty else ""),
            "python": platform.python_version(), "nproc": os.cpu_count(),
            "load_start": os.getloadavg()[0]}


ROWS = [("eval_no-slip_ms", "model evaluation, no-slip (ms)"), ("history_no-slip_ms", "bare history, no-slip (ms)"),
        ("eval_frictionless_ms", "model evaluation, frictionless (ms)"),
        ("history_frictionless_ms", "bare history, frictionless (ms)"),
        ("lsq_300_profile_s", "least squares, 300 rows, both slips, profiles (s)"),
        ("lsq_300_no_profile_s", "least squares, 300 rows, both slips, no profiles (s)"),
        ("lsq_300_no_profile_evals", "least squares, 300 rows, both slips, no profiles (model evaluations)"),
        ("cli_fit_s", "one-file CLI fit, wall (s)"), ("cli_mcmc_s", "one-file CLI MCMC fit, wall (s)"),
        ("import_adhfit_s", "python -c 'import adhfit', wall (s)"), ("cli_help_s", "adhfit --help, wall (s)")]


def report(res: dict, argv: list[str], machine: dict) -> str:
    names = list(res)
    lines = ["# Fit speed", "",
             f"Command: `python benchmarks/bench_fit.py {' '.join(argv)}` at {machine['commit']}; python "
             f"{machine['python']}, nproc {machine['nproc']}, load average at start {machine['load_start']:.2f}, "
             f"at end {machine['load_end']:.2f}. Medians; the trees alternate run by run.", "",
             "| measurement | " + " | ".join(names) + (" | before / after |" if len(names) > 1 else " |"),
             "|---|" + "---:|" * (len(names) + (len(names) > 1))]
    for key, label in ROWS:
        vals = [res[n].get(key) for n in names]
        cells = [("—" if v is None else f"{v:.0f}" if key.endswith("_evals") else f"{v:.3g}") for v in vals]
        ratio = [f"{vals[1] / vals[0]:.2g}×"] if len(names) > 1 and vals[0] and vals[1] else ([] if len(names) == 1 else ["—"])
        lines.append(f"| {label} | " + " | ".join(cells + ratio) + " |")
    a = res[names[0]]
    lines += ["", f"Model evaluation over the bare history ({names[0]}): no-slip "
              f"{a['eval_no-slip_ms'] / a['history_no-slip_ms']:.2f}×, frictionless "
              f"{a['eval_frictionless_ms'] / a['history_frictionless_ms']:.2f}× (target ≤ 1.5×)."]
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--repeat", type=int, default=7)
    ap.add_argument("--before", default=None, metavar="REV", help="an older revision to time side by side")
    args = ap.parse_args(argv)
    machine = _machine()
    with tempfile.TemporaryDirectory(prefix="adhfit-bench-") as tmp:
        work = Path(tmp)
        trees = {"after": ROOT}
        if args.before:
            before = work / "before-tree"
            subprocess.run(["git", "worktree", "add", "--detach", str(before), args.before], cwd=ROOT, check=True,
                           capture_output=True)
            trees["before"] = before
        try:
            res = measure(trees, args.repeat, work)
        finally:
            if args.before:
                subprocess.run(["git", "worktree", "remove", "--force", str(work / "before-tree")], cwd=ROOT,
                               capture_output=True)
    machine["load_end"] = os.getloadavg()[0]
    OUT.mkdir(parents=True, exist_ok=True)
    (OUT / "fit_speed.json").write_text(json.dumps({"machine": machine, "argv": sys.argv[1:], "results": res},
                                                   indent=1))
    text = report(res, sys.argv[1:] if argv is None else argv, machine)
    (OUT / "fit_speed.md").write_text(text)
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
