"""MCMC with the load-cell zero and drift integrated out (bayes/linear.py) against sampling every coordinate.

Same code, same seeds; the only difference is whether :meth:`adhfit.fitting.bayes.linear.Marginal.of` is
allowed to integrate.  Cases: the bundled sample curve (one curve, both slip conditions) and a synthetic
three-pressure series (1 % noise, load-cell zeros per curve).  Reported per case: posterior evaluations,
CPU seconds of the whole fit, and the reported W_ad and μh with their 95 % intervals, so that the two
posteriors can be compared (they must agree within Monte-Carlo error).

Usage: ``python benchmarks/bench_mcmc_linear.py --out benchmarks/results/mcmc_linear``
"""
from __future__ import annotations

import argparse
import functools
import json
import os
import platform
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
SAMPLE = ROOT / "sample_data" / "fea_displacement_no-slip"


def _series():
    from adhfit.scene import Scene  # noqa: PLC0415
    from adhfit.synthetic import synthetic_curve  # noqa: PLC0415
    scenes, curves = [], []
    for i, p in enumerate(("0.8 kPa", "1.2 kPa", "1.8 kPa")):
        sc = functools.partial(Scene, membrane_model="large-stretch")(
            membrane_radius="2 mm", substrate_radius="1 mm", control="displacement", pressure=p, slip="auto")
        c, _ = synthetic_curve(sc, "no-slip", work_of_adhesion=0.4, mu_h=2.0, x_max=5e-4, rows=120, noise=0.01,
                               force_offset=2e-6 * (i - 1), rng=np.random.default_rng(10 + i))
        scenes.append(sc)
        curves.append(c)
    return curves, scenes


def run(case: str, integrate: bool) -> dict:
    import adhfit  # noqa: PLC0415
    from adhfit.fitting.bayes import linear  # noqa: PLC0415
    if not integrate:
        linear.Marginal.of = classmethod(lambda cls, *a, **k: None)
    data, scene = ((str(SAMPLE / "curve.csv"), str(SAMPLE / "scene.toml")) if case == "sample curve"
                   else _series())
    c0, t0 = time.process_time(), time.perf_counter()
    r = adhfit.fit(data, scene, method="mcmc", seed=1, workers=1, progress=False)
    out = {"case": case, "integrate": integrate, "cpu_s": time.process_time() - c0,
           "wall_s": time.perf_counter() - t0,
           "evaluations": sum(v["posterior_evaluations"] for v in r.mcmc["slips"].values()),
           "walkers": {s: v["diagnostics"]["n_walkers"] for s, v in r.mcmc["slips"].items()},
           "steps": {s: v["diagnostics"]["steps"] for s, v in r.mcmc["slips"].items()},
           "converged": bool(r.converged), "verdict": r.slip["verdict"]}
    for k in ("work_of_adhesion", "mu_h"):
        e = r.parameters[k]
        out[k] = {"value": e.value, "ci95": list(e.ci95) if e.ci95 else None}
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--out", default="benchmarks/results/mcmc_linear")
    ap.add_argument("--one", nargs=2, metavar=("CASE", "INTEGRATE"), help=argparse.SUPPRESS)
    a = ap.parse_args(argv)
    if a.one:
        print(json.dumps(run(a.one[0], a.one[1] == "1")))
        return 0
    rows = []
    for case in ("sample curve", "three-pressure series"):
        for integrate in (True, False):  # each in a fresh process: the same warm caches, no shared state
            p = subprocess.run([sys.executable, __file__, "--one", case, "1" if integrate else "0"],
                               capture_output=True, text=True, check=True,
                               env=os.environ | {"MPLBACKEND": "Agg", "PYTHONPATH": str(ROOT)})
            rows.append(json.loads(p.stdout.strip().splitlines()[-1]))
    rev = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True, cwd=ROOT).stdout.strip()
    load = os.getloadavg()
    cmd = "python " + " ".join([Path(sys.argv[0]).as_posix()] + (argv if argv is not None else sys.argv[1:]))
    lines = [f"# MCMC: the load-cell zero and drift integrated out, or sampled\n\nCommand: `{cmd}`  \nadhfit {rev}, "
             f"Python {platform.python_version()}, one worker per fit, load average at the end "
             f"{load[0]:.1f}, {load[1]:.1f}, {load[2]:.1f}.\n\n{__doc__.split(chr(10), 1)[1].split('Usage')[0].strip()}\n",
             "| case | zero and drift | evaluations | CPU s | walkers | steps | converged | W_ad [95 %] | μh [95 %] |",
             "|---|---|---:|---:|---|---|---|---|---|"]
    for r in rows:
        w, m = r["work_of_adhesion"], r["mu_h"]
        lines.append(f"| {r['case']} | {'integrated out' if r['integrate'] else 'sampled'} | {r['evaluations']} | "
                     f"{r['cpu_s']:.1f} | {r['walkers']} | {r['steps']} | {r['converged']} | "
                     f"{w['value']:.4f} [{w['ci95'][0]:.4f}, {w['ci95'][1]:.4f}] | "
                     f"{m['value']:.4f} [{m['ci95'][0]:.4f}, {m['ci95'][1]:.4f}] |")
    md = "\n".join(lines) + "\n"
    Path(a.out + ".md").write_text(md, encoding="utf-8")
    Path(a.out + ".json").write_text(json.dumps(rows, indent=1), encoding="utf-8")
    print(md)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
