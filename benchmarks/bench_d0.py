"""Cost and accuracy of d0(p) under pressure control (``Control._d0_curve``), this tree against a git revision.

A pressure-control history reports delta = d0(p) - d per row, d0(p) the apex deflection of free
inflation at the row's pressure, interpolated from free inflation at a few apex stretches and checked
(``adhfit.exact.control.Control._d0_curve``). For the base case (lambda0 = 1.5, d = 0.2, w = 0.2,
rs = 0.5, a_max = 0.25, 200 points, both slips) it times, in fresh subprocesses alternating between
the two engines:

- ``_d0_curve`` at the history's pressures (each call on a fresh copy of the prepared control;
  perf_counter), and
- the whole history (process_time), median and least of ``--repeat`` per round.

and, once per engine, the accuracy over 50 histories (lambda0 = 1.1, 1.2, 1.5, 2, 3; (d, w) = (0.2,
0.2), (-0.05, 0.2), (0.2, 1), (-0.05, 1), (0.05, 0.5), ranges through p = 0 and not; both slips): the
largest |d0 - direct| over all rows (direct: ``free_inflation`` at each pressure by the bracketing
root search) and the number of histories where the curve was refused (one solve per row instead).

Usage::

    python benchmarks/bench_d0.py --baseline REV [--rounds 3] [--repeat 10]

Writes ``benchmarks/results/d0.md`` and ``d0.json``. The machine is shared (2 cores): medians and
least values, load averages recorded.
"""
from __future__ import annotations

import argparse
import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

_WORKER = r"""
import copy, json, math, sys, time
import numpy as np
from adhfit.exact.control import prepare
from adhfit.exact.history import exact_history
from adhfit.exact.inflation import free_inflation
from adhfit.exact.state import DEFAULT_N
mode, repeat = sys.argv[1], int(sys.argv[2])

def hist(lam, d, w, slip):
    return exact_history("pressure", slip, d=d, w=w, rs=0.5, lambda0=lam, a_max=0.25, points=200)

def ctrl(lam, d, w, slip):
    return prepare("pressure", slip, None, d, w, 0.5, lam, 0.25, None, None, 200, DEFAULT_N)

out = {}
if mode == "time":
    for slip in ("frictionless", "no-slip"):
        p = np.array([s.p for s in hist(1.5, 0.2, 0.2, slip).states])
        c0 = ctrl(1.5, 0.2, 0.2, slip)
        cs = [copy.deepcopy(c0) for _ in range(repeat + 1)]
        cs[0]._d0_curve(p)
        d0 = []
        for c in cs[1:]:
            t = time.perf_counter()
            c._d0_curve(p)
            d0.append(time.perf_counter() - t)
        cpu = []
        for _ in range(repeat):
            t = time.process_time()
            hist(1.5, 0.2, 0.2, slip)
            cpu.append(time.process_time() - t)
        out[slip] = {"d0": d0, "hist_cpu": cpu}
else:
    worst, refused = 0.0, 0
    for lam in (1.1, 1.2, 1.5, 2.0, 3.0):
        for d, w in ((0.2, 0.2), (-0.05, 0.2), (0.2, 1.0), (-0.05, 1.0), (0.05, 0.5)):
            for slip in ("frictionless", "no-slip"):
                p = np.array([s.p for s in hist(lam, d, w, slip).states])
                d0 = ctrl(lam, d, w, slip)._d0_curve(p)
                if d0 is None:
                    refused += 1
                    continue
                direct = np.array([free_inflation(q, lam).d for q in p])
                worst = max(worst, float(np.max(np.abs(d0 - direct))))
    out = {"worst": worst, "refused": refused, "histories": 50}
print(json.dumps(out))
"""


def _worker(tree: Path, mode: str, repeat: int) -> dict:
    env = {**os.environ, "PYTHONPATH": str(tree)}
    res = subprocess.run([sys.executable, "-c", _WORKER, mode, str(repeat)], env=env, capture_output=True,
                         text=True, check=True, cwd=tree)
    return json.loads(res.stdout.strip().splitlines()[-1])


def _stats(xs: list) -> dict:
    return {"median_ms": 1e3 * statistics.median(xs), "least_ms": 1e3 * min(xs), "n": len(xs)}


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--baseline", required=True, help="git revision to time against (same run)")
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--repeat", type=int, default=10)
    args = ap.parse_args()
    load0 = os.getloadavg()
    tmp = Path(tempfile.mkdtemp(prefix="bench_d0_"))
    arch = subprocess.run(["git", "archive", args.baseline, "adhfit"], cwd=ROOT, capture_output=True,
                          check=True).stdout
    subprocess.run(["tar", "xf", "-", "-C", str(tmp)], input=arch, check=True)
    trees = {"old": tmp, "new": ROOT}
    acc = {k: _worker(t, "accuracy", 0) for k, t in trees.items()}
    raw: dict = {k: {} for k in trees}
    for _ in range(args.rounds):
        for k, t in trees.items():
            for slip, v in _worker(t, "time", args.repeat).items():
                for m, xs in v.items():
                    raw[k].setdefault(f"{slip}/{m}", []).extend(xs)
    shutil.rmtree(tmp, ignore_errors=True)
    rows = []
    for key in raw["old"]:
        old, new = _stats(raw["old"][key]), _stats(raw["new"][key])
        rows.append({"what": key, "old": old, "new": new, "ratio": old["median_ms"] / new["median_ms"]})
    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT, capture_output=True,
                            text=True).stdout.strip()
    cmd = f"python benchmarks/bench_d0.py --baseline {args.baseline} --rounds {args.rounds} --repeat {args.repeat}"
    meta = {"command": cmd, "commit": commit, "load_start": load0, "load_end": os.getloadavg()}
    out = ROOT / "benchmarks" / "results"
    (out / "d0.json").write_text(json.dumps({"meta": meta, "rows": rows, "accuracy": acc}, indent=1))
    lines = ["# d0(p) of a pressure-control history: cost and accuracy", "",
             f"Command: `{cmd}` at {commit} (old: {args.baseline}); load average at start {load0[0]:.2f}, "
             f"at end {meta['load_end'][0]:.2f}.", "",
             "Base case lambda0 = 1.5, d = 0.2, w = 0.2, rs = 0.5, a_max = 0.25, 200 points. `d0`: wall time "
             "of `Control._d0_curve` at the history's pressures; `hist_cpu`: CPU time of the whole history. "
             f"Engines alternate in fresh subprocesses ({args.rounds} rounds x {args.repeat}).", "",
             "| what | old median ms | old least ms | new median ms | new least ms | old/new (median) |",
             "|---|---:|---:|---:|---:|---:|"]
    for r in rows:
        lines.append(f"| {r['what']} | {r['old']['median_ms']:.3f} | {r['old']['least_ms']:.3f} | "
                     f"{r['new']['median_ms']:.3f} | {r['new']['least_ms']:.3f} | {r['ratio']:.2f} |")
    lines += ["", "Accuracy over 50 pressure-control histories (lambda0 = 1.1-3, w up to 1, ranges of p "
              "through 0 and not): largest |d0 - free_inflation| over all rows where the curve was "
              "accepted, and histories where it was refused (one solve per row instead).", "",
              "| engine | max abs d0 error | refused |", "|---|---:|---:|"]
    for k in ("old", "new"):
        lines.append(f"| {k} | {acc[k]['worst']:.1e} | {acc[k]['refused']} / {acc[k]['histories']} |")
    (out / "d0.md").write_text("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
