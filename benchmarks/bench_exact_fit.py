"""Exact-membrane least-squares fits: recovery and cost (issue 11 item 3).

Curves from ``adhfit.exact.exact_history`` (tests/exact_curves.py: b = 2 mm, R_s = 1 mm, P = 600 Pa,
μh = 2 N/m, W_ad = 0.4 J/m^2, 240 rows, displacement control), fitted with default settings
(``membrane`` from the scene: auto; slip auto), at λ0 = 1.1, 1.2, 1.5, 2 and 3.  Reports per case: the membrane auto chose, the slip
verdict, the errors of W_ad and μh, whether the 95 % intervals hold the truth, wall and CPU seconds
and the number of histories.  CPU seconds are the figure to compare (the machine is shared).

    PYTHONPATH=. python benchmarks/bench_exact_fit.py [--quick]
    PYTHONPATH=. python benchmarks/bench_exact_fit.py --replicates 8   # seeds 20.. at 0.5 % noise
    PYTHONPATH=. python benchmarks/bench_exact_fit.py --control pressure   # F-P curves (0.4 mm gap, to 1.5 kPa)

``--replicates N`` fits N noise draws of λ0 = 1.2 (frictionless) and 1.5 (no-slip) instead: mean and
spread of the errors, coverage of the 95 % intervals, wrong slip selections (exact_fit_replicates.md).
"""
from __future__ import annotations

import argparse
import json
import os
import platform
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from adhfit.fitting.api import fit as fit_curve  # noqa: E402
from tests.exact_curves import exact_curve, scene  # noqa: E402

CASES = [(lam, slip, noise) for lam in (1.1, 1.2, 1.5, 2.0, 3.0) for slip in ("frictionless", "no-slip")
         for noise in (0.005, 0.01)]


def run(lam: float, slip: str, noise: float, seed: int = 1, control: str = "displacement") -> dict:
    """One fit of one exact curve; the row of the results table."""
    curve, truth = exact_curve(lam, slip, noise=noise, seed=seed, control=control)
    t, c = time.perf_counter(), time.process_time()
    res = fit_curve(curve, scene(lam, control=control))
    row = {"lambda0": lam, "slip": slip, "noise": noise, "membrane": res.model["membrane"],
           "verdict": res.slip["verdict"], "selected": res.slip["selected"],
           "wall_s": time.perf_counter() - t, "cpu_s": time.process_time() - c, "histories": res.n_histories,
           "why": res.model["why"]}
    c = time.process_time()
    fit_curve(curve, scene(lam, control=control), membrane="large-stretch")  # the same curve, the approximation
    row["ls_cpu_s"] = time.process_time() - c
    for k in ("work_of_adhesion", "mu_h"):
        e = res.parameters[k]
        row[f"{k}_error"] = e.value / truth[k] - 1.0
        row[f"{k}_covered"] = bool(e.ci95 and e.ci95[0] is not None and e.ci95[1] is not None
                                   and e.ci95[0] <= truth[k] <= e.ci95[1])
    return row


def replicates(n: int) -> list[str]:
    """Error statistics, coverage and wrong-slip counts over ``n`` seeds per case."""
    import numpy as np  # noqa: PLC0415
    lines = ["| λ0 | truth | noise | seeds | W_ad err mean ± sd | μh err mean ± sd | max abs err W/μh | "
             "covered W/μh | wrong slip | CPU s per fit |", "|---|---|---|---|---|---|---|---|---|---|"]
    for lam, slip in ((1.2, "frictionless"), (1.5, "no-slip")):
        rows = [run(lam, slip, 0.005, seed=20 + k) for k in range(n)]
        ew = np.array([r["work_of_adhesion_error"] for r in rows])
        em = np.array([r["mu_h_error"] for r in rows])
        lines.append(f"| {lam:g} | {slip} | 0.5 % | {n} | {100 * ew.mean():+.2f} ± {100 * ew.std():.2f} % | "
                     f"{100 * em.mean():+.2f} ± {100 * em.std():.2f} % | {100 * abs(ew).max():.2f} / "
                     f"{100 * abs(em).max():.2f} % | {sum(r['work_of_adhesion_covered'] for r in rows)} / "
                     f"{sum(r['mu_h_covered'] for r in rows)} | "
                     f"{sum(r['selected'] not in (slip, None) for r in rows)} | "
                     f"{np.median([r['cpu_s'] for r in rows]):.1f} |")
    return lines


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="0.5 %% noise only")
    ap.add_argument("--replicates", type=int, default=0, help="N noise draws per case instead (see above)")
    ap.add_argument("--control", choices=("displacement", "pressure"), default="displacement",
                    help="pressure: F-P curves at a 0.4 mm gap loaded to 1.5 kPa (exact_fit_pressure.*)")
    args = ap.parse_args()
    if args.replicates:
        lines = ["# Exact-membrane fits: replicates (default settings)", "",
                 f"`PYTHONPATH=. python benchmarks/bench_exact_fit.py --replicates {args.replicates}`", "",
                 *replicates(args.replicates)]
        (ROOT / "benchmarks" / "results" / "exact_fit_replicates.md").write_text("\n".join(lines) + "\n")
        print("\n".join(lines))
        return
    run(*CASES[0], control=args.control)  # warm-up: kernels loaded, lmfit imported
    rows = [run(*c, control=args.control) for c in CASES if not (args.quick and c[2] != 0.005)]
    name = "exact_fit" if args.control == "displacement" else "exact_fit_pressure"
    git = {"cwd": ROOT, "capture_output": True, "text": True}
    rev = subprocess.run(["git", "rev-parse", "--short", "HEAD"], **git).stdout.strip()
    dirty = subprocess.run(["git", "status", "--porcelain", "adhfit"], **git).stdout
    machine = (f"commit {rev}{'+dirty' if dirty.strip() else ''}; Python {platform.python_version()}, "
               f"nproc {os.cpu_count()} (shared with other jobs: compare CPU seconds)")
    out = ROOT / "benchmarks" / "results"
    (out / f"{name}.json").write_text(json.dumps(rows, indent=1))
    lines = [f"# Exact-membrane fits (default settings, {args.control} control)", "",
             f"`PYTHONPATH=. python benchmarks/bench_exact_fit.py{' --quick' if args.quick else ''}"
             f"{' --control pressure' if args.control == 'pressure' else ''}`", "", machine, "",
             "Last columns: the CPU seconds of the same curve fitted with `membrane=\"large-stretch\"`, and the ratio "
             "(issue 21: the exact fit within 2x).", "",
             "| λ0 | truth | noise | membrane | slip verdict | W_ad err | μh err | in 95 % (W/μh) | CPU s | wall s |"
             " histories | CPU s large-stretch | ratio |", "|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {r['lambda0']:g} | {r['slip']} | {100 * r['noise']:g} % | {r['membrane']} | {r['verdict']} | "
                     f"{100 * r['work_of_adhesion_error']:+.2f} % | {100 * r['mu_h_error']:+.2f} % | "
                     f"{'yes' if r['work_of_adhesion_covered'] else 'NO'}/{'yes' if r['mu_h_covered'] else 'NO'} | "
                     f"{r['cpu_s']:.2f} | {r['wall_s']:.1f} | {r['histories']} | {r['ls_cpu_s']:.2f} | "
                     f"{r['cpu_s'] / r['ls_cpu_s']:.2f} |")
    import statistics  # noqa: PLC0415
    ratios = [r["cpu_s"] / r["ls_cpu_s"] for r in rows]
    lines += ["", f"CPU ratio exact (default) / large-stretch: median {statistics.median(ratios):.2f}, "
              f"range {min(ratios):.2f}-{max(ratios):.2f}; intervals holding the truth: "
              f"{sum(r['work_of_adhesion_covered'] for r in rows)}/{len(rows)} W_ad, "
              f"{sum(r['mu_h_covered'] for r in rows)}/{len(rows)} μh."]
    (out / f"{name}.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
