"""Coverage of the MCMC 95 % intervals with the load-cell zero and drift integrated out (bayes/linear.py).

Each replicate draws a synthetic displacement-control curve (W_ad = 0.4 J/m², μh = 2 N/m, no-slip, 200 rows)
with a random displacement offset, load-cell zero and drift, fits it by MCMC with the slip imposed, and
records whether each 95 % interval (W_ad, μh, the zero, the drift) holds the truth.  Cells: force noise
0.5, 2 and 5 % of the peak force.  A coverage below the 1 % lower binomial quantile of Bin(n, 0.95) is
flagged ``!``.

Usage: ``python benchmarks/mcmc_linear_coverage.py --replicates 40 --workers 2 --out benchmarks/results/mcmc_linear_coverage``
"""
from __future__ import annotations

import argparse
import functools
import json
import platform
import subprocess
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np
from scipy import stats

TRUTH = {"work_of_adhesion": 0.4, "mu_h": 2.0}
NAMES = ("work_of_adhesion", "mu_h", "force_offset", "force_drift")


def replicate(job: tuple[float, int]) -> dict:
    noise, seed = job
    from adhfit.fitting.api import fit  # noqa: PLC0415
    from adhfit.scene import Scene  # noqa: PLC0415
    from adhfit.synthetic import synthetic_curve  # noqa: PLC0415
    scene = functools.partial(Scene, membrane_model="large-stretch")(
        membrane_radius="2 mm", substrate_radius="1 mm", control="displacement", pressure="1.2 kPa", slip="no-slip")
    rng = np.random.default_rng(seed)
    peak = 1.6e-3  # ~ the peak force of this scene at x_max = 6e-4 m, N
    truth = dict(TRUTH, force_offset=float(rng.uniform(-0.03, 0.03)) * peak,
                 force_drift=float(rng.uniform(-0.03, 0.03)) * peak)
    curve, _ = synthetic_curve(scene, "no-slip", x_max=6e-4, rows=200, noise=noise,
                               x_offset=float(rng.uniform(-3e-5, 3e-5)), force_offset=truth["force_offset"],
                               force_drift=truth["force_drift"], approach=0.2, tail=0.25, rng=rng, **TRUTH)
    t = time.perf_counter()
    res = fit(curve, scene, method="mcmc", seed=seed, workers=1, progress=False)
    out = {"noise": noise, "seed": seed, "seconds": time.perf_counter() - t, "converged": bool(res.converged),
           "integrated_out": res.mcmc["slips"]["no-slip"]["integrated_out"],
           "evaluations": res.mcmc["slips"]["no-slip"]["posterior_evaluations"]}
    for name in NAMES:
        e = res.parameters.get(name)
        ci = None if e is None or e.ci95 is None or None in e.ci95 else [float(v) for v in e.ci95]
        out[name] = {"truth": truth[name], "ci95": ci, "value": None if e is None else float(e.value)}
    return out


def table(rows: list[dict]) -> str:
    lines = ["| noise % | n | converged | integrated out | evaluations (median) | "
             + " | ".join(f"{n} coverage" for n in NAMES) + " |", "|---" * (5 + len(NAMES)) + "|"]
    for noise in sorted({r["noise"] for r in rows}):
        cell = [r for r in rows if r["noise"] == noise]
        cov = []
        for name in NAMES:
            claims = [r[name] for r in cell if r[name]["ci95"] is not None]
            k = sum(c["ci95"][0] <= c["truth"] <= c["ci95"][1] for c in claims)
            low = k < stats.binom.ppf(0.01, len(claims), 0.95) if claims else False
            cov.append(f"{k / max(len(claims), 1):.2f} ({k}/{len(claims)}){' !' if low else ''}")
        integ = sum(bool(r["integrated_out"]) for r in cell)
        ev = int(np.median([r["evaluations"] for r in cell]))
        lines.append(f"| {noise * 100:g} | {len(cell)} | {sum(r['converged'] for r in cell)} | {integ} | {ev} | "
                     + " | ".join(cov) + " |")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--replicates", type=int, default=40)
    ap.add_argument("--noise", type=float, nargs="+", default=[0.005, 0.02, 0.05])
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--seed", type=int, default=20261204)
    ap.add_argument("--out", default="benchmarks/results/mcmc_linear_coverage")
    a = ap.parse_args(argv)
    jobs = [(n, a.seed + 1000 * i + k) for i, n in enumerate(a.noise) for k in range(a.replicates)]
    t = time.perf_counter()
    with ProcessPoolExecutor(a.workers) as ex:
        rows = list(ex.map(replicate, jobs))
    wall = time.perf_counter() - t
    rev = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True).stdout.strip()
    cmd = "python " + " ".join([Path(sys.argv[0]).as_posix()] + (argv if argv is not None else sys.argv[1:]))
    md = (f"# MCMC coverage with the load-cell zero and drift integrated out\n\nCommand: `{cmd}`  \n"
          f"adhfit {rev}, {len(rows)} fits in {wall:.0f} s on {a.workers} workers, Python "
          f"{platform.python_version()}.\n\n{__doc__.split(chr(10), 1)[1].split('Usage')[0].strip()}\n\n"
          f"{table(rows)}\n")
    Path(a.out + ".md").write_text(md, encoding="utf-8")
    Path(a.out + ".json").write_text(json.dumps(rows, indent=1), encoding="utf-8")
    print(md)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
