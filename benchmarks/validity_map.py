"""Validity map of the large-stretch approximation against the exact neo-Hookean membrane (issue 11).

Over (lambda0, p), displacement control, w = 0.2, rs = 0.5, a_max = 0.25, both slip conditions: the
relative error (approximation - exact)/|exact| of the force at the end of loading (f_max), of the
pull-off force (f_min) and of the free apex deflection d0, and the absolute error of the
displacement at the turning point.

Usage::

    python benchmarks/validity_map.py

Writes ``benchmarks/results/validity_map.md``, ``validity_map.json`` and ``validity_map.png``.
"""
from __future__ import annotations

import json
import math
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import matplotlib  # noqa: E402

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from adhfit import simulate  # noqa: E402
from adhfit.errors import AdhfitError  # noqa: E402
from adhfit.exact.history import exact_history  # noqa: E402
from adhfit.exact.inflation import free_inflation  # noqa: E402

LAMBDAS = (1.1, 1.2, 1.3, 1.5, 2.0, 3.0, 5.0)
PRESSURES = (0.2, 0.4, 0.6, 0.8)
BASE = {"w": 0.2, "rs": 0.5, "a_max": 0.25}


def _case(slip, lam0, p):
    ls = simulate("displacement", slip, p=p, **BASE).summary
    try:
        ex = exact_history("displacement", slip, p=p, lambda0=lam0, points=60, **BASE).summary
    except AdhfitError as exc:
        return {"error": str(exc)}
    rel = lambda a, b: (a - b) / abs(b)  # noqa: E731
    d0_ls = p / (1 + math.sqrt(1 - p * p))
    d0_ex = free_inflation(p, lam0).d
    return {"f_max": rel(ls["f_max"], ex["f_max"]), "f_min": rel(ls["f_min"]["f"], ex["f_min"]["f"]),
            "d0": rel(d0_ls, d0_ex),
            "turn_delta": ls["turning_point"]["delta"] - ex["turning_point"]["delta"]}


def main() -> None:
    res = {slip: {f"{l}/{p}": _case(slip, l, p) for l in LAMBDAS for p in PRESSURES}
           for slip in ("frictionless", "no-slip")}
    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT, capture_output=True,
                            text=True).stdout.strip()
    out = ROOT / "benchmarks" / "results"
    (out / "validity_map.json").write_text(json.dumps({"commit": commit, "base": BASE, "results": res}, indent=1))
    lines = ["# Validity map: large-stretch approximation against the exact membrane", "",
             f"Command: `python benchmarks/validity_map.py` at {commit}. Displacement control, w = 0.2, "
             "rs = 0.5, a_max = 0.25. Entries: (approximation - exact)/|exact| in percent for the force at "
             "the end of loading f_max, the pull-off force f_min and the free apex deflection d0; "
             "'—' where the exact membrane has no Case I state.", ""]
    for slip, r in res.items():
        for key, label in (("f_max", "f_max"), ("f_min", "pull-off f_min"), ("d0", "apex deflection d0")):
            lines += [f"## {slip}: {label}", "", "| lambda0 \\ p | " + " | ".join(map(str, PRESSURES)) + " |",
                      "|---|" + "---:|" * len(PRESSURES)]
            for lam in LAMBDAS:
                cells = []
                for p in PRESSURES:
                    c = r[f"{lam}/{p}"]
                    cells.append("—" if "error" in c else f"{100 * c[key]:+.2f}")
                lines.append(f"| {lam} | " + " | ".join(cells) + " |")
            lines.append("")
    lines.append("![validity map](validity_map.png)")
    (out / "validity_map.md").write_text("\n".join(lines) + "\n")
    _plot(res, out / "validity_map.png")
    print("\n".join(lines))


def _plot(res, path):
    fig, axes = plt.subplots(1, 3, figsize=(13, 4), constrained_layout=True)
    for ax, (slip, key, title) in zip(axes, (("frictionless", "f_max", "f_max (both slips)"),
                                             ("frictionless", "f_min", "pull-off f_min, frictionless"),
                                             ("no-slip", "f_min", "pull-off f_min, no slip"))):
        for p in PRESSURES:
            ys = [abs(res[slip][f"{l}/{p}"].get(key, np.nan)) * 100 for l in LAMBDAS]
            ax.loglog(LAMBDAS, ys, "o-", label=f"p = {p}")
        ax.set_xlabel("pre-stretch lambda0")
        ax.set_ylabel("|approximation error| (%)")
        ax.set_title(title)
        ax.grid(True, which="both", alpha=0.3)
    axes[0].legend()
    fig.savefig(path, dpi=110)


if __name__ == "__main__":
    main()
