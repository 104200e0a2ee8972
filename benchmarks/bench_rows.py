"""Fit time and peak memory against the rows of a curve, 300 to 1,000,000 (issue 23: a dense lab log).

Each curve is a seeded synthetic displacement-control test (the recovery study's curved scene:
W_ad = 0.4 J/m², μh = 2 N/m, 1 % force noise) written to a CSV file, then fitted by the command line
in a fresh process (``adhfit fit CURVE --scene SCENE -o OUT``: read, checks, fit of both slip
conditions, reports).  Wall time and peak resident memory come from ``/usr/bin/time``; the verdict
and the 95 % intervals from ``report.json``.  Curves above 6,000 rows are fitted as ~2,000 bins of
consecutive rows (``adhfit.fitting.segments.thin``); with ``--raw-up-to N`` the same curves up to N
rows are also fitted row by row (the library's ``thin=False``, in process), to show that the bins
give the same intervals.

Usage: python benchmarks/bench_rows.py [--rows 300 1000 ...] [--slips no-slip frictionless] [--raw-up-to 20000]
"""
from __future__ import annotations

import argparse
import json
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

SCENE = """[membrane]
radius = "2 mm"
prestretch = 2.0
model = "large-stretch"
[substrate]
radius = "1 mm"
[test]
control = "displacement"
pressure = "1.2 kPa"
"""
TRUTH = {"work_of_adhesion": 0.4, "mu_h": 2.0}


def _revision() -> str:
    rev = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT, capture_output=True, text=True).stdout.strip()
    dirty = subprocess.run(["git", "status", "--porcelain", "adhfit"], cwd=ROOT, capture_output=True, text=True).stdout
    return rev + ("+dirty" if dirty.strip() else "")


def make_curve(rows: int, slip: str, seed: int, folder: Path) -> tuple[Path, Path]:
    """Write the seeded curve and its scene; returns (csv, toml)."""
    import pandas as pd

    from adhfit.scene import load_scene
    from adhfit.synthetic import synthetic_curve
    toml = folder / "scene.toml"
    toml.write_text(SCENE)
    scene = load_scene(toml)
    curve, _ = synthetic_curve(scene, slip, **TRUTH, x_max=0.6e-3, x_offset=20e-6, rows=rows, noise=0.01,
                               rng=np.random.default_rng(seed))
    path = folder / f"curve_{slip}_{rows}.csv"
    pd.DataFrame({"displacement [m]": curve.x, "force [N]": curve.force}).to_csv(path, index=False)
    return path, toml


def cli_fit(path: Path, toml: Path, out: Path) -> dict:
    """One ``adhfit fit`` in a fresh process: wall s, peak RSS MiB, verdict, intervals."""
    cmd = ["/usr/bin/time", "-f", "%e %M", sys.executable, "-m", "adhfit.cli", "fit", str(path), "--scene",
           str(toml), "-o", str(out)]
    proc = subprocess.run(cmd, capture_output=True, text=True, cwd=ROOT)
    wall, rss_kb = proc.stderr.strip().splitlines()[-1].split()
    rec = {"wall_s": float(wall), "peak_rss_mib": int(rss_kb) / 1024, "exit": proc.returncode}
    if (out / "report.json").exists():
        rep = json.loads((out / "report.json").read_text())
        rec.update(selected=rep["slip"]["selected"], evidence=rep["slip"].get("evidence"),
                   delta_bic=rep["slip"].get("delta_bic"),
                   **{f"{k}_ci95": rep["parameters"][k]["ci95"] for k in TRUTH},
                   **{k: rep["parameters"][k]["value"] for k in TRUTH})
    return rec


def raw_fit(path: Path, toml: Path) -> dict:
    """The same curve fitted row by row (``thin=False``) in this process: wall s and intervals."""
    import adhfit
    t0 = time.perf_counter()
    r = adhfit.fit(path, toml, thin=False)
    rec = {"wall_s": time.perf_counter() - t0, "selected": r.slip["selected"], "evidence": r.slip.get("evidence"),
           "delta_bic": r.slip.get("delta_bic")}
    for k in TRUTH:
        rec[k] = r.parameters[k].value
        rec[f"{k}_ci95"] = list(r.parameters[k].ci95) if r.parameters[k].ci95 is not None else None
    return rec


def _width(ci) -> float:
    return float(ci[1] - ci[0]) if ci and None not in ci else float("nan")


def report(records: list[dict], args, started: float) -> str:
    lines = ["# Fit time and peak memory against rows", "",
             f"Command: `python benchmarks/bench_rows.py {' '.join(sys.argv[1:])}`  ",
             f"Machine: python {platform.python_version()}, {platform.machine()}, nproc "
             f"{len(__import__('os').sched_getaffinity(0))}, adhfit revision {_revision()}, load average at start "
             f"{args.load0}, at end {', '.join(f'{x:.2f}' for x in __import__('os').getloadavg())}; "
             f"{time.time() - started:.0f} s in all.", "",
             "Each row: one seeded synthetic curve (displacement control, curved substrate, W_ad = 0.4 J/m², "
             "μh = 2 N/m, 1 % noise) fitted by `adhfit fit` in a fresh process (numba cache warm): wall time and peak "
             "resident memory of the whole command (read, checks, both slip fits, reports).  Above 6,000 rows the "
             "fit sees ~2,000 bins of consecutive rows (the report says so).", "",
             "| rows | slip | wall s | peak RSS MiB | verdict | W_ad 95 % | μh 95 % | truth inside |",
             "|---:|---|---:|---:|---|---|---|---|"]
    for r in records:
        if r["kind"] != "cli":
            continue
        inside = all(r.get(f"{k}_ci95") and r[f"{k}_ci95"][0] <= v <= r[f"{k}_ci95"][1] for k, v in TRUTH.items())
        ci = {k: ("[%.5g, %.5g]" % tuple(r[f"{k}_ci95"])) if r.get(f"{k}_ci95") else "—" for k in TRUTH}
        lines.append(f"| {r['rows']:,} | {r['slip']} | {r['wall_s']:.1f} | {r['peak_rss_mib']:.0f} | "
                     f"{r.get('selected')}: {r.get('evidence')} (ΔBIC {r.get('delta_bic') or 0:.3g}) | "
                     f"{ci['work_of_adhesion']} | {ci['mu_h']} | {'yes' if inside else 'NO'} |")
    raws = [r for r in records if r["kind"] == "raw"]
    if raws:
        lines += ["", "## Bins against every row (the same curves, `adhfit.fit(..., thin=False)` in process)", "",
                  "| rows | slip | wall s, every row | W_ad width: bins / rows | μh width: bins / rows | "
                  "W_ad shift / SE | verdict, every row |", "|---:|---|---:|---:|---:|---:|---|"]
        for r in raws:
            b = next(c for c in records if c["kind"] == "cli" and c["rows"] == r["rows"] and c["slip"] == r["slip"])
            ratio = {k: _width(b[f"{k}_ci95"]) / _width(r[f"{k}_ci95"]) for k in TRUTH}
            se = _width(r["work_of_adhesion_ci95"]) / 3.92
            shift = (b["work_of_adhesion"] - r["work_of_adhesion"]) / se
            lines.append(f"| {r['rows']:,} | {r['slip']} | {r['wall_s']:.1f} | {ratio['work_of_adhesion']:.3f} | "
                         f"{ratio['mu_h']:.3f} | {shift:+.2f} | {r['selected']}: {r['evidence']} "
                         f"(ΔBIC {r['delta_bic'] or 0:.3g}) |")
    return "\n".join(lines) + "\n"


def main() -> None:
    import os
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--rows", type=int, nargs="+", default=[300, 1000, 5000, 20000, 100000, 1000000])
    ap.add_argument("--slips", nargs="+", default=["no-slip", "frictionless"])
    ap.add_argument("--raw-up-to", type=int, default=20000, help="also fit row by row up to this many rows")
    ap.add_argument("--seed", type=int, default=20261204)
    ap.add_argument("--out", default=str(ROOT / "benchmarks" / "results" / "rows"))
    args = ap.parse_args()
    args.load0 = ", ".join(f"{x:.2f}" for x in os.getloadavg())
    started = time.time()
    records = []
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        for slip in args.slips:
            for i, rows in enumerate(args.rows):
                path, toml = make_curve(rows, slip, args.seed + i, tmp)
                rec = {"kind": "cli", "rows": rows, "slip": slip, **cli_fit(path, toml, tmp / f"out_{slip}_{rows}")}
                print(rec, flush=True)
                records.append(rec)
                if rows <= args.raw_up_to and rows > 6000:
                    raw = {"kind": "raw", "rows": rows, "slip": slip, **raw_fit(path, toml)}
                    print(raw, flush=True)
                    records.append(raw)
                path.unlink()
    out = Path(args.out)
    out.with_suffix(".json").write_text(json.dumps(records, indent=1))
    out.with_suffix(".md").write_text(report(records, args, started))
    print(out.with_suffix(".md").read_text())


if __name__ == "__main__":
    main()
