"""Cost of fits with the exact membrane: one least-squares fit and one short MCMC (issue 11 item 5).

An exact curve (tests/exact_curves.py: lambda0 = 1.5, frictionless, 0.5 % noise, seed 1, 240 rows,
displacement control) is fitted with ``membrane = "exact"`` and the slip condition given:

- least squares: ``fit_curve`` with default settings;
- MCMC: ``fit_curve_mcmc`` with 2 ensembles of 8 walkers, at most 100 steps, one worker.

Each in a fresh subprocess after a warm-up fit (kernels compiled or loaded), CPU seconds
(process_time) of the measured fit and the number of exact histories it computed.  With
``--baseline REV`` the same for git revision REV's engine (``git archive`` into a temporary
directory), alternating.

Usage::

    python benchmarks/bench_exact_mcmc.py [--baseline REV]

Writes ``benchmarks/results/exact_mcmc.md`` and ``exact_mcmc.json``.
"""
from __future__ import annotations

import argparse
import json
import os
import platform
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

_WORKER = """
import json, sys, time
sys.path.insert(0, sys.argv[1])
from adhfit.exact import history as H
import adhfit.exact as E
from adhfit.fitting.api import fit as fit_curve
from functools import partial
from adhfit.fitting.api import fit
fit_curve_mcmc = partial(fit, method="mcmc")
from tests.exact_curves import exact_curve, scene
count = {"n": 0}
orig = H.exact_history
def counted(*a, **k):
    count["n"] += 1
    return orig(*a, **k)
H.exact_history = E.exact_history = counted
curve, truth = exact_curve(1.5, "frictionless", noise=0.005, seed=1)
sc = scene(1.5, membrane="exact")
short = dict(n_walkers=8, n_ensembles=2, max_steps=100)
fit_curve(curve, sc, slip="frictionless")
fit_curve_mcmc(curve, sc, slip="frictionless", seed=1, workers=1, progress=False, n_walkers=8, n_ensembles=2,
               tune_steps=10, max_steps=20, evidence_draws=20, predictive_draws=10)
out = {}
for name, run in (("lsq", lambda: fit_curve(curve, sc, slip="frictionless")),
                  ("mcmc", lambda: fit_curve_mcmc(curve, sc, slip="frictionless", seed=1, workers=1,
                                                  progress=False, **short))):
    count["n"] = 0
    t, c = time.perf_counter(), time.process_time()
    res = run()
    out[name] = {"cpu_s": time.process_time() - c, "wall_s": time.perf_counter() - t, "exact_histories": count["n"],
                 "W_err": res.parameters["work_of_adhesion"].value / truth["work_of_adhesion"] - 1,
                 "mu_err": res.parameters["mu_h"].value / truth["mu_h"] - 1}
print(json.dumps(out))
"""


def _run(tree: Path) -> dict:
    env = {**os.environ, "PYTHONPATH": str(tree)}
    out = subprocess.run([sys.executable, "-c", _WORKER, str(tree)], env=env, cwd=tree, capture_output=True,
                         text=True, check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--baseline", default=None, help="git revision to time against")
    args = ap.parse_args()
    load0 = os.getloadavg()
    trees = [("this tree", ROOT)]
    if args.baseline:
        tmp = Path(tempfile.mkdtemp(prefix="bench_exact_mcmc_"))
        arch = subprocess.run(["git", "archive", args.baseline, "adhfit", "tests"], cwd=ROOT, capture_output=True,
                              check=True).stdout
        subprocess.run(["tar", "xf", "-", "-C", str(tmp)], input=arch, check=True)
        trees.insert(0, (args.baseline, tmp))
    res = {name: _run(tree) for name, tree in trees}
    rev = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT, capture_output=True, text=True).stdout.strip()
    cmd = "python benchmarks/bench_exact_mcmc.py" + (f" --baseline {args.baseline}" if args.baseline else "")
    meta = {"command": cmd, "commit": rev, "python": platform.python_version(), "nproc": os.cpu_count(),
            "load_start": load0, "load_end": os.getloadavg()}
    out = ROOT / "benchmarks" / "results"
    (out / "exact_mcmc.json").write_text(json.dumps({"meta": meta, "results": res}, indent=1))
    lines = ["# Fits with the exact membrane: cost per fit", "",
             f"Command: `{cmd}` at {rev}; python {meta['python']}, nproc {meta['nproc']}, load average at start "
             f"{load0[0]:.2f}, at end {meta['load_end'][0]:.2f}.", "",
             "Exact curve lambda0 = 1.5, frictionless, 0.5 % noise (tests/exact_curves.py), membrane = exact, slip "
             "given. Least squares: default settings. MCMC: 2 ensembles x 8 walkers, at most 100 steps, one "
             "worker. CPU seconds of one fit after a warm-up fit, in a fresh process per engine; the per-history "
             "column divides the whole fit (its large-stretch start included) by the exact histories.", "",
             "| engine | fit | CPU s | wall s | exact histories | CPU ms / exact history (whole fit) | W_ad err | μh err |",
             "|---|---|---:|---:|---:|---:|---:|---:|"]
    for name, r in res.items():
        for kind in ("lsq", "mcmc"):
            q = r[kind]
            per = 1e3 * q["cpu_s"] / max(q["exact_histories"], 1)
            lines.append(f"| {name} | {kind} | {q['cpu_s']:.1f} | {q['wall_s']:.1f} | {q['exact_histories']} | "
                         f"{per:.1f} | {100 * q['W_err']:+.3f} % | {100 * q['mu_err']:+.3f} % |")
    (out / "exact_mcmc.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
