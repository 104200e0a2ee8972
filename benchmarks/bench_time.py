"""Run time of ``adhfit.simulate`` and of the plain scipy baseline (issue 2, item 7a).

(a) Median (and min) wall time per history of ``adhfit.simulate`` for the 8 combinations
    control x slip x substrate (the paper's base cases p = 0.6 / d = 0, w = 0.2, rs = 0.5,
    a_max = 0.25, and a flat-substrate variant rs = inf; pressure control on the flat needs d > 0,
    so it uses d = 0.2) at points = 50, 200, 1000.
(b) The headline: the 200-row displacement-control frictionless history, engine against
    ``benchmarks/baseline_quad.py`` (scipy quad + brentq) on exactly the same rows (the engine frame's
    locators, fed to the baseline), with the agreement between the two on those rows; plus the
    engine's no-slip and pressure-control times relative to it and the baseline on the same rows
    for the other curved-substrate combinations.

Usage::

    python benchmarks/bench_time.py [--repeat 15] [--quick]

Writes ``benchmarks/results/time.md`` and ``benchmarks/results/time.json``.  Timing lives here only,
never in the tests.  The engine is timed twice: ``adhfit.loading.history`` (the dimensionless history
as numpy columns, with what it always does: locating the onset, the force minimum and the turning
point to 1e-8) and ``adhfit.simulate`` (the same plus the pandas DataFrame); the baseline only
computes the rows.  The machine is shared: every time is the median (and min) of ``--repeat`` calls,
and the load average is recorded at the start and the end.
"""
from __future__ import annotations

import argparse
import gc
import json
import math
import os
import platform
import statistics
import subprocess
import sys
import time
from pathlib import Path
from typing import Callable

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))

import adhfit  # noqa: E402
from adhfit.loading import history  # noqa: E402
import baseline_quad  # noqa: E402

RESULTS = ROOT / "benchmarks" / "results"
POINTS = (50, 200, 1000)
from cases import CASES, HEADLINE  # noqa: E402 - shared with the other benchmark


def engine_revision() -> str:
    """Commit of the working tree, with '+dirty' when adhfit/ has uncommitted changes."""
    def git(*args: str) -> str:
        try:
            return subprocess.run(["git", *args], cwd=ROOT, capture_output=True, text=True,
                                  timeout=10).stdout.strip()
        except (OSError, subprocess.SubprocessError):
            return ""
    if os.environ.get("ADHFIT_BENCH_REVISION"):   # set when running from an exported snapshot
        return os.environ["ADHFIT_BENCH_REVISION"]
    head = git("rev-parse", "--short", "HEAD") or "unknown"
    return head + ("+dirty" if git("status", "--porcelain", "--", "adhfit") else "")


def machine_info() -> dict:
    import pandas
    import scipy
    return {"python": platform.python_version(), "numpy": np.__version__, "scipy": scipy.__version__,
            "pandas": pandas.__version__, "adhfit": f"{adhfit.__version__} ({engine_revision()})",
            "nproc": os.cpu_count(), "platform": platform.platform(),
            "processor": platform.processor() or platform.machine(),
            "load average (1, 5, 15 min) at start": ", ".join(f"{x:.2f}" for x in os.getloadavg())}


def timed(fun: Callable[[], object], repeat: int) -> dict:
    """Median, min and all wall times (s) of ``repeat`` back-to-back calls after one warm-up call.

    The garbage collector runs once before the calls and is off during them: collecting before
    every call (as this used to) walks the whole heap between calls and times each one with cold
    caches, which inflated a 0.2 ms history by ~0.1 ms and hardly touched a 30 ms baseline.
    """
    fun()
    times = []
    gc.collect()
    gc.disable()
    try:
        for _ in range(repeat):
            t0 = time.perf_counter()
            fun()
            times.append(time.perf_counter() - t0)
    finally:
        gc.enable()
    return {"median_s": statistics.median(times), "min_s": min(times), "runs_s": times}


def engine_table(repeat: int, points: tuple[int, ...]) -> list[dict]:
    rows = []
    for label, control, slip, kw in CASES:
        for n in points:
            try:
                res = adhfit.simulate(control, slip, points=n, **kw)
            except Exception as e:  # noqa: BLE001 - a failing case is reported, not fatal
                rows.append({"case": label, "points": n, "rows": 0, "error": f"{type(e).__name__}: {e}",
                             "median_s": math.nan, "min_s": math.nan, "runs_s": []})
                print(f"  engine {label:40s} points={n:5d}: FAILED {type(e).__name__}", flush=True)
                continue
            t = timed(lambda: adhfit.simulate(control, slip, points=n, **kw), repeat)
            rows.append({"case": label, "points": n, "rows": len(res.frame), **t})
            print(f"  engine {label:40s} points={n:5d}: median {1e3 * t['median_s']:8.2f} ms", flush=True)
    return rows


def locators(frame) -> dict[str, np.ndarray]:
    """Per-stage locators of an engine frame: a (making contact, delamination), alpha (pinning)."""
    st = frame["stage"].to_numpy()
    return {"making_contact": frame["a"].to_numpy()[st == "making_contact"],
            "pinning": frame["alpha"].to_numpy()[st == "pinning"],
            "delamination": frame["a"].to_numpy()[st == "delamination"]}


def same_rows(label: str, control: str, slip: str, kw: dict, repeat: int, quad_tol: float,
              root_tol: float) -> dict:
    """Engine and baseline on the engine's 200-point rows: times and max differences."""
    res = adhfit.simulate(control, slip, points=200, **kw)
    loc = locators(res.frame)
    kw_b = {k: v for k, v in kw.items()}

    def base() -> dict:
        return baseline_quad.history(control, slip, locators=loc, quad_tol=quad_tol, root_tol=root_tol,
                                     **kw_b)

    b = base()
    fr = res.frame
    diff = {k: float(np.nanmax(np.abs(b[k] - fr[k].to_numpy(dtype=float)))) for k in ("f", "delta", "p", "a")}
    t_hist = timed(lambda: history(control, slip, points=200, **kw), repeat)
    t_eng = timed(lambda: adhfit.simulate(control, slip, points=200, **kw), repeat)
    t_base = timed(base, repeat)
    out = {"case": label, "rows": len(fr), "quad_tol": quad_tol, "root_tol": root_tol,
           "history": t_hist, "engine": t_eng, "baseline": t_base,
           "ratio_history_median": t_base["median_s"] / t_hist["median_s"],
           "ratio_history_min": t_base["min_s"] / t_hist["min_s"],
           "ratio_median": t_base["median_s"] / t_eng["median_s"],
           "ratio_min": t_base["min_s"] / t_eng["min_s"],
           "max_abs_diff": diff}
    print(f"  same rows {label:40s}: history {1e3 * t_hist['median_s']:.3f} ms, simulate "
          f"{1e3 * t_eng['median_s']:.3f} ms, baseline {1e3 * t_base['median_s']:.2f} ms, ratio "
          f"{out['ratio_history_median']:.0f} (history) {out['ratio_median']:.0f} (simulate), "
          f"max|df| {diff['f']:.1e}", flush=True)
    return out


def write_markdown(rep: dict, path: Path) -> None:
    m = rep["machine"]
    lines = ["# Run time per history", "",
             f"Command: `{rep['command']}`  ",
             "Machine: " + ", ".join(f"{k} {v}" for k, v in m.items()) + "  ",
             f"Each time: median (min) of {rep['repeat']} back-to-back calls after one warm-up call, garbage "
             "collector run once before them and off during them. Base cases: p = 0.6 (displacement) / d = 0 (pressure; d = 0.2 on the flat, "
             "where d = 0 is outside the domain), w = 0.2, a_max = 0.25, rs = 0.5 or inf.", "",
             "## Headline: 200-row displacement-control frictionless history, same rows", ""]
    h = rep["headline"]
    lines += [f"- engine `adhfit.loading.history`: **{1e3 * h['history']['median_s']:.3f} ms** median "
              f"(min {1e3 * h['history']['min_s']:.3f} ms), {h['rows']} rows, all summary extrema",
              f"- engine `adhfit.simulate` (the same plus the pandas DataFrame): "
              f"**{1e3 * h['engine']['median_s']:.3f} ms** median (min {1e3 * h['engine']['min_s']:.3f} ms); "
              f"the DataFrame adds {1e3 * (h['engine']['median_s'] - h['history']['median_s']):.3f} ms",
              f"- baseline (scipy quad + brentq, quad_tol {h['quad_tol']:g}, root_tol {h['root_tol']:g}): "
              f"**{1e3 * h['baseline']['median_s']:.2f} ms** median (min {1e3 * h['baseline']['min_s']:.2f} ms)",
              f"- ratio baseline / `history`: **{h['ratio_history_median']:.0f}x** of the medians, "
              f"{h['ratio_history_min']:.0f}x of the mins; baseline / `simulate`: "
              f"{h['ratio_median']:.0f}x of the medians, {h['ratio_min']:.0f}x of the mins (the min is the "
              f"less load-sensitive one on a shared machine)",
              f"- agreement on those rows: max |Δf| = {h['max_abs_diff']['f']:.1e}, "
              f"max |Δδ| = {h['max_abs_diff']['delta']:.1e}", ""]
    lines += ["The engine's time also covers locating the onset, f_min and the turning point to 1e-8 "
              "and building the DataFrame; the baseline computes the rows only.", "",
              "### Other combinations on the engine's 200-point rows", "",
              "| case | rows | history median (min) ms | history / headline history | simulate median ms "
              "| baseline median ms | baseline / history (medians) | baseline / history (mins) "
              "| max abs Δf | max abs Δδ |",
              "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    th = h["history"]["median_s"]
    for s in rep["same_rows"]:
        lines.append(f"| {s['case']} | {s['rows']} | {1e3 * s['history']['median_s']:.3f} "
                     f"({1e3 * s['history']['min_s']:.3f}) | {s['history']['median_s'] / th:.2f} | "
                     f"{1e3 * s['engine']['median_s']:.3f} | {1e3 * s['baseline']['median_s']:.2f} | "
                     f"{s['ratio_history_median']:.0f} | {s['ratio_history_min']:.0f} | "
                     f"{s['max_abs_diff']['f']:.1e} | {s['max_abs_diff']['delta']:.1e} |")
    t0 = h["engine"]["median_s"]
    lines += ["", "## Engine: `adhfit.simulate` per history", "",
              "| case | points | rows | median (ms) | min (ms) | relative to headline (200 pts) |",
              "|---|---:|---:|---:|---:|---:|"]
    for r in rep["engine"]:
        if "error" in r:
            lines.append(f"| {r['case']} | {r['points']} | — | failed | failed | — |")
            continue
        lines.append(f"| {r['case']} | {r['points']} | {r['rows']} | {1e3 * r['median_s']:.2f} | "
                     f"{1e3 * r['min_s']:.2f} | {r['median_s'] / t0:.2f} |")
    errors = [r for r in rep["engine"] if "error" in r]
    if errors:
        lines += ["", "## Engine failures", ""]
        lines += [f"- {r['case']}, points={r['points']}: `{r['error']}`" for r in errors]
    path.write_text("\n".join(lines) + "\n")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=15, help="timed calls per measurement (>= 15 advised)")
    ap.add_argument("--quick", action="store_true", help="points 50 and 200 only, 3 repeats (a smoke run)")
    ap.add_argument("--quad-tol", type=float, default=1e-10)
    ap.add_argument("--root-tol", type=float, default=1e-12)
    ap.add_argument("--out", type=Path, default=RESULTS)
    args = ap.parse_args(argv)
    info = machine_info()       # the load average is taken here, before the runs
    repeat = 3 if args.quick else args.repeat
    points = (50, 200) if args.quick else POINTS
    print("engine table", flush=True)
    eng = engine_table(repeat, points)
    print("same rows", flush=True)
    same = [same_rows(label, c, s, kw, repeat, args.quad_tol, args.root_tol)
            for label, c, s, kw in CASES if "rs=0.5" in label or label.startswith("displacement")]
    rep = {"command": " ".join(["python"] + sys.argv), "repeat": repeat, "machine": info,
           "headline": next(s for s in same if s["case"] == HEADLINE), "same_rows": same, "engine": eng}
    info["load average (1, 5, 15 min) at end"] = ", ".join(f"{x:.2f}" for x in os.getloadavg())
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "time.json").write_text(json.dumps(rep, indent=1) + "\n")
    write_markdown(rep, args.out / "time.md")
    h = rep["headline"]
    print(f"headline: history {1e3 * h['history']['median_s']:.3f} ms, simulate "
          f"{1e3 * h['engine']['median_s']:.3f} ms, baseline {1e3 * h['baseline']['median_s']:.2f} ms, "
          f"ratio {h['ratio_history_median']:.0f}x (history), {h['ratio_median']:.0f}x (simulate)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
