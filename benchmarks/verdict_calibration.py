"""Slip-verdict calibration: how often each evidence word of the slip verdict is wrong (issue 20).

Seeded replicate curves of the recovery study's cases (``recovery_cases.py``: both controls x curved /
flat substrate, both true slips) at several noise levels, clean, with a drifting load-cell zero, and
stopped early, are written to CSV and fitted as a user would (``adhfit.fit(path, scene, slip="auto")``,
default options).  Every fit records the true slip, the favoured slip, the evidence word, ΔBIC and
whether a slip was selected; ``verdict_stats.py`` counts, per word, the uses and the wrong ones with a
Clopper-Pearson bound, overall, per noise level, per variant and per case.  The promise checked:
"very strong" wrong in <= 1 % of its uses, "strong" in <= 5 %.

Every fit has its own seed, ``SeedSequence(--seed, spawn_key=(case, slip, variant, noise in 1e-4,
replicate))`` (``recovery.seed_sequence``), so a fit's curve does not depend on the selection, the order
or the worker count.  Records are appended to ``OUT.partial.jsonl`` as they complete; ``--resume`` runs
only the fits missing there, ``--from-records`` only makes the report (``--refit-wrong``: the wrong
strong verdicts of records without per-slip facts are fitted again from their seeds to add them).

Usage (from the repository root)::

    python benchmarks/verdict_calibration.py [--replicates 10] [--replicates-variants 2]
        [--noise 0.005 0.01 0.02 0.03 0.05] [--variants clean drift trunc-turn ...] [--cases ...]
        [--slips ...] [--rows 200] [--seed 20261204] [--workers 2]
        [--resume | --from-records FILE [--refit-wrong]] [--out benchmarks/results/verdict_calibration]

Writes ``OUT.json`` (every fit and every table) and ``OUT.md``.
"""
from __future__ import annotations

import argparse
import json
import os
import platform
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import scipy

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))

import recovery  # noqa: E402
import recovery_cases as rc  # noqa: E402
import verdict_stats as vs  # noqa: E402

NOISES = (0.005, 0.01, 0.02, 0.03, 0.05)
VARIANTS = ("clean", "drift", "trunc-turn", "trunc-pinning", "trunc-delamination")
SEED = 20261204
KEY = ("case", "slip", "variant", "noise", "rep")


def plan(args) -> list[dict]:
    """Every fit to run: ``--replicates`` per clean cell, ``--replicates-variants`` per cell of another
    variant, at every noise level; ordered so that any prefix of the run is balanced over the cells."""
    jobs = []
    for case in args.cases:
        for slip in args.slips:
            for variant in args.variants:
                if not rc.applicable(case, slip, variant):
                    continue
                n = args.replicates if variant == "clean" else args.replicates_variants
                jobs += [{"case": case, "slip": slip, "variant": variant, "noise": noise, "rep": k,
                          "seed": args.seed, "rows": args.rows, "_order": k / n}
                         for noise in args.noise for k in range(n)]
    jobs.sort(key=lambda j: j["_order"])
    for j in jobs:
        del j["_order"]
    return jobs


def run_one(job: dict) -> dict:
    """Make, write and fit one curve; the slip verdict against the true slip."""
    ss = recovery.seed_sequence(job["seed"], job["case"], job["slip"], job["variant"], job["noise"], job["rep"])
    rec = dict(job, spawn_key=list(ss.spawn_key), error=None)
    from adhfit import fit  # noqa: PLC0415
    t0 = time.perf_counter()
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "curve.csv"
        truth = rc.make_curve(job["case"], job["slip"], job["noise"], job["variant"], np.random.default_rng(ss),
                              path, rows=job["rows"])
        rec["truth"] = {k: truth[k] for k in ("rows", "sigma", "pull_off_in_data", "first_detached_row")}
        try:
            rep = fit(str(path), rc.CASES[job["case"]].scene, slip="auto").as_dict()
        except Exception as err:  # noqa: BLE001 - the study counts every failure, whatever its kind
            rep = {}
            rec["error"] = f"{type(err).__name__}: {err}"[:300]
    rec["wall_s"] = time.perf_counter() - t0
    for k in ("favoured", "evidence", "delta_bic", "selected"):
        rec[k] = rep.get("slip", {}).get(k)
    rec["fits"] = {s: _fit_facts(f) for s, f in rep.get("fits", {}).items()}
    return rec


def _fit_facts(f: dict) -> dict:
    """What tells a stuck optimum from noise, per slip: χ², σ, lag-1 residual autocorrelation, the row
    the model detaches at (compare ``truth.first_detached_row``)."""
    return {k: f.get(k) for k in ("chisqr", "ndata", "sigma", "residual_autocorrelation", "first_detached_row",
                                  "success")}


def _indexed(k: int, job: dict) -> tuple[int, dict]:
    return k, run_one(job)


def _key(rec: dict) -> tuple:
    return tuple(rec[k] for k in KEY) + (rec["seed"], rec["rows"])


def read_records(path: Path) -> list[dict]:
    """The records of a ``.partial.jsonl`` (a torn last line, from a killed run, is skipped)."""
    out = []
    for line in path.read_text(encoding="utf-8").splitlines() if path.exists() else []:
        try:
            out.append(json.loads(line))
        except json.JSONDecodeError:
            continue
    return out


def execute(args, argv: list[str]) -> tuple[list[dict], float]:
    """Run the plan's missing fits in ``--workers`` processes, appending each record to OUT.partial.jsonl."""
    from adhfit.cli import runners  # noqa: PLC0415
    jobs = plan(args)
    partial = Path(args.out).with_suffix(".partial.jsonl")
    partial.parent.mkdir(parents=True, exist_ok=True)
    old = {_key(r): r for r in read_records(partial)} if args.resume else {}
    if not args.resume:
        partial.write_text("", encoding="utf-8")
    done = {k: old[_key(j)] for k, j in enumerate(jobs) if _key(j) in old}
    calls = [(k, j) for k, j in enumerate(jobs) if k not in done]
    t0 = time.perf_counter()
    source = {"commit": revision()["commit"], "command": "python benchmarks/verdict_calibration.py " + " ".join(argv)}

    def report(item: tuple[int, dict]) -> None:
        k, rec = item
        rec.update(source)   # which code and which run made this record (files merged by --resume keep it)
        done[k] = rec
        with partial.open("a", encoding="utf-8") as fh:
            fh.write(json.dumps(rec, default=str) + "\n")
        print(f"[{len(done)}/{len(jobs)} {time.perf_counter() - t0:.0f} s] {rec['case']} {rec['slip']} "
              f"{rec['variant']} {100 * rec['noise']:g} % #{rec['rep']}: {rec['favoured']} {rec['evidence']} "
              f"{rec['error'] or ''}", file=sys.stderr, flush=True)

    def crashed(k: int, message: str) -> tuple[int, dict]:
        return k, dict(jobs[k], error=message[:300], favoured=None, evidence=None, delta_bic=None, selected=None,
                       wall_s=None, spawn_key=None)

    if args.workers > 1:
        runners.run_local(_indexed, calls, args.workers, report, crashed)
    else:
        for call in calls:
            report(_indexed(*call))
    return [done[k] for k in range(len(jobs))], time.perf_counter() - t0


def refit_wrong(records: list[dict]) -> list[dict]:
    """Records of wrong strong / very strong verdicts that lack the per-slip facts (``fits``: made by an
    older ``run_one``) fitted again from their seeds; the verdict must come out the same."""
    out = []
    for r in records:
        if r.get("fits") is None and r.get("evidence") in vs.PROMISE and vs.is_wrong(r):
            new = run_one({k: r[k] for k in (*KEY, "seed", "rows")})
            if (new["favoured"], new["evidence"]) != (r["favoured"], r["evidence"]):
                raise RuntimeError(f"refit of {r['spawn_key']} gave {new['favoured']} {new['evidence']}, "
                                   f"the run {r['favoured']} {r['evidence']}")
            r = dict(r, truth=new["truth"], fits=new["fits"], refit=True)
        out.append(r)
    return out


def revision() -> dict:
    """The checkout's commit (``+dirty`` with uncommitted changes under adhfit/) and adhfit/'s last commit,
    taken when the run starts; the load average then."""
    dirty = bool(recovery._git("status", "--porcelain", "--", "adhfit"))
    return {"commit": (recovery._git("rev-parse", "--short", "HEAD") or "?") + ("+dirty" if dirty else ""),
            "adhfit_last_changed": recovery._git("log", "-1", "--format=%h", "--", "adhfit"),
            "date_utc": time.strftime("%Y-%m-%d %H:%M", time.gmtime()), "load_start": _load()}


def provenance(argv: list[str], wall: float | None, workers: int, start: dict) -> dict:
    """Command, engine revision at the start, machine facts."""
    import adhfit  # noqa: PLC0415
    return {"command": "python benchmarks/verdict_calibration.py " + " ".join(argv), **start,
            "adhfit": adhfit.__version__, "wall_s": None if wall is None else round(wall, 1), "workers": workers,
            "nproc": os.cpu_count(), "load_end": _load(),
            "python": platform.python_version(), "numpy": np.__version__, "scipy": scipy.__version__,
            "partial": None}


def _load() -> str:
    return " ".join(f"{x:.2f}" for x in os.getloadavg())


def run(args, argv: list[str]) -> dict:
    """Run (or read) the fits, summarise them, write OUT.json and OUT.md."""
    start = revision()
    out_json = Path(args.out).with_suffix(".json")
    if args.from_records:
        records, wall = read_records(Path(args.from_records)), None
        if args.refit_wrong:
            records = refit_wrong(records)
    else:
        records, wall = execute(args, argv)
    prov = provenance(argv, wall, args.workers, start)
    if args.from_records:
        prov |= _remade(args, len(records), out_json)
    out = {"provenance": prov,
           "settings": {k: v for k, v in vars(args).items()
                        if k not in ("out", "from_records", "resume", "refit_wrong")}
           | {"truth": rc.TRUTH, "drift_fraction": rc.DRIFT, "promise": vs.PROMISE, "level": vs.LEVEL},
           "summary": vs.summarize(records), "records": records}
    out_path = Path(args.out)
    out_path.parent.mkdir(parents=True, exist_ok=True)
    out_json.write_text(json.dumps(out, indent=1, default=str) + "\n", encoding="utf-8")
    vs.write_markdown(out, out_path.with_suffix(".md"))
    return out


def _remade(args, n: int, out_json: Path) -> dict:
    """Provenance of a report remade from records: the file, the previous run's facts (from OUT.json when
    it is there), and whether records are missing from the plan."""
    prev = json.loads(out_json.read_text(encoding="utf-8")).get("provenance", {}) if out_json.exists() else {}
    out = {"remade_from": args.from_records + (" (wrong strong verdicts refitted)" if args.refit_wrong else ""),
           "run": prev.get("run") or prev or None}
    planned = len(plan(args))
    if n < planned:
        out["partial"] = (f"report from the {n} records of {args.from_records} (of the {planned} planned; "
                          "every cell advances in proportion to its replicate count)")
    return out


def parse(argv: list[str]) -> argparse.Namespace:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--replicates", type=int, default=10, help="fits per clean cell (case x slip x noise)")
    ap.add_argument("--replicates-variants", type=int, default=2, help="fits per cell of the other variants")
    ap.add_argument("--noise", type=float, nargs="+", default=list(NOISES),
                    help="force noise σ as a fraction of the peak force")
    ap.add_argument("--variants", nargs="+", default=list(VARIANTS), choices=list(rc.VARIANTS))
    ap.add_argument("--cases", nargs="+", default=list(rc.CASES), choices=list(rc.CASES))
    ap.add_argument("--slips", nargs="+", default=list(rc.SLIPS), choices=list(rc.SLIPS))
    ap.add_argument("--rows", type=int, default=rc.ROWS, help="rows of a whole test (sets the row spacing)")
    ap.add_argument("--seed", type=int, default=SEED, help="root seed of every fit's SeedSequence")
    ap.add_argument("--workers", type=int, default=1, help="local processes (as adhfit fit --workers)")
    ap.add_argument("--out", default=str(ROOT / "benchmarks" / "results" / "verdict_calibration"),
                    help="output path without suffix")
    group = ap.add_mutually_exclusive_group()
    group.add_argument("--resume", action="store_true", help="run only the fits missing from OUT.partial.jsonl")
    group.add_argument("--from-records", help="make the report from a .partial.jsonl, fitting nothing")
    ap.add_argument("--refit-wrong", action="store_true",
                    help="with --from-records: fit the wrong strong verdicts again to add the per-slip facts")
    args = ap.parse_args(argv)
    if args.workers < 1 or args.replicates < 0 or args.replicates_variants < 0 or args.rows < 20:
        ap.error("--workers must be >= 1, replicate counts >= 0 and --rows >= 20")
    return args


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    args = parse(argv)
    out = run(args, argv)
    print(f"{out['summary']['fits']} fits in {out['provenance']['wall_s']} s -> {args.out}.md")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
