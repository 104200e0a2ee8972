"""MCMC with the exact membrane: the checked stand-in against a plain exact run (issue 21).

Curves made with the exact membrane (tests/exact_curves.py, 330 rows, 0.5 % noise) at λ0 = 2 are fitted
by ``adhfit.fit(..., method="mcmc")`` with the default membrane (``auto``: it chooses the exact membrane
here) twice, in fresh processes: with the stand-in (the default: the large-stretch model plus the exact
model's difference, checked on posterior draws, ``adhfit.fitting.stand_in``) and with
``stand_in=False`` (every posterior evaluation an exact history).  For the selected slip condition's
posterior, the table gives the difference of the means and of the 2.5 / 97.5 % quantiles in units of the
plain run's posterior standard deviation (targets: means within 0.1, interval ends within 0.2), and the
CPU and wall seconds of each fit (the machine may be shared: CPU seconds are the steadier figure).
Two independent runs of the same sampler differ by their Monte-Carlo error too (about
sqrt(2) · sd / sqrt(ESS) for the means).

Usage: python benchmarks/bench_exact_stand_in.py [--curves displacement:no-slip:1 ...]
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
WORKER = r"""
import json, sys, time, resource
sys.path.insert(0, sys.argv[1])
import numpy as np
import adhfit
from tests.exact_curves import exact_curve, scene
control, slip, seed, stand = sys.argv[2], sys.argv[3], int(sys.argv[4]), sys.argv[5] == "1"
curve, truth = exact_curve(2.0, slip, noise=0.005, seed=seed, rows=330, control=control)
sc = scene(2.0, membrane="auto", control=control)
adhfit.fit(curve, sc, method="mcmc", seed=1, workers=2, progress=False, n_walkers=8, n_ensembles=2,
           tune_steps=5, max_steps=10, evidence_draws=20, predictive_draws=5, stand_in=stand)  # warm-up
t, c = time.perf_counter(), time.process_time()
r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
r = adhfit.fit(curve, sc, method="mcmc", seed=seed, workers=2, progress=False, stand_in=stand)
r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
cpu = time.process_time() - c + (r1.ru_utime + r1.ru_stime) - (r0.ru_utime + r0.ru_stime)
slip_rep = r.mcmc["model_probabilities"]["favoured"]
x = np.asarray(r.sampling["samples"][slip_rep])
names = r.sampling["summary"]["slips"][slip_rep]["parameters"]
out = {"wall_s": time.perf_counter() - t, "cpu_s": cpu, "membrane": r.model["membrane"], "slip": slip_rep,
       "selected": r.slip["selected"], "evaluations": r.n_evaluations,
       "stand_in": r.sampling["summary"]["slips"][slip_rep]["diagnostics"].get("exact_stand_in")}
for name in ("work_of_adhesion", "mu_h"):
    col = x[:, names.index(name)]
    out[name] = {"mean": float(col.mean()), "sd": float(col.std()), "lo": float(np.quantile(col, 0.025)),
                 "hi": float(np.quantile(col, 0.975)), "truth": truth[name]}
print("RESULT " + json.dumps(out))
"""


def run(control: str, slip: str, seed: int, stand: bool) -> dict:
    proc = subprocess.run([sys.executable, "-c", WORKER, str(ROOT), control, slip, str(seed), "1" if stand else "0"],
                          capture_output=True, text=True, cwd=ROOT)
    line = [ln for ln in proc.stdout.splitlines() if ln.startswith("RESULT ")]
    if not line:
        raise SystemExit(proc.stderr[-3000:])
    return json.loads(line[-1][7:])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--curves", nargs="+", default=["displacement:no-slip:1", "displacement:frictionless:2",
                                                    "pressure:no-slip:3", "pressure:frictionless:4"])
    ap.add_argument("--out", default=str(ROOT / "benchmarks" / "results" / "exact_stand_in"))
    args = ap.parse_args()
    load0 = ", ".join(f"{x:.2f}" for x in os.getloadavg())
    rev = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT, capture_output=True, text=True).stdout.strip()
    records = []
    for spec in args.curves:
        control, slip, seed = spec.split(":")
        stand, plain = run(control, slip, int(seed), True), run(control, slip, int(seed), False)
        records.append({"curve": spec, "stand_in": stand, "plain": plain})
        print(spec, json.dumps(records[-1])[:400], flush=True)
    lines = ["# MCMC with the exact membrane: the checked stand-in against a plain exact run", "",
             f"Command: `python benchmarks/bench_exact_stand_in.py {' '.join(sys.argv[1:])}`  ",
             f"Machine: python {platform.python_version()}, nproc {len(os.sched_getaffinity(0))}, revision {rev}, "
             f"load average at start {load0}, at end {', '.join(f'{x:.2f}' for x in os.getloadavg())}.", "",
             "Curves: tests/exact_curves.py at λ0 = 2, 330 rows, 0.5 % noise (control:slip:seed); default MCMC "
             "settings, two workers, membrane auto (chose the exact membrane in every run: column `membrane`). "
             "Differences of the stand-in's posterior from the plain exact run's, in units of the plain run's "
             "posterior standard deviation.", "",
             "| curve | membrane | Δ mean W_ad | Δ mean μh | Δ 2.5 % W_ad | Δ 97.5 % W_ad | Δ 2.5 % μh | Δ 97.5 % μh | "
             "check: sd ln(L_E/L_S), max dev (σ) | CPU s stand-in / plain | wall s stand-in / plain |",
             "|---|---|---:|---:|---:|---:|---:|---:|---|---:|---:|"]
    worst = {"mean": 0.0, "end": 0.0}
    for rec in records:
        s, p = rec["stand_in"], rec["plain"]
        d = {}
        for name in ("work_of_adhesion", "mu_h"):
            sd = p[name]["sd"]
            d[name] = {k: (s[name][k] - p[name][k]) / sd for k in ("mean", "lo", "hi")}
            worst["mean"] = max(worst["mean"], abs(d[name]["mean"]))
            worst["end"] = max(worst["end"], abs(d[name]["lo"]), abs(d[name]["hi"]))
        chk = s.get("stand_in") or {}
        lines.append(f"| {rec['curve']} | {s['membrane']} / {p['membrane']} | {d['work_of_adhesion']['mean']:+.3f} | "
                     f"{d['mu_h']['mean']:+.3f} | {d['work_of_adhesion']['lo']:+.3f} | {d['work_of_adhesion']['hi']:+.3f} | "
                     f"{d['mu_h']['lo']:+.3f} | {d['mu_h']['hi']:+.3f} | "
                     f"{chk.get('sd_log_ratio', float('nan')):.3f}, {chk.get('max_deviation_sigma', float('nan')):.3f}"
                     f"{'' if chk.get('passed', True) else ' (failed: exact run)'} | "
                     f"{s['cpu_s']:.1f} / {p['cpu_s']:.1f} | {s['wall_s']:.1f} / {p['wall_s']:.1f} |")
    cpu = [r["stand_in"]["cpu_s"] / r["plain"]["cpu_s"] for r in records]
    lines += ["", f"Largest |Δ mean| {worst['mean']:.3f} sd (target ≤ 0.1), largest |Δ interval end| "
              f"{worst['end']:.3f} sd (target ≤ 0.2); CPU time of the stand-in run over the plain run: "
              f"{min(cpu):.2f}-{max(cpu):.2f}."]
    Path(args.out).with_suffix(".json").write_text(json.dumps(records, indent=1))
    Path(args.out).with_suffix(".md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
