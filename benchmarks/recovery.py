"""Recovery study: how often adhfit's intervals hold the truth, on tests that look like real ones.

Seeded replicate curves from the forward model (``recovery_cases.py``: noise, an un-tared load cell,
tests stopped early, duplicated rows — added here, not by the fitting code) are written to CSV and
fitted as a user would (``fit_curve(path, scene)`` with default options, both slip conditions
compared).  Per cell (case x true slip x variant x noise) the study reports bias and scatter of W_ad
and μh, coverage of each reported 95 % interval or one-sided bound, the count of each ``status``,
and the slip outcome (right / wrong / undecided).  Every replicate has its own seed:
``SeedSequence(--seed, spawn_key=(case, slip, variant, noise in 1e-4, replicate))``, so a replicate's
curve does not depend on which other cells run or on the worker count.

Usage (from the repository root)::

    python benchmarks/recovery.py [--replicates 20] [--replicates-other 4] [--noise 0.002 ...]
        [--headline-noise 0.02 0.04] [--variant-noise 0.02] [--cases displacement-curved ...]
        [--slips no-slip frictionless] [--variants clean baseline ...] [--seed 20261201]
        [--method {lsq,mcmc}] [--workers 2 | --scheduler ADDRESS] [--out benchmarks/results/recovery]

Writes ``OUT.json`` (every replicate and every cell), ``OUT.md`` (tables, the command) and ``OUT.png``.
"""
from __future__ import annotations

import argparse
import json
import os
import platform
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))

import recovery_cases as rc  # noqa: E402
import recovery_stats as rs  # noqa: E402
from recovery_report import write_markdown  # noqa: E402

#: MCMC settings of the study: shorter than the CLI's defaults (cost), long enough for stable percentiles
MCMC_SETTINGS = {"n_walkers": 8, "n_ensembles": 2, "tune_steps": 10, "max_steps": 120, "predictive_draws": 4}


def seed_sequence(root: int, case: str, slip: str, variant: str, noise: float, rep: int) -> np.random.SeedSequence:
    """The replicate's own seed (indices into the global tuples, so selections do not shift it)."""
    key = (list(rc.CASES).index(case), rc.SLIPS.index(slip), rc.VARIANTS.index(variant),
           int(round(noise * 1e4)), rep)
    return np.random.SeedSequence(root, spawn_key=key)


def plan(args) -> list[dict]:
    """Every replicate to run: clean at every noise level, other variants at ``--variant-noise``.

    Clean cells at a ``--headline-noise`` level get ``--replicates``; every other cell
    ``--replicates-other``.
    """
    jobs = []
    for case in args.cases:
        for slip in args.slips:
            for variant in args.variants:
                if not rc.applicable(case, slip, variant):
                    continue
                noises = args.noise if variant == "clean" else args.variant_noise
                for noise in noises:
                    head = variant == "clean" and any(abs(noise - h) < 1e-12 for h in args.headline_noise)
                    n = args.replicates if head else args.replicates_other
                    jobs += [{"case": case, "slip": slip, "variant": variant, "noise": noise, "rep": k,
                              "seed": args.seed, "method": args.method, "_order": k / n} for k in range(n)]
    # every cell advances in proportion to its replicate count: any prefix of the run is balanced
    jobs.sort(key=lambda j: j["_order"])
    for j in jobs:
        del j["_order"]
    return jobs


def _fit(path: Path, scene, method: str, seed: int) -> dict:
    from adhfit.fitting import fit  # noqa: PLC0415
    if method == "lsq":
        return fit(str(path), scene, slip="auto").as_dict()
    return fit(str(path), scene, method="mcmc", slip="auto", seed=seed, workers=1, progress=False,
               **MCMC_SETTINGS).as_dict()


def run_one(job: dict) -> dict:
    """Make, write and fit one replicate; what the report says against the truth."""
    ss = seed_sequence(job["seed"], job["case"], job["slip"], job["variant"], job["noise"], job["rep"])
    rng = np.random.default_rng(ss)
    rec = dict(job, spawn_key=list(ss.spawn_key), error=None)
    scene = rc.CASES[job["case"]].scene
    t0 = time.perf_counter()
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "curve.csv"
        truth = rec["truth"] = rc.make_curve(job["case"], job["slip"], job["noise"], job["variant"], rng, path)
        jump = _data_jump(path, truth)
        try:
            rep = _fit(path, scene, job["method"], int(ss.generate_state(1)[0]))
        except Exception as err:  # noqa: BLE001 - the study counts every failure, whatever its kind
            rep = None
            rec["error"] = f"{type(err).__name__}: {err}"[:300]
    rec["wall_s"] = time.perf_counter() - t0
    for name in rs.PARAMS:
        rec[name] = (rs.judge(rep["parameters"][name], truth[name]) if rep else
                     {"status": "error", "value": None, "lo": None, "hi": None, "covered": None, "rel_err": None})
    slip = (rep or {}).get("slip", {})
    rec["selected"] = slip.get("selected")
    rec["slip_outcome"] = rs.outcome(slip.get("selected"), job["slip"]) if rep else "error"
    rec["delta_bic"] = slip.get("delta_bic")
    rec["warnings"] = list((rep or {}).get("warnings", []))
    rec["warned_duplicates"] = any("duplicat" in w.lower() for w in rec["warnings"])
    rec.update(_verdict_and_fits(rep, truth, jump) if rep else {})
    return rec


_CAME_FROM = re.compile(r"the optimum came from: (.*)$")


def _verdict_and_fits(rep: dict, truth: dict, jump: dict) -> dict:
    """What issue 20 checks of one fit: the evidence word, the data's jump row, and per slip condition the
    fit's own W_ad / μh claims against the truth, its χ², the row it detaches at and the start that won."""
    slip = rep.get("slip", {})
    fits = {}
    for s, f in (rep.get("fits") or {}).items():
        pars = f.get("parameters", {})
        came = [m.group(1) for d in f.get("diagnostics", []) if (m := _CAME_FROM.search(d))]
        fits[s] = {name: rs.judge(pars[name], truth[name]) for name in rs.PARAMS if name in pars} | {
            k: f.get(k) for k in ("chisqr", "ndata", "success", "misfit", "interval_widening",
                                  "residual_autocorrelation", "first_detached_row")} | {
            "optimum_from": came[0] if came else None}
    return {"favoured": slip.get("favoured"), "evidence": slip.get("evidence"),
            "parameters_from": slip.get("parameters_from"), "jump": jump, "fits": fits}


def _data_jump(path: Path, truth: dict) -> dict:
    """The data's own jump row: ``detect_jump`` on the CSV's force (rows as the fit numbers them), next to
    the first row past the true turning point (``truth['first_detached_row']``)."""
    from adhfit.fitting.segments import detect_jump  # noqa: PLC0415
    a = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
    i_turn = int(np.argmax(a[:, 1]))
    row, _ = detect_jump(a[:, 2], i_turn)
    return {"i_turn": i_turn, "detected": row, "true": truth.get("first_detached_row")}


def _git(*cmd: str) -> str | None:
    try:
        return subprocess.run(["git", *cmd], cwd=ROOT, capture_output=True, text=True, check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return None


def provenance(argv: list[str], wall: float | None, workers: int) -> dict:
    import adhfit  # noqa: PLC0415
    dirty = bool(_git("status", "--porcelain", "--", "adhfit"))
    return {"command": "python benchmarks/recovery.py " + " ".join(argv),
            "commit": (_git("rev-parse", "--short", "HEAD") or "?") + ("+dirty" if dirty else ""),
            "adhfit": adhfit.__version__,
            "date_utc": time.strftime("%Y-%m-%d %H:%M", time.gmtime()),
            "wall_s": None if wall is None else round(wall, 1),
            "workers": workers, "python": platform.python_version(), "numpy": np.__version__,
            "nproc": os.cpu_count()}


def _failed_record(job: dict, message: str) -> dict:
    """The record of a replicate whose worker process died or was lost (counted as an error)."""
    none = {"status": "error", "value": None, "lo": None, "hi": None, "covered": None, "rel_err": None}
    return dict(job, error=message[:300], wall_s=None, selected=None, slip_outcome="error", delta_bic=None,
                warnings=[], warned_duplicates=False, **{name: dict(none) for name in rs.PARAMS})


def _execute(args) -> tuple[list[dict], float]:
    """Run the plan with the runners of ``adhfit fit`` batches (serial, ``--workers`` local processes or
    the Dask cluster at ``--scheduler``); every record is also appended to OUT.partial.jsonl as it
    completes.  The records come back in plan order whoever ran them."""
    from adhfit.cli import runners  # noqa: PLC0415
    jobs = plan(args)
    t0 = time.perf_counter()
    done: dict[int, dict] = {}
    partial = Path(args.out).with_suffix(".partial.jsonl")
    partial.parent.mkdir(parents=True, exist_ok=True)
    partial.write_text("", encoding="utf-8")

    def report(item: tuple[int, dict]) -> None:
        k, rec = item
        done[k] = rec
        with partial.open("a", encoding="utf-8") as fh:
            fh.write(json.dumps(rec, default=str) + "\n")
        print(f"[{len(done)}/{len(jobs)} {time.perf_counter() - t0:.0f} s] {rec['case']} {rec['slip']} "
              f"{rec['variant']} {100 * rec['noise']:g} % #{rec['rep']}: W {rec['work_of_adhesion']['status']} "
              f"{rec['work_of_adhesion']['covered']}, slip {rec['slip_outcome']}", file=sys.stderr, flush=True)

    def crashed(k: int, message: str) -> tuple[int, dict]:
        return k, _failed_record(jobs[k], message)

    calls = [(k, job) for k, job in enumerate(jobs)]
    if args.scheduler:
        runners.run_dask(_indexed, calls, args.scheduler, report, crashed)
    elif args.workers > 1:
        runners.run_local(_indexed, calls, args.workers, report, crashed)
    else:
        for call in calls:
            report(_indexed(*call))
    return [done[k] for k in range(len(jobs))], time.perf_counter() - t0


def _indexed(k: int, job: dict) -> tuple[int, dict]:
    return k, run_one(job)


def run(args, argv: list[str]) -> dict:
    """Run the plan (in ``--workers`` processes), summarise, write OUT.json / OUT.md / OUT.png.

    With ``--from-records FILE`` (a ``.partial.jsonl`` of an interrupted run) nothing is fitted: the
    report is made from the records there, and says so.
    """
    if args.from_records:
        lines = Path(args.from_records).read_text(encoding="utf-8").splitlines()
        records, wall = [json.loads(x) for x in lines if x.strip()], None
    else:
        records, wall = _execute(args)
    out = {"provenance": provenance(argv, wall, args.workers) | {
               "partial": f"report from the {len(records)} records of {args.from_records} (run stopped early; "
                          "every cell advances in proportion to its replicate count)" if args.from_records else None},
           "settings": {k: v for k, v in vars(args).items() if k != "out"} | {
               "truth": rc.TRUTH, "baseline_fraction": rc.BASELINE, "drift_fraction": rc.DRIFT,
               "mcmc_settings": MCMC_SETTINGS if args.method == "mcmc" else None},
           "pooled": rs.cells(records, ("variant", "noise")),
           "cells": rs.cells(records, ("case", "slip", "variant", "noise")),
           "issue20": {"pooled": rs.issue20(records, ("variant", "noise")),
                       "cells": rs.issue20(records, ("case", "slip", "variant", "noise"))}
           if any("fits" in r for r in records) else None,
           "replicates": records}
    out_path = Path(args.out)
    out_path.parent.mkdir(parents=True, exist_ok=True)
    out_path.with_suffix(".json").write_text(json.dumps(out, indent=1, default=str) + "\n", encoding="utf-8")
    write_markdown(out, out_path.with_suffix(".md"))
    if not args.no_plot:
        from recovery_plot import plot  # noqa: PLC0415
        plot(out, out_path.with_suffix(".png"))
    return out


def parse(argv: list[str]) -> argparse.Namespace:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--replicates", type=int, default=20, help="replicates per clean cell at the headline noise levels")
    ap.add_argument("--replicates-other", type=int, default=4, help="replicates per cell elsewhere")
    ap.add_argument("--noise", type=float, nargs="+", default=list(rc.NOISES),
                    help="force noise levels (fraction of the peak force) of the clean variant")
    ap.add_argument("--headline-noise", type=float, nargs="+", default=[0.02, 0.04])
    ap.add_argument("--variant-noise", type=float, nargs="+", default=[0.02],
                    help="noise levels of the variants other than clean")
    ap.add_argument("--cases", nargs="+", default=list(rc.CASES), choices=list(rc.CASES))
    ap.add_argument("--slips", nargs="+", default=list(rc.SLIPS), choices=list(rc.SLIPS))
    ap.add_argument("--variants", nargs="+", default=list(rc.VARIANTS), choices=list(rc.VARIANTS))
    ap.add_argument("--seed", type=int, default=20261201)
    ap.add_argument("--method", choices=("lsq", "mcmc"), default="lsq")
    ap.add_argument("--workers", type=int, default=1, help="local processes (as adhfit fit --workers)")
    ap.add_argument("--scheduler", default=None, metavar="ADDRESS",
                    help="run the replicates on the Dask distributed cluster at ADDRESS (as adhfit fit --scheduler)")
    ap.add_argument("--out", default=str(ROOT / "benchmarks" / "results" / "recovery"),
                    help="output path without suffix")
    ap.add_argument("--no-plot", action="store_true")
    ap.add_argument("--from-records", help="make the report from a .partial.jsonl of an interrupted run")
    args = ap.parse_args(argv)
    if args.workers < 1 or args.replicates < 0 or args.replicates_other < 0:
        ap.error("--workers must be >= 1 and replicate counts >= 0")
    return args


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    out = run(parse(argv), argv)
    print(f"{len(out['replicates'])} fits in {out['provenance']['wall_s']} s -> {Path(parse(argv).out)}.md")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
