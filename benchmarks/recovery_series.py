"""Recovery study of the global fit (issue 13): series of 3 curves of one membrane (0.8, 1.2, 1.6 kPa).

For each replicate one seeded series is generated (adhfit.synthetic.synthetic_series: 1 or 2 % force
noise, contact radius with 1 % of its largest value) and fitted twice with ``fit_global``: with the
contact radius and without it (the same force rows).  Reported per (truth slip, noise, observables):
median and worst relative error of W_ad and mu_h, coverage of their 95 % intervals, how often the
right slip is selected / the wrong one selected / undecided, the median relative W_ad interval width,
and for comparison the best single-curve W_ad interval width of the same curves.

Usage: python benchmarks/recovery_series.py N [--noise 0.01,0.02] [--slips no-slip,frictionless]
           [--profile] [--workers 2] [--distinct-seeds] [--drop-fold-rows K]
           [-o benchmarks/results/recovery_series.md]

Replicates run in order (replicate 0 of every cell, then replicate 1, ...), so a partial run (the
table is rewritten after every series) is balanced over the cells.
"""
from __future__ import annotations

import argparse
import dataclasses
import json
import multiprocessing
import subprocess
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

from adhfit.fitting.api import fit as fit_global
from adhfit.synthetic import synthetic_series
from adhfit.scene import load_scene

SCENE = Path(__file__).resolve().parents[1] / "sample_data" / "fea_displacement_no-slip" / "scene.toml"
TRUE = {"work_of_adhesion": 0.4, "mu_h": 2.0}
PRESSURES = (800.0, 1200.0, 1600.0)


def _drop_fold_rows(curve, i_jump: int, k: int):
    """The curve without its last ``k`` attached rows before pull-off (the rows next to the fold)."""
    keep = np.ones(len(curve.x), bool)
    keep[max(i_jump - k, curve.i_turn + 1):i_jump] = False
    cols = {n: np.asarray(getattr(curve, n))[keep] for n in ("x", "force", "line")}
    if curve.contact_radius is not None:
        cols["contact_radius"] = np.asarray(curve.contact_radius)[keep]
    return dataclasses.replace(curve, **cols)


def one(slip: str, noise: float, seed: int, profile: bool, drop_fold_rows: int = 0) -> list[dict]:
    scene = load_scene(SCENE)
    series = synthetic_series(scene, slip, pressures=PRESSURES, **TRUE, x_max=6e-4, noise=noise,
                              radius_noise=0.01, rng=np.random.default_rng(seed))
    curves, scenes = [c for c, _, _ in series], [s for _, s, _ in series]
    if drop_fold_rows:
        curves = [_drop_fold_rows(c, t["i_jump"], drop_fold_rows) for c, _, t in series]
    out = []
    for radius in (True, False):
        t0 = time.perf_counter()
        r = fit_global(curves, scenes, contact_radius=radius, profile=profile)
        rec = {"slip": slip, "noise": noise, "seed": seed, "radius": radius, "drop_fold_rows": drop_fold_rows, "selected": r.slip["selected"],
               "delta_bic": r.slip["delta_bic"], "favoured": r.slip["favoured"], "seconds": time.perf_counter() - t0}
        for name, true in TRUE.items():
            e = r.parameters[name]
            lo, hi = e.ci95 if e.ci95 is not None else (None, None)
            se = e.stderr if e.stderr else None
            rec[name] = {"rel_error": e.value / true - 1.0, "status": e.status, "value": e.value, "stderr": se,
                         "z": None if se is None else (e.value - true) / se,
                         "covered": (lo is None or lo <= true) and (hi is None or true <= hi) and e.status != "undetermined",
                         "rel_width": None if lo is None or hi is None else (hi - lo) / e.value}
            cov = e.ci95_covariance
            rec[name]["covered_covariance"] = None if cov is None else bool(cov[0] <= true <= cov[1])
        widths = [(c["alone"]["work_of_adhesion"]["ci95"][1] - c["alone"]["work_of_adhesion"]["ci95"][0])
                  / c["alone"]["work_of_adhesion"]["optimum"] for c in r.curves
                  if c["alone"]["work_of_adhesion"]["ci95"] and None not in c["alone"]["work_of_adhesion"]["ci95"]]
        rec["best_single_rel_width"] = min(widths) if widths else None
        rec["flags"] = sum(bool(c["flags"]) for c in r.curves)
        out.append(rec)
    return out


def _one(job: tuple) -> list[dict]:
    return one(*job)


def _z(g: list[dict], name: str) -> str:
    z = np.array([r[name]["z"] for r in g if r[name].get("z") is not None])
    return "–" if z.size < 2 else f"{z.mean():+.2f} ± {z.std(ddof=1) / np.sqrt(z.size):.2f} ({z.std(ddof=1):.2f})"


def pooled(rows: list[dict]) -> str:
    """Coverage and z = (estimate - truth)/stderr pooled per observables: a bias shows as a mean z away
    from 0 (± its standard error), intervals too narrow as an sd of z above 1 and coverage below 95 %
    (``!``: below the 1 % binomial quantile); with ``--profile`` also the covariance intervals' coverage."""
    from scipy import stats  # noqa: PLC0415
    cov = any(r["work_of_adhesion"].get("covered_covariance") is not None for r in rows)
    lines = ["| observables | n | W_ad cover | W_ad z: mean ± se (sd) | μh cover | μh z: mean ± se (sd) |"
             + (" W_ad cover (covariance) | μh cover (covariance) |" if cov else ""),
             "|---|---|---|---|---|---|" + ("---|---|" if cov else "")]
    for radius in (True, False):
        g = [r for r in rows if r["radius"] == radius and "z" in r["work_of_adhesion"]]
        if not g:
            continue
        cells = []
        for name in TRUE:
            k = sum(r[name]["covered"] for r in g)
            low = stats.binom.ppf(0.01, len(g), 0.95)
            cells += [f"{k}/{len(g)} ({100 * k / len(g):.0f} %){' !' if k < low else ''}", _z(g, name)]
        if cov:
            for name in TRUE:
                k = sum(bool(r[name].get("covered_covariance")) for r in g)
                cells.append(f"{k}/{len(g)} ({100 * k / len(g):.0f} %)")
        lines.append(f"| {'force + contact radius' if radius else 'force'} | {len(g)} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def table(rows: list[dict]) -> str:
    lines = ["| truth | noise | observables | n | W_ad median err | W_ad worst | W_ad cover | μh median err | "
             "μh cover | right slip | wrong | undecided | W_ad 95 % width (median) | best single width | curves flagged |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    keys = sorted({(r["slip"], r["noise"], r["radius"]) for r in rows}, key=lambda k: (k[0], k[1], not k[2]))
    for slip, noise, radius in keys:
        g = [r for r in rows if (r["slip"], r["noise"], r["radius"]) == (slip, noise, radius)]
        we = np.array([r["work_of_adhesion"]["rel_error"] for r in g])
        me = np.array([r["mu_h"]["rel_error"] for r in g])
        wid = [r["work_of_adhesion"]["rel_width"] for r in g if r["work_of_adhesion"]["rel_width"] is not None]
        single = [r["best_single_rel_width"] for r in g if r["best_single_rel_width"] is not None]
        right = sum(r["selected"] == slip for r in g)
        wrong = sum(r["selected"] not in (None, slip) for r in g)
        lines.append(
            f"| {slip} | {100 * noise:g} % | {'force + contact radius' if radius else 'force'} | {len(g)} | "
            f"{100 * np.median(we):+.2f} % | {100 * we[np.argmax(np.abs(we))]:+.2f} % | "
            f"{sum(r['work_of_adhesion']['covered'] for r in g)}/{len(g)} | {100 * np.median(me):+.2f} % | "
            f"{sum(r['mu_h']['covered'] for r in g)}/{len(g)} | {right}/{len(g)} | {wrong} | {len(g) - right - wrong} | "
            f"{100 * np.median(wid):.2f} % | {100 * np.median(single):.2f} % | {sum(r['flags'] for r in g)} |")
    return "\n".join(lines)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("n", type=int)
    ap.add_argument("--noise", default="0.01,0.02")
    ap.add_argument("--slips", default="no-slip,frictionless")
    ap.add_argument("--profile", action="store_true")
    ap.add_argument("--seed0", type=int, default=13_000)
    ap.add_argument("--workers", type=int, default=1)
    ap.add_argument("--distinct-seeds", action="store_true", help="seeds seed0 + 1000·cell + i (independent cells)")
    ap.add_argument("--drop-fold-rows", type=int, default=0,
                    help="leave out each curve's last K attached rows before pull-off (the fold experiment)")
    ap.add_argument("-o", "--output", type=Path, default=None)
    ap.add_argument("--from-json", type=Path, default=None, help="re-render the tables of a finished run")
    args = ap.parse_args(argv)
    if args.from_json is not None:
        rows = json.loads(args.from_json.read_text(encoding="utf-8"))
        print(table(rows) + "\n\n" + pooled(rows))
        return 0
    rows = []
    # every (slip, noise) cell its own seeds: with one seed list the cells share their noise draws
    # (scaled), and a replicate that misleads one cell misleads all four
    cells = [(slip, noise) for slip in args.slips.split(",") for noise in map(float, args.noise.split(","))]
    plan = [(slip, noise, args.seed0 + i + (1000 * c if args.distinct_seeds else 0), args.profile, args.drop_fold_rows)
            for i in range(args.n) for c, (slip, noise) in enumerate(cells)]
    pool = ProcessPoolExecutor(args.workers, mp_context=multiprocessing.get_context("fork")) \
        if args.workers > 1 else None
    results = pool.map(_one, plan) if pool is not None else map(_one, plan)
    for got in results:
        rows += got
        print(json.dumps(got, default=str), file=sys.stderr, flush=True)
        _write(args, argv, rows)  # after every series: a long run leaves its partial table
    if pool is not None:
        pool.shutdown()
    print(table(rows))
    return 0


def _write(args, argv, rows) -> None:
    if args.output is None:
        return
    cmd = "python benchmarks/recovery_series.py " + " ".join(argv if argv is not None else sys.argv[1:])
    secs = np.median([r["seconds"] for r in rows])
    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True,
                            cwd=Path(__file__).parent).stdout.strip()
    args.output.write_text(f"# Recovery of series fits (issue 13)\n\nCommand: `PYTHONPATH=. {cmd}`\n\n"
                           f"{__doc__.split(chr(10) + chr(10))[1]}\n\n{table(rows)}\n\n{pooled(rows)}\n\nIntervals: "
                           f"{'likelihood profile' if args.profile else 'covariance'}; median wall time per "
                           f"global fit {secs:.0f} s (2 shared cores, loaded); commit {commit}.\n", encoding="utf-8")
    args.output.with_suffix(".json").write_text(json.dumps(rows, indent=1, default=str), encoding="utf-8")


if __name__ == "__main__":
    sys.exit(main())
