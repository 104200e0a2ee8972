"""Seeded replicate fits for the estimator work of issue 9: bias and coverage of W_ad and mu_h.

Usage: python benchmarks/trust_replicates.py NOISE N [CASE:SLIP ...] [--force-offset F] [--truncate K]
Prints one line per case: jump found, median bias, coverage of W_ad and mu_h, slip outcomes.
"""
from __future__ import annotations

import sys
import time

import numpy as np

from adhfit.fitting.api import fit as fit_curve
from adhfit.synthetic import synthetic_curve
from tests.test_recovery import CASES, TRUE


def run(case, slip, noise, n, force_offset=0.0, seed0=20_000):
    scene, x_max, off = CASES[case]
    rows = []
    for i in range(n):
        rng = np.random.default_rng(seed0 + i)
        curve, truth = synthetic_curve(scene, slip, **TRUE, x_max=x_max, x_offset=off, noise=noise, rng=rng)
        if force_offset:
            curve, truth = synthetic_curve(scene, slip, **TRUE, x_max=x_max, x_offset=off, noise=noise,
                                           rng=np.random.default_rng(seed0 + i),
                                           force_offset=force_offset * truth["sigma"] / noise)
        r = fit_curve(curve, scene, slip="auto")
        rec = {"sel": r.slip["selected"]}
        for name in TRUE:
            e = r.parameters[name]
            lo, hi = (e.ci95 if e.ci95 is not None else (None, None))
            lo = -np.inf if lo is None else lo
            hi = np.inf if hi is None else hi
            rec[name] = ((e.value or np.nan) / TRUE[name] - 1, lo <= TRUE[name] <= hi)
        rows.append(rec)
    return rows


def main():
    args = sys.argv[1:]
    fo = 0.0
    if "--force-offset" in args:
        k = args.index("--force-offset")
        fo = float(args[k + 1])
        del args[k:k + 2]
    noise, n = float(args[0]), int(args[1])
    combos = [a.split(":") for a in args[2:]] or [(c, s) for c in CASES for s in ("no-slip", "frictionless")]
    for case, slip in combos:
        t0 = time.perf_counter()
        rows = run(case, slip, noise, n, fo)
        out = [f"{case:18s} {slip:12s} noise={noise:.3f} n={n}"]
        for name in TRUE:
            b = np.array([r[name][0] for r in rows])
            c = np.mean([r[name][1] for r in rows])
            out.append(f"{name}: bias={np.nanmedian(b):+.3f} cov={c:.2f}")
        sel = [r["sel"] for r in rows]
        out.append(f"right={sum(s == slip for s in sel)} wrong={sum(s not in (slip, None) for s in sel)}")
        out.append(f"{time.perf_counter() - t0:.0f}s")
        print("  ".join(out), flush=True)


if __name__ == "__main__":
    main()
