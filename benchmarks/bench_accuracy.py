"""Run time against error: engine vs the scipy quad baseline at several tolerances (issue 2, item 7b).

Error: max |Δf| and max |Δδ| (also |Δp|, |Δa|) over a set of states against the 30-digit mpmath
reference.  The states are read from ``tests/data/reference_states.json`` when it exists (written by
``python -m tests.reference.make_reference``); otherwise they are computed here with
``tests/reference/mp_model.py`` for the base cases and cached in
``benchmarks/results/accuracy_reference.json``.

Time: for every reference case (inputs x slip) one 200-point history, ``adhfit.simulate`` for the
engine and ``baseline_quad.history`` at each tolerance for the baseline; the table and plot use the
sum over cases of the least of ``--repeat`` runs.  The baseline's errors come from
``baseline_quad.state`` at the same locators and tolerance (``quad_tol`` = quad epsabs = epsrel,
``root_tol`` = brentq xtol, set equal), the engine's from ``adhfit.loading.state_at``.

Usage::

    python benchmarks/bench_accuracy.py [--tols 1e-4 1e-6 1e-8 1e-10 1e-12] [--repeat 3]

Writes ``benchmarks/results/accuracy.md``, ``accuracy.json`` and ``accuracy.png`` (log-log).
"""
from __future__ import annotations

import argparse
import json
import math
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))

import adhfit  # noqa: E402
import baseline_quad  # noqa: E402
from adhfit.loading import state_at  # noqa: E402
from bench_time import machine_info  # noqa: E402

RESULTS = ROOT / "benchmarks" / "results"
REFERENCE = ROOT / "tests" / "data" / "reference_states.json"
FALLBACK = RESULTS / "accuracy_reference.json"
TOLS = (1e-4, 1e-6, 1e-8, 1e-10, 1e-12)
KEYS = ("f", "delta", "p", "a")
INF = math.inf


# --------------------------------------------------------------------------------------------------
# reference states
# --------------------------------------------------------------------------------------------------
def _fallback_cases() -> list[dict]:
    """Reference states for the paper's base cases with mp_model (minutes; cached)."""
    from tests.reference import mp_model as M

    cases = []
    inputs = [("displacement", dict(p=0.6, w=0.2, rs=0.5, a_max=0.25)),
              ("displacement", dict(p=0.6, w=0.2, rs=INF, a_max=0.25)),
              ("pressure", dict(d=0.0, w=0.2, rs=0.5, a_max=0.25)),
              ("pressure", dict(d=0.2, w=0.2, rs=INF, a_max=0.25))]
    for control, kw in inputs:
        for slip in M.SLIPS:
            h = M.history(control, slip, **kw)
            locs = [("making_contact", "a", 0.25 * fr) for fr in (0.3, 0.7, 1.0)]
            locs += [("pinning", "alpha", float(h.alpha_onset * fr)) for fr in (0.25, 0.6, 0.999)]
            locs += [("delamination", "a", float(h.a_onset * fr)) for fr in (0.999, 0.6, 0.25, 0.05)]
            states = []
            for stage, name, loc in locs:
                st = M.state(control, slip, stage, **kw, **{name: loc})
                rec = {"stage": stage, "locator": {name: loc}}
                rec.update({k: None if st[k] is None else M.mp.nstr(st[k], 30) for k in ("a", "alpha", "p", "d",
                                                                                        "delta", "f", "G")})
                states.append(rec)
            cases.append({"id": f"{control}-{slip}-{'flat' if kw['rs'] == INF else 'base'}", "control": control,
                          "slip": slip, "inputs": {"p": None, "d": None, **kw}, "states": states})
            print(f"  reference {cases[-1]['id']}: {len(states)} states", flush=True)
    return cases


def load_reference() -> tuple[str, list[dict]]:
    """(source, cases): each case has control, slip, inputs (rs may be 'inf') and states."""
    if REFERENCE.exists():
        return str(REFERENCE.relative_to(ROOT)), json.loads(REFERENCE.read_text())["cases"]
    if not FALLBACK.exists():
        FALLBACK.parent.mkdir(parents=True, exist_ok=True)
        cases = _fallback_cases()
        FALLBACK.write_text(json.dumps({"cases": cases}, indent=1, default=str) + "\n")
    return str(FALLBACK.relative_to(ROOT)), json.loads(FALLBACK.read_text())["cases"]


def scene(case: dict) -> dict:
    """Keyword arguments of one reference case (floats; rs 'inf' -> inf; unused p/d dropped)."""
    out = {}
    for k, v in case["inputs"].items():
        if v is None:
            continue
        out[k] = INF if v == "inf" else float(v)
    return out


# --------------------------------------------------------------------------------------------------
# errors and times
# --------------------------------------------------------------------------------------------------
def _errors(got: dict, ref: dict) -> dict:
    out = {}
    for k in KEYS:
        if ref.get(k) is None or got.get(k) is None or not math.isfinite(got[k]):
            out[k] = None if ref.get(k) is None else math.inf
            continue
        out[k] = abs(float(got[k]) - float(ref[k]))
    return out


def state_errors(case: dict, solver) -> list[dict]:
    """Errors of every reference state of a case; a failed solve counts as an infinite error."""
    kw = scene(case)
    out = []
    for st in case["states"]:
        try:
            got = solver(case["control"], case["slip"], st["stage"], **kw, **st["locator"])
        except Exception as e:  # noqa: BLE001 - a failure is a data point here
            out.append({"stage": st["stage"], "locator": st["locator"], "failed": f"{type(e).__name__}: {e}"[:200],
                        **{k: math.inf for k in KEYS}})
            continue
        out.append({"stage": st["stage"], "locator": st["locator"], **_errors(got, st)})
    return out


def best_time(fun, repeat: int) -> float:
    """Least wall time of ``repeat`` calls after a warm-up call (NaN if the call fails).

    The least, not the median: on a shared machine the least is the one other jobs inflate least.
    """
    try:
        fun()
    except Exception:  # noqa: BLE001
        return math.nan
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fun()
        times.append(time.perf_counter() - t0)
    return min(times)


def _worst(errs: list[dict], key: str) -> float:
    """Max error over the states that were solved (failures are counted and listed separately)."""
    vals = [e[key] for e in errs if e.get(key) is not None and math.isfinite(e[key])]
    return max(vals) if vals else math.nan


def _aggregate(level: dict) -> None:
    """(Re)compute a level's max/median errors and failure counts from its per-state errors."""
    errs_all = [e for c in level["cases"] for e in c["states"]]
    for c in level["cases"]:
        c["max_abs"] = {k: _worst(c["states"], k) for k in KEYS}
        c["failed_states"] = sum("failed" in e for e in c["states"])
    level["failed_states"] = sum("failed" in e for e in errs_all)
    level["max_abs"] = {k: _worst(errs_all, k) for k in KEYS}
    level["median_abs"] = {k: float(np.median([e[k] for e in errs_all if e.get(k) is not None
                                               and math.isfinite(e[k])])) for k in KEYS}


def run_level(cases: list[dict], label: str, solver, history_fun, repeat: int) -> dict:
    per_case, t_total, errs_all = [], 0.0, []
    for case in cases:
        errs = state_errors(case, solver)
        kw = scene(case)
        t = best_time(lambda: history_fun(case["control"], case["slip"], **kw), repeat)
        t_total += t if math.isfinite(t) else 0.0
        errs_all += errs
        per_case.append({"id": case["id"], "history_time_s": t, "max_abs": {k: _worst(errs, k) for k in KEYS},
                         "failed_states": sum("failed" in e for e in errs), "states": errs})
    level = {"label": label, "history_time_total_s": t_total,
             "failed_histories": sum(not math.isfinite(c["history_time_s"]) for c in per_case),
             "cases": per_case}
    _aggregate(level)
    print(f"  {label:28s}: time {1e3 * t_total:9.1f} ms  max|df| {level['max_abs']['f']:.2e}  "
          f"max|dδ| {level['max_abs']['delta']:.2e}  failed states {level['failed_states']}", flush=True)
    return level


def engine_level(cases: list[dict], repeat: int) -> dict:
    def solver(control, slip, stage, **kw):
        kw = {k: v for k, v in kw.items()}
        return state_at(control, slip, stage, **kw)

    def hist(control, slip, **kw):
        return adhfit.simulate(control, slip, points=200, **kw)

    return run_level(cases, "engine (adhfit)", solver, hist, repeat)


def baseline_level(cases: list[dict], tol: float, repeat: int) -> dict:
    def solver(control, slip, stage, **kw):
        return baseline_quad.state(control, slip, stage, quad_tol=tol, root_tol=tol, **kw)

    def hist(control, slip, **kw):
        return baseline_quad.history(control, slip, points=200, quad_tol=tol, root_tol=tol, **kw)

    lev = run_level(cases, f"baseline tol {tol:g}", solver, hist, repeat)
    lev["tol"] = tol
    return lev


# --------------------------------------------------------------------------------------------------
# report
# --------------------------------------------------------------------------------------------------
def plot(rep: dict, path: Path) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(10, 4.2), sharex=True)
    base = rep["baseline"]
    eng = rep["engine"]
    for ax, key, name in ((axes[0], "f", "max |Δf|"), (axes[1], "delta", "max |Δδ|")):
        x = [lv["history_time_total_s"] for lv in base]
        y = [max(lv["max_abs"][key], 1e-17) for lv in base]
        ax.loglog(x, y, "o-", color="tab:blue", label="scipy quad + brentq baseline")
        for lv, xi, yi in zip(base, x, y):
            ax.annotate(f"tol {lv['tol']:g}", (xi, yi), textcoords="offset points", xytext=(5, 4), fontsize=8)
        ax.loglog([eng["history_time_total_s"]], [max(eng["max_abs"][key], 1e-17)], "*", ms=14,
                  color="tab:red", label="adhfit engine")
        ax.set_xlabel(f"time for {rep['n_cases']} histories of 200 points (s)")
        ax.set_ylabel(f"{name} over {rep['n_states']} reference states")
        ax.grid(True, which="both", alpha=0.3)
    axes[0].legend(fontsize=8)
    fig.suptitle("Run time against error (30-digit mpmath reference)", fontsize=11)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def write_markdown(rep: dict, path: Path) -> None:
    lines = ["# Run time against error", "",
             f"Command: `{rep['command']}`  ",
             f"Reference: `{rep['reference']}` ({rep['n_cases']} cases, {rep['n_states']} states, 30 digits).  ",
             "Machine: " + ", ".join(f"{k} {v}" for k, v in rep["machine"].items()) + "  ",
             f"Time: sum over the cases of the least of {rep['repeat']} runs (after a warm-up run) of one "
             "200-point history. "
             "Errors: max (and median) absolute error over the reference states that were solved; "
             "failed solves are counted and listed below.", "",
             "| solver | time, all histories (ms) | max abs Δf | max abs Δδ | max abs Δp | max abs Δa "
             "| median abs Δf | failed states | failed histories |",
             "|---|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for lv in [rep["engine"]] + rep["baseline"]:
        m = lv["max_abs"]
        lines.append(f"| {lv['label']} | {1e3 * lv['history_time_total_s']:.1f} | {m['f']:.1e} | {m['delta']:.1e} | "
                     f"{m['p']:.1e} | {m['a']:.1e} | {lv['median_abs']['f']:.1e} | {lv['failed_states']} | "
                     f"{lv['failed_histories']} |")
    lines += ["", "![time vs error](accuracy.png)", "", "## Per case: max abs Δf", "",
              "| case | engine | " + " | ".join(f"tol {lv['tol']:g}" for lv in rep["baseline"]) + " |",
              "|---|---:|" + "---:|" * len(rep["baseline"])]
    for i, c in enumerate(rep["engine"]["cases"]):
        lines.append(f"| {c['id']} | {c['max_abs']['f']:.1e} | "
                     + " | ".join(f"{lv['cases'][i]['max_abs']['f']:.1e}" for lv in rep["baseline"]) + " |")
    fails = [(lv["label"], c["id"], s) for lv in [rep["engine"]] + rep["baseline"] for c in lv["cases"]
             for s in c["states"] if "failed" in s]
    if fails:
        lines += ["", "## Failed solves", ""]
        lines += [f"- {lab}, {cid}, {s['stage']} {s['locator']}: {s['failed']}" for lab, cid, s in fails[:40]]
    path.write_text("\n".join(lines) + "\n")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--tols", type=float, nargs="+", default=list(TOLS))
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--out", type=Path, default=RESULTS)
    ap.add_argument("--render", action="store_true",
                    help="only rebuild accuracy.md and accuracy.png from an existing accuracy.json")
    args = ap.parse_args(argv)
    if args.render:
        rep = json.loads((args.out / "accuracy.json").read_text())
        for lv in [rep["engine"]] + rep["baseline"]:
            _aggregate(lv)
        (args.out / "accuracy.json").write_text(json.dumps(rep, indent=1, default=str) + "\n")
        write_markdown(rep, args.out / "accuracy.md")
        plot(rep, args.out / "accuracy.png")
        return 0
    source, cases = load_reference()
    print(f"reference: {source}, {len(cases)} cases", flush=True)
    rep = {"command": " ".join(["python"] + sys.argv), "reference": source, "repeat": args.repeat,
           "machine": machine_info(), "n_cases": len(cases),
           "n_states": sum(len(c["states"]) for c in cases)}
    rep["engine"] = engine_level(cases, args.repeat)
    rep["baseline"] = [baseline_level(cases, tol, args.repeat) for tol in args.tols]
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "accuracy.json").write_text(json.dumps(rep, indent=1, default=str) + "\n")
    write_markdown(rep, args.out / "accuracy.md")
    plot(rep, args.out / "accuracy.png")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
