"""Domain-wide stress run of the exact membrane (issue 11): random scenes at the default step count
against the same scenes at n = 32.

Scenes are drawn with an explicitly seeded ``numpy.random.Generator``: lambda0 uniform in [1.1, 3],
control and slip alternating, rs in {0.5, 1, 2, flat}, w log-uniform in [0.02, 1], a_max uniform in
[0.1, 0.4] (capped at 0.9 rs), p uniform in [0.2, 0.8] (displacement) or d in [-0.05, 0.3] (pressure),
200 rows. Each scene is run at the default n (CPU time measured) and at n = 32 and counted as

    success | success_branch_ends_early | input_error | convergence_error | other_exception
    | outcome_mismatch | nan_in_output | invariant_violation

``outcome_mismatch``: the two step counts disagree on whether the scene has a Case I history.
``nan_in_output``: a NaN outside ``delta`` (which is NaN exactly where free inflation has no Case I
state at the row's pressure: the two runs must agree on which rows), or in the summary's f and a.
``invariant_violation``: stage order, 0 <= G <= w (1e-9), no-slip alpha >= 0 (the membrane never
enters the substrate), f_min <= every pinning/delamination f. For every success: the largest
difference of the summary (f_max; onset, f_min, turning point: f, p, a, delta) from n = 32 and of the
rows that sit on the same parameter grid (every making-contact and pinning row, and the delamination
rows at the same rho_a, i.e. all but the inserted extrema): a, alpha, p, d, delta, f, G.

Usage::

    python benchmarks/stress_exact.py --n 200 --seed 20261202

Writes ``stress_exact.md`` and ``stress_exact.json`` to ``benchmarks/results``.
"""
from __future__ import annotations

import argparse
import json
import math
import os
import platform
import subprocess
import sys
import time
from collections import Counter
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from adhfit.errors import ConvergenceError, InputError  # noqa: E402
from adhfit.exact.history import exact_history  # noqa: E402
from adhfit.exact.state import DEFAULT_N  # noqa: E402

FINE_N = 32
COLS = ("a", "alpha", "p", "d", "delta", "f", "G")
STAGES = ("making_contact", "pinning", "delamination")


def draw(rng: np.random.Generator, i: int) -> dict:
    """Scene i: see the module docstring."""
    control = ("displacement", "pressure")[(i // 2) % 2]
    rs = (0.5, 1.0, 2.0, math.inf)[(i // 4) % 4]
    sc = {"control": control, "slip": ("frictionless", "no-slip")[i % 2], "lambda0": float(rng.uniform(1.1, 3.0)),
          "rs": rs, "w": float(10 ** rng.uniform(math.log10(0.02), 0.0)),
          "a_max": float(min(rng.uniform(0.1, 0.4), 0.9 * rs)), "points": 200}
    if control == "displacement":
        sc["p"] = float(rng.uniform(0.2, 0.8))
    else:
        sc["d"] = float(rng.uniform(-0.05, 0.3))
    return sc


def _summary(h) -> np.ndarray:
    s = h.summary
    vals = [s["f_max"]] + [s[k][q] for k in ("onset", "f_min", "turning_point") for q in ("f", "p", "a", "delta")]
    return np.array([math.nan if v is None else v for v in vals], dtype=float)


def _grid_rows(h) -> dict:
    """Rows on the parameter grid, keyed (stage, index within the stage) for making contact and pinning,
    (stage, rounded rho_a) for delamination (the inserted extrema are left out)."""
    out, k = {}, Counter()
    ext = {round(h.summary[q]["a"], 12) for q in ("f_min", "turning_point")}
    for i, (stage, st) in enumerate(zip(h.columns["stage"], h.states)):
        if stage == "delamination":
            if round(st.a, 12) in ext:
                continue
            key = (stage, round(st.rho_a, 7))
        else:
            key = (stage, k[stage])
            k[stage] += 1
        out[key] = np.array([h.columns[c][i] for c in COLS], dtype=float)
    return out


def _violations(h, w: float, slip: str) -> list[str]:
    c = h.columns
    found = []
    order = [STAGES.index(s) for s in c["stage"]]
    if any(b < a for a, b in zip(order, order[1:])):
        found.append("stage order")
    if not np.all((c["G"] >= -1e-9) & (c["G"] <= w + 1e-9)):
        found.append("G outside [0, w]")
    if slip == "no-slip" and np.any(c["alpha"] < 0.0):
        found.append("no-slip alpha < 0")
    after = np.isin(c["stage"], ("pinning", "delamination"))
    if np.any(c["f"][after] < h.summary["f_min"]["f"] - 1e-9):
        found.append("a row below f_min")
    return found


def _nan_problem(h) -> bool:
    c = h.columns
    if any(not np.all(np.isfinite(c[k])) for k in ("a", "alpha", "p", "d", "f", "G")):
        return True
    return not np.all(np.isfinite(_summary(h)[[0, 1, 3, 5, 7, 9, 11]]))


def run_scene(sc: dict) -> dict:
    """Both step counts of one scene; the record of the results."""
    rec = {"scene": sc}
    kw = {k: v for k, v in sc.items() if k not in ("control", "slip")}
    outs = []
    for n in (DEFAULT_N, FINE_N):
        t = time.process_time()
        try:
            outs.append(exact_history(sc["control"], sc["slip"], n=n, **kw))
        except InputError as exc:
            outs.append(("input_error", str(exc)[:160]))
        except ConvergenceError as exc:
            outs.append(("convergence_error", str(exc)[:160]))
        except Exception as exc:  # noqa: BLE001 - counted, with its message
            outs.append(("other_exception", f"{type(exc).__name__}: {exc}"[:160]))
        if n == DEFAULT_N:
            rec["cpu_ms"] = 1e3 * (time.process_time() - t)
    h, fine = outs
    if isinstance(h, tuple) or isinstance(fine, tuple):
        kinds = {o[0] if isinstance(o, tuple) else "success" for o in outs}
        rec["outcome"] = h[0] if len(kinds) == 1 else "outcome_mismatch"
        rec["message"] = h[1] if isinstance(h, tuple) else fine[1]
        return rec
    bad = _violations(h, sc["w"], sc["slip"])
    if _nan_problem(h):
        rec["outcome"] = "nan_in_output"
        return rec
    if bad:
        rec["outcome"], rec["message"] = "invariant_violation", "; ".join(bad)
        return rec
    ends = "delamination_ends_at_a" in h.inputs
    rec["outcome"] = "success_branch_ends_early" if ends else "success"
    sa, sb = _summary(h), _summary(fine)
    if not np.array_equal(np.isnan(sa), np.isnan(sb)):
        rec["outcome"], rec["message"] = "nan_in_output", "summary delta NaN at one step count only"
        return rec
    rec["summary_err"] = float(np.nanmax(np.abs(sa - sb)))
    ga, gb = _grid_rows(h), _grid_rows(fine)
    common = [k for k in ga if k in gb]
    errs = [np.abs(ga[k] - gb[k]) for k in common]
    if any(not np.array_equal(np.isnan(ga[k]), np.isnan(gb[k])) for k in common):
        rec["outcome"], rec["message"] = "nan_in_output", "delta NaN at one step count only"
        return rec
    rec["rows_compared"] = len(common)
    rec["rows_err"] = float(np.nanmax(errs)) if errs else math.nan
    return rec


def _q(x: list, qs=(0.5, 0.95, 1.0)) -> list:
    return [float(np.quantile(x, q)) for q in qs] if x else [math.nan] * len(qs)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--n", type=int, default=200, help="scenes")
    ap.add_argument("--seed", type=int, default=20261202)
    args = ap.parse_args()
    rng = np.random.default_rng(args.seed)
    load0 = os.getloadavg()
    exact_history("pressure", "no-slip", d=0.2, w=0.2, rs=0.5, a_max=0.25, lambda0=1.5)  # compile/load
    recs = [run_scene(draw(rng, i)) for i in range(args.n)]
    counts = Counter(r["outcome"] for r in recs)
    ok = [r for r in recs if r["outcome"].startswith("success")]
    summ, rows, cpu = ([r[k] for r in ok] for k in ("summary_err", "rows_err", "cpu_ms"))
    worst = sorted(ok, key=lambda r: -max(r["summary_err"], r["rows_err"]))[:5]
    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT, capture_output=True,
                            text=True).stdout.strip()
    meta = {"command": f"python benchmarks/stress_exact.py --n {args.n} --seed {args.seed}", "commit": commit,
            "python": platform.python_version(), "nproc": os.cpu_count(), "load_start": load0,
            "load_end": os.getloadavg(), "default_n": DEFAULT_N, "fine_n": FINE_N}
    out = ROOT / "benchmarks" / "results"
    (out / "stress_exact.json").write_text(json.dumps({"meta": meta, "counts": counts, "records": recs},
                                                      indent=1, default=str))
    lines = ["# Exact membrane: domain-wide stress run (default n against n = 32)", "",
             f"Command: `{meta['command']}` at {commit}; python {meta['python']}, nproc {meta['nproc']}, "
             f"load average at start {load0[0]:.2f}, at end {meta['load_end'][0]:.2f}. Default n = {DEFAULT_N}.",
             "", "Scenes and outcomes as in the script's docstring.", "", "| outcome | scenes |", "|---|---:|"]
    lines += [f"| {k} | {v} |" for k, v in sorted(counts.items())]
    lines += ["", "Over the successful scenes (median / 95th percentile / max):", "",
              "| quantity | median | 95 % | max |", "|---|---:|---:|---:|"]
    for name, xs, fmt in (("summary error vs n = 32", summ, "{:.1e}"), ("grid rows error vs n = 32", rows, "{:.1e}"),
                          ("CPU ms per 200-row history (default n)", cpu, "{:.1f}")):
        lines.append(f"| {name} | " + " | ".join(fmt.format(v) for v in _q(xs)) + " |")
    lines += ["", "Largest errors:", "", "| scene | summary err | rows err |", "|---|---:|---:|"]
    for r in worst:
        s = r["scene"]
        lines.append(f"| {s['control']} {s['slip']} lambda0 {s['lambda0']:.3f} rs {s['rs']} w {s['w']:.3g} "
                     f"a_max {s['a_max']:.3f} {'p' if 'p' in s else 'd'} {s.get('p', s.get('d')):.3f} | "
                     f"{r['summary_err']:.1e} | {r['rows_err']:.1e} |")
    failed = [r for r in recs if not r["outcome"].startswith("success")]
    if failed:
        lines += ["", "Scenes without a history (first 10):", ""]
        for r in failed[:10]:
            lines.append(f"- {r['outcome']}: {r['scene']} — {r.get('message', '')}")
    (out / "stress_exact.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
