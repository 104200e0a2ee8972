"""The step count n of the exact-membrane history against its error (issue 11: 1e-6 on every observable).

For lambda0 = 1.1, 1.2, 1.5, 2, 3 and the four base cases (control x slip; p = 0.6 or d = 0.2, w = 0.2,
rs = 0.5, a_max = 0.25, 200 points) and each n of ``--n``:

- ``summary``: max abs error of the A2 summary values (f_max; onset, f_min, turning point: f, delta, p,
  a) against the same engine at n = 128;
- ``columns``: max abs error over every row of the A2 columns a, alpha, p, d, delta, f, G against
  n = 128 (row by row: the rows sit at fixed fractions of a_max, of the onset's alpha and of the loading
  end's rho_a, so a row's error includes that of where it sits);
- ``reference`` (the n of ``--ref-n`` only): states of the history re-shot by the independent adaptive
  solver of tests/exact_reference.py (scipy DOP853 at rtol 1e-13, another formulation) from the
  engine's own unknowns -- the end of loading, the onset, the turning point and the middle delamination
  row: max of |r(beta) - 1|, |d|, |f| and |G| differences; and d0 of free inflation (displacement: at p;
  pressure: at the turning point's pressure) against the reference's;
- ``cpu ms``: median CPU (process_time) of 3 histories after a warm-up (the machine is shared).

The n = 128 engine agrees with the reference to ~1e-11 on single states (tests, exact.md), so the
first two errors are the discretization errors of the history at n.

Usage::

    python benchmarks/bench_exact_n.py [--n 6 7 8 10 12] [--ref-n 8 12]

Writes ``benchmarks/results/exact_n.md`` and ``exact_n.json``.
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
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from adhfit.exact.history import exact_history  # noqa: E402
from adhfit.exact.state import DEFAULT_N  # noqa: E402
from bench_exact import _flat  # noqa: E402 - the summary as flat keys, as bench_exact reports it
from tests import exact_reference as ref  # noqa: E402

LAMBDAS = (1.1, 1.2, 1.5, 2.0, 3.0)
CASES = [("displacement", "frictionless", {"p": 0.6}), ("displacement", "no-slip", {"p": 0.6}),
         ("pressure", "frictionless", {"d": 0.2}), ("pressure", "no-slip", {"d": 0.2})]
COLS = ("a", "alpha", "p", "d", "delta", "f", "G")
RS, W, A_MAX = 0.5, 0.2, 0.25


def _run(control, slip, kw, lam, n):
    return exact_history(control, slip, w=W, rs=RS, a_max=A_MAX, lambda0=lam, points=200, n=n, **kw)


def _worst(got: dict, best: dict) -> tuple[float, str]:
    key = max(best, key=lambda q: abs(got[q] - best[q]))
    return abs(got[key] - best[key]), key


def _columns(h, best) -> tuple[float, str]:
    """Max abs row-by-row difference over COLS (inf if the row counts or NaN patterns differ)."""
    if len(h.columns["a"]) != len(best.columns["a"]):
        return math.inf, "rows"
    errs = {}
    for k in COLS:
        x, y = [list(map(float, c[k])) for c in (h.columns, best.columns)]
        if any(math.isnan(p) != math.isnan(q) for p, q in zip(x, y)):
            return math.inf, k + " NaN"
        errs[k] = max(abs(p - q) for p, q in zip(x, y) if not math.isnan(p))
    key = max(errs, key=errs.get)
    i = max(range(len(h.columns[key])), key=lambda j: abs(h.columns[key][j] - best.columns[key][j])
            if not math.isnan(h.columns[key][j]) else -1.0)
    return errs[key], f"{key} ({h.columns['stage'][i]})"


def _picks(h):
    """(name, state, edge data) of the end of loading, onset, turning point and middle delamination row."""
    stg = list(h.columns["stage"])
    m = h.states[max(i for i, s in enumerate(stg) if s == "making_contact")]
    on = h.states[max(i for i, s in enumerate(stg) if s == "pinning")]
    turn = h.states[max(i for i, s in enumerate(h.columns["stable"]) if s)]
    dl = [i for i, s in enumerate(stg) if s == "delamination"]
    return m, [("loading end", m), ("onset", on), ("turning point", turn), ("delamination", h.states[dl[len(dl) // 2]])]


def _ref_error(h, control, slip, kw, lam) -> tuple[float, str]:
    """Max difference of the picked states re-shot by the reference, and of d0 (see the module doc)."""
    m, picks = _picks(h)
    worst, where = 0.0, ""
    for name, s in picks:
        if name == "loading end":
            edge, lc, l1p = "frictionless", s.lc, None  # alpha = 0: lambda1 continuous
        elif slip == "frictionless":
            edge, lc, l1p = "frictionless", s.lc, None
        else:
            edge, lc, l1p = "given", m.lc, s.l1p
        r_end, d, f, g = ref.edge_state(s.p, lam, RS, lc, s.rho_a, s.alpha, edge, l1p)
        for q, e in (("r", abs(r_end - 1.0)), ("d", abs(d - s.d)), ("f", abs(f - s.f)), ("G", abs(g - s.G))):
            if e > worst:
                worst, where = e, f"{name} {q}"
    p_turn = h.summary["turning_point"]["p"] if control == "pressure" else kw["p"]
    i = max(i for i, s in enumerate(h.columns["stable"]) if s)
    d0 = h.columns["delta"][i] + h.columns["d"][i]
    d0_ref = math.copysign(ref.free_inflation(abs(p_turn), lam)[0], p_turn)
    if abs(d0 - d0_ref) > worst:
        worst, where = abs(d0 - d0_ref), "d0"
    return worst, where


def _cpu(fn, repeat=3):
    fn()
    out = []
    for _ in range(repeat):
        c = time.process_time()
        fn()
        out.append(time.process_time() - c)
    return statistics.median(out)


def table(ns, ref_ns) -> list[dict]:
    rows = []
    for lam in LAMBDAS:
        for control, slip, kw in CASES:
            best = _run(control, slip, kw, lam, 128)
            sb = _flat(best.summary)
            for n in ns:
                h = _run(control, slip, kw, lam, n)
                se, sk = _worst(_flat(h.summary), sb)
                ce, ck = _columns(h, best)
                re, rk = _ref_error(h, control, slip, kw, lam) if n in ref_ns else (None, "")
                rows.append({"lambda0": lam, "control": control, "slip": slip, "n": n, "summary_err": se,
                             "summary_worst": sk, "column_err": ce, "column_worst": ck, "ref_err": re,
                             "ref_worst": rk, "cpu_ms": 1e3 * _cpu(lambda: _run(control, slip, kw, lam, n))})
                print(rows[-1], flush=True)
    return rows


def _lines(rows, meta) -> list[str]:
    lines = ["# Exact membrane: step count n against error over lambda0 (200-row histories)", "",
             f"Command: `{meta['command']}` at {meta['commit']}; python {meta['python']}, nproc {meta['nproc']}, "
             f"load average at start {meta['load_start'][0]:.2f}, at end {meta['load_end'][0]:.2f}. "
             f"Default n = {DEFAULT_N}.", "",
             "Base cases p = 0.6 (displacement) or d = 0.2 (pressure), w = 0.2, rs = 0.5, a_max = 0.25. Errors "
             "are max abs: summary (A2 summary values) and columns (every row of a, alpha, p, d, delta, f, G) "
             "against this engine at n = 128; reference: the end of loading, onset, turning point and middle "
             "delamination states re-shot by the independent adaptive solver (|r(beta) - 1|, d, f, G) and d0 "
             "(see the script's docstring). Issue 11's target: 1e-6 on every observable.", "",
             "| lambda0 | control | slip | n | CPU ms | summary err | worst | columns err | worst | "
             "reference err | worst |", "|---:|---|---|---:|---:|---:|---|---:|---|---:|---|"]
    for r in rows:
        re = "—" if r["ref_err"] is None else f"{r['ref_err']:.1e}"
        lines.append(f"| {r['lambda0']:g} | {r['control']} | {r['slip']} | {r['n']} | {r['cpu_ms']:.1f} | "
                     f"{r['summary_err']:.1e} | {r['summary_worst']} | {r['column_err']:.1e} | "
                     f"{r['column_worst']} | {re} | {r['ref_worst']} |")
    lines += ["", "## Worst case over lambda0 and the four cases, per n", "",
              "| n | summary err | columns err | reference err | CPU ms at lambda0 = 1.5 (4 cases) |",
              "|---:|---:|---:|---:|---|"]
    for n in sorted({r["n"] for r in rows}):
        sel = [r for r in rows if r["n"] == n]
        refs = [r["ref_err"] for r in sel if r["ref_err"] is not None]
        cpu = " / ".join(f"{r['cpu_ms']:.1f}" for r in sel if r["lambda0"] == 1.5)
        lines.append(f"| {n} | {max(r['summary_err'] for r in sel):.1e} | "
                     f"{max(r['column_err'] for r in sel):.1e} | "
                     f"{(f'{max(refs):.1e}' if refs else '—')} | {cpu} |")
    return lines


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--n", type=int, nargs="+", default=[6, 7, 8, 10, 12])
    ap.add_argument("--ref-n", type=int, nargs="*", default=[8, 12])
    args = ap.parse_args()
    load0 = os.getloadavg()
    rows = table(args.n, set(args.ref_n))
    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT, capture_output=True,
                            text=True).stdout.strip()
    cmd = "python benchmarks/bench_exact_n.py --n " + " ".join(map(str, args.n))
    cmd += " --ref-n " + " ".join(map(str, args.ref_n))
    meta = {"command": cmd, "commit": commit, "python": platform.python_version(), "nproc": os.cpu_count(),
            "load_start": load0, "load_end": os.getloadavg(), "default_n": DEFAULT_N}
    out = ROOT / "benchmarks" / "results"
    (out / "exact_n.json").write_text(json.dumps({"meta": meta, "rows": rows}, indent=1))
    lines = _lines(rows, meta)
    (out / "exact_n.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
