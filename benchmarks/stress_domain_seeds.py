"""The domain stress run (``stress_domain.py``) over several seeds, one line a seed (issue 24).

One seed's 10,000 (large-stretch) or 1,000 (exact) scenes can miss a failure class that shows on
another; this runs ``stress_domain.py`` once per seed (each into its own folder under ``--work``) and
tabulates what the issue's "done when" asks of every seed: ConvergenceErrors (listed), invariant
violations, NaN, unexpected exceptions, summary values off the 1001-row ones by more than 1e-8,
outcome changes with the row count, and the time per history.

Usage::

    python benchmarks/stress_domain_seeds.py --membrane large-stretch --seeds 3 5 7 11 13 24
    python benchmarks/stress_domain_seeds.py --membrane exact --seeds 2 3 5 7 11 24

writes (or extends, one section a membrane) ``stress_domain_seeds.md`` and
``stress_domain_seeds_<membrane>.json`` in ``--out`` (default ``benchmarks/results``).
"""
from __future__ import annotations

import argparse
import json
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "benchmarks"))

import stress_domain  # noqa: E402

SIZES = {"large-stretch": (10_000, 500), "exact": (1_000, 300)}


def _commit() -> str:
    try:
        return subprocess.run(["git", "describe", "--always", "--dirty"], cwd=ROOT, capture_output=True,
                              text=True, check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return "unknown"


def one_seed(membrane: str, seed: int, n: int, check: int, workers: int, work: Path) -> dict:
    """Run ``stress_domain.py`` for one seed and keep the numbers the issue asks of it."""
    out = work / f"{membrane}_{seed}"
    stress_domain.main(["--membrane", membrane, "--n", str(n), "--seed", str(seed), "--points-check",
                        str(check), "--domain-check", str(check), "--workers", str(workers), "--out", str(out)])
    rep = json.loads((out / f"stress_domain_{membrane}.json").read_text())
    pc = rep.get("points_check", {})
    load = str(rep.get("machine", "")).rpartition("load ")[2] or "?"
    return {"seed": seed, "n": n, "counts": rep["counts"], "load": load,
            "convergence_errors": rep["convergence_errors"],
            "points_checked": pc.get("scenes", 0), "max_abs_diff": pc.get("max_abs_diff", 0.0),
            "over_1e-8": pc.get("over_1e-8", 0), "outcome_flips": pc.get("outcome_flips", []),
            "domain_checked": rep.get("domain_check", {}).get("scenes", 0),
            "domain_flips": rep.get("domain_check", {}).get("outcome_flips", []),
            "time_history_ms": {k: 1e3 * v for k, v in rep["time_history_s"].items()}}


def section(membrane: str, rows: list[dict], command: str) -> str:
    """The markdown section of one membrane."""
    lines = [f"## {membrane}", "", f"Command: `{command}`  ",
             f"Commit {_commit()}. Times are wall time in 2 worker processes: they grow with the machine's "
             "load (last column; 2 cores).", "",
             "| seed | scenes | histories | DomainError | ConvergenceError | invariant violations | NaN "
             "| other exceptions | scenes off 1001 rows by > 1e-8 (of checked) | largest difference "
             "| outcome changes | DomainErrors not one on every grid (of checked) | p99 per history (ms) "
             "| load at start |",
             "|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for r in rows:
        c = r["counts"]
        lines.append(
            f"| {r['seed']} | {r['n']} | {c['success'] + c['success_branch_ends_early']} | {c['domain_error']} "
            f"| {c['convergence_error']} | {c['invariant_violation']} | {c['nan_in_output']} "
            f"| {c['other_exception']} | {r['over_1e-8']} ({r['points_checked']}) | {r['max_abs_diff']:.2g} "
            f"| {len(r['outcome_flips'])} | {len(r['domain_flips'])} ({r['domain_checked']}) "
            f"| {r['time_history_ms']['p99']:.1f} | {r['load']} |")
    listed = [(r["seed"], e) for r in rows for e in r["convergence_errors"]]
    lines += ["", f"Every ConvergenceError ({len(listed)}):", ""]
    lines += [f"- seed {s}: `{json.dumps(e['scene'])}`: {e['detail']}" for s, e in listed] or ["none"]
    flips = [(r["seed"], f) for r in rows for f in r["outcome_flips"] + r["domain_flips"]]
    lines += ["", f"Every outcome change with the row count ({len(flips)}):", ""]
    lines += [f"- seed {s}: `{json.dumps(f['scene'])}` at {f['points']} rows" for s, f in flips] or ["none"]
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--membrane", choices=tuple(SIZES), default="large-stretch")
    ap.add_argument("--seeds", type=int, nargs="+", required=True)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--work", type=Path, default=Path("/tmp/stress_domain_seeds"))
    ap.add_argument("--out", type=Path, default=stress_domain.RESULTS)
    args = ap.parse_args(argv)
    n, check = SIZES[args.membrane]
    rows = [one_seed(args.membrane, s, n, check, args.workers, args.work) for s in args.seeds]
    command = "python benchmarks/stress_domain_seeds.py --membrane {} --seeds {}".format(
        args.membrane, " ".join(map(str, args.seeds)))
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / f"stress_domain_seeds_{args.membrane}.json").write_text(
        json.dumps({"command": command, "commit": _commit(), "seeds": rows}, indent=1) + "\n")
    md = args.out / "stress_domain_seeds.md"
    parts = {}
    if md.exists():
        for chunk in md.read_text().split("\n## ")[1:]:
            parts[chunk.split("\n", 1)[0].strip()] = "## " + chunk
    parts[args.membrane] = section(args.membrane, rows, command)
    head = ("# Domain stress runs over several seeds\n\n"
            "Each seed: `benchmarks/stress_domain.py` (its generator and invariants), 200 rows a history, "
            "the first solved scenes (and as many DomainError scenes) re-run at 10, 11, 50, 200 and 1001 rows.\n\n")
    md.write_text(head + "\n".join(parts[k].rstrip() + "\n" for k in sorted(parts)))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
