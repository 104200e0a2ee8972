"""Run time of a history whose loading end is given as delta_max / p_max, against the same history
given its a_max (the end-of-loading solve: in the compiled kernel since issue 10, a Python Newton
before), and of long histories (points = 1000, 5000).

Usage::

    python benchmarks/bench_loading_end.py [--repeat 31]

Writes ``benchmarks/results/loading_end.md`` and ``loading_end.json``. Medians and mins of
``--repeat`` back-to-back ``adhfit.loading.history`` calls after one warm-up call, the garbage
collector off during them.
"""
from __future__ import annotations

import argparse
import gc
import json
import statistics
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))

from adhfit.loading import history  # noqa: E402
from bench_time import engine_revision, machine_info  # noqa: E402

RESULTS = ROOT / "benchmarks" / "results"
BASE = {"displacement": dict(p=0.6, w=0.2, rs=0.5), "pressure": dict(d=0.0, w=0.2, rs=0.5)}


def _time(kw: dict, repeat: int) -> dict:
    history(**kw)
    gc.collect()
    gc.disable()
    try:
        ts = []
        for _ in range(repeat):
            t = time.perf_counter()
            history(**kw)
            ts.append(time.perf_counter() - t)
    finally:
        gc.enable()
    return {"median_ms": 1e3 * statistics.median(ts), "min_ms": 1e3 * min(ts)}


def _cases() -> list[tuple[str, dict]]:
    out = []
    for control, end in (("displacement", "delta_max"), ("pressure", "p_max")):
        for slip in ("frictionless", "no-slip"):
            kw = dict(control=control, slip=slip, **BASE[control])
            a_max = 0.25
            value = history(**kw, a_max=a_max).columns
            mc = value["stage"] == "making_contact"
            reached = float(value["delta"][mc][-1] if end == "delta_max" else value["p"][mc][-1])
            out.append((f"{control} / {slip} / {end}={reached:.6g}", {**kw, end: reached}))
            out.append((f"{control} / {slip} / a_max={a_max}", {**kw, "a_max": a_max}))
    for control in ("displacement", "pressure"):
        for slip in ("frictionless", "no-slip"):
            for points in (1000, 5000):
                out.append((f"{control} / {slip} / a_max=0.25 / points={points}",
                            dict(control=control, slip=slip, **BASE[control], a_max=0.25, points=points)))
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=31)
    ap.add_argument("--out", type=Path, default=RESULTS)
    args = ap.parse_args(argv)
    rows = []
    for name, kw in _cases():
        try:
            rows.append({"case": name, **_time(kw, args.repeat)})
        except Exception as err:  # noqa: BLE001 - a failing case is a result (points limit before)
            rows.append({"case": name, "error": f"{type(err).__name__}: {err}"[:160]})
        print(rows[-1], flush=True)
    res = {"revision": engine_revision(), "machine": machine_info(), "repeat": args.repeat, "rows": rows}
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "loading_end.json").write_text(json.dumps(res, indent=1) + "\n")
    lines = [f"# History with the loading end given as delta_max / p_max, and long histories ({res['revision']})",
             "", f"Command: `python benchmarks/bench_loading_end.py --repeat {args.repeat}`  ",
             "Machine: " + ", ".join(f"{k} {v}" for k, v in res["machine"].items()), "", "| case | median ms | min ms |", "|---|---:|---:|"]
    for r in rows:
        lines.append(f"| {r['case']} | {r['median_ms']:.3f} | {r['min_ms']:.3f} |" if "error" not in r
                     else f"| {r['case']} | failed: {r['error']} | |")
    (args.out / "loading_end.md").write_text("\n".join(lines) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
