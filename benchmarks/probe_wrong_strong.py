"""Wrong strong verdicts of verdict_calibration_strong: is the losing fit a stuck optimum?  Each curve
fitted with slip auto, then each slip alone; χ², detachment row and W_ad per fit.  Also a consistency
check of records made at 1abc506: refit and compare ΔBIC."""
import sys, json, tempfile
from pathlib import Path
sys.path.insert(0, "benchmarks")
import numpy as np, recovery, recovery_cases as rc
from adhfit.fitting import fit

def curve(case, slip, variant, noise, rep, seed=20261204):
    ss = recovery.seed_sequence(seed, case, slip, variant, noise, rep)
    p = Path(tempfile.mkdtemp()) / "c.csv"
    rc.make_curve(case, slip, noise, variant, np.random.default_rng(ss), p)
    return p

mode = sys.argv[1]  # "wrong" or "consistency"; run from the repository root with PYTHONPATH=.
if mode == "wrong":
    for case, slip, variant, noise, rep, seed in [("pressure-flat", "frictionless", "drift", 0.045, 0, 20261204),
                                                   ("pressure-flat", "frictionless", "clean", 0.035, 10, 20261204),
                                                   ("pressure-flat", "no-slip", "clean", 0.05, 23, 20261220)]:
        p = curve(case, slip, variant, noise, rep, seed)
        print(case, slip, variant, noise, rep, "seed", seed, flush=True)
        for s in ("auto", "no-slip", "frictionless"):
            d = fit(str(p), rc.CASES[case].scene, slip=s).as_dict()
            print("  slip=", s, d["slip"].get("verdict"))
            for k, f in d["fits"].items():
                print("    ", k, "chisqr %.2f" % f["chisqr"], "row", f["first_detached_row"],
                      "W %.4f muh %.4f" % (f["parameters"]["work_of_adhesion"]["value"], f["parameters"]["mu_h"]["value"]),
                      [x for x in f["diagnostics"] if "came from" in x or x.startswith("start")], flush=True)
else:
    recs = json.load(open("benchmarks/results/verdict_calibration_strong.json"))["records"]
    old = [r for r in recs if r["commit"] == "1abc506" and r["variant"] == "clean"][::29][:12]
    for r in old:
        p = curve(r["case"], r["slip"], r["variant"], r["noise"], r["rep"], r["seed"])
        d = fit(str(p), rc.CASES[r["case"]].scene, slip="auto").as_dict()["slip"]
        print(r["case"], r["slip"], r["noise"], r["rep"], "1abc506:", r["favoured"], r["evidence"], round(r["delta_bic"], 3),
              "now:", d["favoured"], d["evidence"], round(d["delta_bic"], 3), flush=True)
