"""Issue 20, replicates_20.md: the early-detachment optimum of displacement-curved / frictionless / 5 % /
rep 6 (root seed 20261220), fitted with slip auto, frictionless and no-slip (run from the repository root,
``PYTHONPATH=. python benchmarks/probe_early_detachment.py``)."""
import sys, json, tempfile
from pathlib import Path
sys.path.insert(0, "benchmarks")
import numpy as np, recovery, recovery_cases as rc
from adhfit.fitting import fit
case, slip, noise, rep = "displacement-curved", "frictionless", 0.05, 6
ss = recovery.seed_sequence(20261220, case, slip, "clean", noise, rep)
p = Path(tempfile.mkdtemp()) / "rep6.csv"
truth = rc.make_curve(case, slip, noise, "clean", np.random.default_rng(ss), p)
sc = rc.CASES[case].scene
for s in ("auto", "frictionless", "no-slip"):
    d = fit(str(p), sc, slip=s).as_dict()
    print("slip=", s, d["slip"].get("verdict"), d["slip"].get("delta_bic"))
    for k, f in d["fits"].items():
        print("  ", k, "chisqr %.2f" % f["chisqr"], "sigma %.3g" % f["sigma"], "row", f["first_detached_row"],
              "W %.4f muh %.4f" % (f["parameters"]["work_of_adhesion"]["value"], f["parameters"]["mu_h"]["value"]),
              [x for x in f["diagnostics"] if "came from" in x or "start" in x][:6])
