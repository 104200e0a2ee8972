"""Compiled (numba) backend against the numpy path of the engine.

(a) Median wall time of ``adhfit.simulate`` for the 8 combinations control x slip x substrate
    (the paper's base cases p = 0.6 / d = 0, w = 0.2, rs = 0.5, a_max = 0.25, and a flat variant,
    d = 0.2 under pressure control), 200 rows, under each backend, and their ratio; for the headline
    case also the split between loading.py's own Python, the backend layer and the kernels.
(b) First-call time in a fresh process: numba import + compilation with an empty cache, and the same
    with the cache filled (both in a temporary NUMBA_CACHE_DIR, so the repository's cache is untouched).
(c) ``import adhfit`` time (``-X importtime``) and whether it imports numba.

Usage::

    python benchmarks/bench_backend.py [--repeat 9] [--quick]

Writes ``benchmarks/results/backend.md`` and ``backend.json``.
"""
from __future__ import annotations

import argparse
import json
import math
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))

import numpy as np  # noqa: E402

import adhfit  # noqa: E402
from adhfit.core import backend  # noqa: E402

RESULTS = ROOT / "benchmarks" / "results"
from cases import CASES, HEADLINE  # noqa: E402 - shared with the other benchmark

FIRST_CALL = """
import time, sys
t0 = time.perf_counter()
import adhfit
t1 = time.perf_counter()
adhfit.simulate("displacement", "frictionless", p=0.6, w=0.2, rs=0.5, a_max=0.25)
t2 = time.perf_counter()
for control, slip, kw in [("displacement", "no-slip", dict(p=0.6)), ("pressure", "frictionless", dict(d=0.0)),
                          ("pressure", "no-slip", dict(d=0.0))]:
    adhfit.simulate(control, slip, w=0.2, rs=0.5, a_max=0.25, **kw)
t3 = time.perf_counter()
print(t1 - t0, t2 - t1, t3 - t2)
"""


def _median_ms(fn, repeat):
    fn()  # warm-up (compilation / cache load happens here)
    times = []
    for _ in range(repeat):
        t = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t)
    return 1e3 * statistics.median(times), 1e3 * min(times)


def time_cases(repeat):
    rows = []
    for label, control, slip, kw in CASES:
        out = {"case": label}
        for name in ("numpy", "numba"):
            with backend.use(name):
                med, best = _median_ms(lambda: adhfit.simulate(control, slip, points=200, **kw),
                                       repeat if name == "numba" else max(3, repeat // 3))
            out[name] = {"median_ms": med, "min_ms": best}
        out["ratio"] = out["numpy"]["median_ms"] / out["numba"]["median_ms"]
        rows.append(out)
        print(f"{label:40s} numpy {out['numpy']['median_ms']:9.2f} ms  numba "
              f"{out['numba']['median_ms']:7.3f} ms  x{out['ratio']:.0f}", flush=True)
    return rows


def split_headline(repeat):
    """Time spent in loading.py itself, in the backend layer and in the kernels (headline case)."""
    import adhfit.loading as L
    from adhfit.core import compiled as K

    spent = {"backend": 0.0, "kernels": 0.0}

    def wrap(mod, name, bucket):
        fn = getattr(mod, name)

        def timed(*a, **k):
            t = time.perf_counter()
            try:
                return fn(*a, **k)
            finally:
                spent[bucket] += time.perf_counter() - t
        return fn, timed

    saved = []
    for mod, names, bucket in ((L, ("evaluate", "solve_state", "derivative", "check_ok"), "backend"),
                               (K, ("evaluate_batch", "solve_batch", "derivative_batch", "first_bad"),
                                "kernels")):
        for name in names:
            fn, timed = wrap(mod, name, bucket)
            saved.append((mod, name, fn))
            setattr(mod, name, timed)
    try:
        best = None
        with backend.use("numba"):
            for _ in range(repeat + 1):
                spent.update(backend=0.0, kernels=0.0)
                t = time.perf_counter()
                L.history("displacement", "frictionless", p=0.6, w=0.2, rs=0.5, a_max=0.25)
                total = time.perf_counter() - t
                if best is None or total < best[0]:
                    best = (total, dict(spent))
    finally:
        for mod, name, fn in saved:
            setattr(mod, name, fn)
    total, s = best
    return {"history_ms": 1e3 * total, "backend_ms": 1e3 * s["backend"], "kernels_ms": 1e3 * s["kernels"],
            "loading_itself_ms": 1e3 * (total - s["backend"])}


def first_call():
    with tempfile.TemporaryDirectory() as cache:
        env = {**os.environ, "NUMBA_CACHE_DIR": cache}
        res = {}
        for name in ("cold", "warm"):
            out = subprocess.run([sys.executable, "-c", FIRST_CALL], env=env, capture_output=True,
                                 text=True, check=True, cwd=ROOT)
            imp, first, more = (float(v) for v in out.stdout.split())
            res[name] = {"import_s": imp, "first_simulate_s": first, "three_more_combos_s": more}
            print(f"first call, {name} cache: import {imp:.2f} s, first simulate {first:.2f} s, "
                  f"3 more combinations {more:.2f} s", flush=True)
    return res


def import_time():
    out = subprocess.run([sys.executable, "-X", "importtime", "-c",
                          "import adhfit, sys; print('numba' in sys.modules)"],
                         capture_output=True, text=True, check=True, cwd=ROOT)
    us = [int(line.split("|")[1]) for line in out.stderr.splitlines()
          if line.strip().endswith("| adhfit")]
    return {"adhfit_cumulative_ms": us[-1] / 1e3 if us else None,
            "numba_imported": out.stdout.strip() == "True"}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=9)
    ap.add_argument("--quick", action="store_true", help="fewer repeats, no first-call runs")
    args = ap.parse_args()
    repeat = 3 if args.quick else args.repeat
    rev = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True,
                         cwd=ROOT).stdout.strip()
    dirty = subprocess.run(["git", "status", "--porcelain", "adhfit"], capture_output=True, text=True,
                           cwd=ROOT).stdout.strip()
    result = {
        "command": " ".join([Path(sys.executable).name, *sys.argv]),
        "machine": {"python": platform.python_version(), "numpy": np.__version__,
                    "numba": __import__("numba").__version__, "nproc": os.cpu_count(),
                    "load_average": os.getloadavg()},
        "revision": rev + ("+dirty" if dirty else ""),
        "cases": time_cases(repeat),
        "headline_split": split_headline(repeat),
        "import": import_time(),
    }
    if not args.quick:
        result["first_call"] = first_call()
    RESULTS.mkdir(exist_ok=True)
    (RESULTS / "backend.json").write_text(json.dumps(result, indent=2))
    lines = [f"# numba backend vs numpy path ({result['revision']})", "",
             f"`{result['command']}`; {result['machine']}", "",
             "| case (200 rows) | numpy median ms | numba median ms | numba min ms | ratio |",
             "|---|---|---|---|---|"]
    for r in result["cases"]:
        lines.append(f"| {r['case']} | {r['numpy']['median_ms']:.2f} | {r['numba']['median_ms']:.3f} | "
                     f"{r['numba']['min_ms']:.3f} | {r['ratio']:.0f} |")
    s = result["headline_split"]
    lines += ["", f"Headline ({HEADLINE}), best of {repeat}: history {s['history_ms']:.3f} ms = "
              f"loading.py itself {s['loading_itself_ms']:.3f} ms + backend {s['backend_ms']:.3f} ms "
              f"(of which kernels {s['kernels_ms']:.3f} ms).",
              f"import adhfit: {result['import']['adhfit_cumulative_ms']} ms, numba imported: "
              f"{result['import']['numba_imported']}"]
    if "first_call" in result:
        for name, v in result["first_call"].items():
            lines.append(f"First call ({name} numba cache): import {v['import_s']:.2f} s, first simulate "
                         f"{v['first_simulate_s']:.2f} s, three more combinations "
                         f"{v['three_more_combos_s']:.2f} s.")
    (RESULTS / "backend.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
