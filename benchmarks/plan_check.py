"""Check ``adhfit plan``'s predictions against what the fit actually does (issue 22, "Done when").

For each protocol (both control modes, both true slips, slips decided and undecided), the plan predicts
the expected 95 % interval widths of W_ad and μh and P(slip decided); then ``--replicates`` noisy curves
are made as ``adhfit simulate --scene ... -o`` makes them (:func:`adhfit.synthetic.measured_frame`,
written to CSV) and fitted as ``adhfit fit`` fits them (:func:`adhfit.fit` on the CSV file, default
settings: least squares, slip auto, profiles).  Compared:

- **widths per verdict class** (the check): a decided fit reports its slip condition's interval, an
  undecided one the hull of both conditions' intervals; the plan predicts the decided width and the median
  undecided hull (:mod:`adhfit.planning.hull`: both slips' estimates and ΔBIC drawn jointly under the
  linearised noise, kept where the verdict is undecided).  Pass: each class with at least 5 fits within 20 %
  of its median reported width, for W_ad and μh.
- **the median over all fits** (printed, and judged separately): the plan's prediction of it is the median of
  the predicted mixture (P(decided)·decided width + P(undecided)·hull distribution).  The reported widths
  are bimodal (the hull is 3-15 times the decided width), so where the observed share of decided fits is
  within two binomial standard errors of 0.5 the sample median falls in either mode by chance: that median
  is ill-conditioned there and its ratio says nothing about the widths (marked "ill-cond.").
- **P(slip decided)** against the observed rate of fits that select the true slip (pass: within 0.1; the
  binomial standard error of the observed rate is printed: at 30 replicates and P = 0.5 it is 0.09, so a
  0.1 bound there is about one standard error).

A diagnostic, not part of the check: the undecided fits whose hull's two ends both come from profile sides
that converged (a side that does not converge reports the nearest probe beyond its limit, which can be far
out: the fit's first probe, placed by its covariance, overshoots where the optimum sits at the pull-off's
kink).

    python benchmarks/plan_check.py --replicates 30 --workers 2 --out benchmarks/results/plan_check.md

``--quick`` runs two protocols with a few replicates (what tests/test_plan_check.py runs).
"""
from __future__ import annotations

import argparse
import math
import multiprocessing
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

#: (name, scene file, control end, end value SI, true slip, noise fraction)
PROTOCOLS = [
    ("disp-deep-ns", "flat_displacement_no-slip", "displacement_max", 4e-4, "no-slip", 0.03),
    ("disp-deep-fr", "flat_displacement_no-slip", "displacement_max", 4e-4, "frictionless", 0.03),
    ("disp-shallow-ns", "flat_displacement_no-slip", "displacement_max", 1.3e-4, "no-slip", 0.03),
    ("disp-shallow-fr", "flat_displacement_no-slip", "displacement_max", 1.3e-4, "frictionless", 0.03),
    ("pres-1200-ns-2%", "flat_pressure_no-slip", "pressure_max", 1200.0, "no-slip", 0.02),
    ("pres-1200-fr-3%", "flat_pressure_no-slip", "pressure_max", 1200.0, "frictionless", 0.03),
    ("pres-900-ns-5%", "flat_pressure_no-slip", "pressure_max", 900.0, "no-slip", 0.05),
    ("pres-900-fr-5%", "flat_pressure_no-slip", "pressure_max", 900.0, "frictionless", 0.05),
]
QUICK = [PROTOCOLS[0], PROTOCOLS[4]]
W_AD, MU_H, ROWS = 0.3, 1.5, 300
#: fewest replicates of a verdict class (decided / undecided) whose median width is checked
MIN_CLASS = 5
ROOT = Path(__file__).resolve().parents[1]


def _scene(name: str):
    from adhfit.scene import load_scene
    return load_scene(ROOT / "sample_data" / name / "scene.toml")


def predict(proto) -> dict:
    """The plan's prediction for one protocol (its true slip only)."""
    from adhfit.planning.evaluate import predict as one
    from adhfit.planning.protocols import Protocol
    name, scene, end, value, slip, noise = proto
    e = one(Protocol(_scene(scene), end, value, ROWS, noise), (slip,), W_AD, MU_H, "large-stretch")
    b = e["by_slip"][slip]
    out = {"p": e["p_slip_decided"][slip], "wrong": e["p_wrong_slip"][slip], "x_max": e["settings"]["control_max"]}
    for key, name in (("w", "work_of_adhesion"), ("mu", "mu_h")):
        out[key] = b["ci95_width_median"][name]
        out[f"{key}_mean"] = b["ci95_width"][name]
        out[f"{key}_decided"] = b["ci95_width_decided"][name]
        out[f"{key}_undecided"] = b["ci95_width_undecided"][name]
    return out


def replicate(job) -> dict:
    """One simulated curve (as ``adhfit simulate --scene -o`` writes it) fitted as ``adhfit fit`` fits it."""
    import adhfit
    from adhfit.synthetic import measured_frame
    proto, x_max, seed = job
    name, scene_name, end, value, slip, noise = proto
    scene = _scene(scene_name)
    frame, _ = measured_frame(scene, slip, mu_h=MU_H, work_of_adhesion=W_AD, x_max=x_max, rows=ROWS, noise=noise,
                              seed=seed)
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "curve.csv"
        frame.to_csv(path, index=False, float_format="%.9g")
        try:
            r = adhfit.fit(path, scene)
        except Exception as err:  # noqa: BLE001 - counted, never hidden
            return {"name": name, "error": f"{type(err).__name__}: {err}"}
    out = {"name": name, "selected": r.slip.get("selected"), "delta_bic": r.slip.get("delta_bic"),
           "favoured": r.slip.get("favoured")}
    for key, par in (("w", "work_of_adhesion"), ("mu", "mu_h")):
        ci = r.parameters[par].ci95
        out[key] = (ci[1] - ci[0]) if ci is not None and None not in ci else None
        out[f"{key}_ci"] = None if ci is None else [None if c is None else float(c) for c in ci]
        out[f"{key}_value"] = r.parameters[par].value
        # coverage: the reported interval (a missing bound is open on that side) holds the truth
        truth = W_AD if key == "w" else MU_H
        out[f"{key}_covers"] = None if ci is None else bool((ci[0] is None or ci[0] <= truth) and
                                                            (ci[1] is None or truth <= ci[1]))
    # each slip condition's own fit (what an undecided fit hulls): its estimate, interval, χ² and nuisances
    out["by_slip"] = {}
    for s, f in r.fits.items():
        one = {"chisqr": f.chisqr, "bic": f.bic, "ndata": f.ndata, "nvarys": f.nvarys, "sigma": f.sigma,
               "nuisances": [k for k in f.parameters if k not in ("work_of_adhesion", "mu_h")],
               # each profile side converged (a side that did not reports its nearest probe beyond the limit)
               "profile_converged": {k: list(v.get("converged", [])) for k, v in f.profile.items()}}
        for key, par in (("w", "work_of_adhesion"), ("mu", "mu_h")):
            e = f.parameters[par]
            one[f"{key}_value"] = e.value
            one[f"{key}_ci"] = None if e.ci95 is None else [None if c is None else float(c) for c in e.ci95]
        out["by_slip"][s] = one
    return out


def run(protocols, replicates: int, workers: int, seed: int = 1000, raw: list | None = None,
        distinct: bool = False) -> list[dict]:
    """Predict and fit ``replicates`` curves per protocol.  Replicate k has seed ``seed + k`` in every protocol
    (the same standard-normal noise, scaled): the two slips of one test then see the same noise, and their
    verdict rates' errors are anti-correlated (the wrong fit's misfit directions are nearly opposite).
    ``distinct``: seed ``seed + 1000 i + k`` for the i-th protocol of :data:`PROTOCOLS` (independent)."""
    preds = {p[0]: predict(p) for p in protocols}
    jobs = [(p, preds[p[0]]["x_max"], seed + (1000 * PROTOCOLS.index(p) if distinct else 0) + k)
            for p in protocols for k in range(replicates)]
    if workers > 1:
        with multiprocessing.get_context("fork").Pool(workers) as pool:
            results = pool.map(replicate, jobs, chunksize=1)
    else:
        results = [replicate(j) for j in jobs]
    if raw is not None:
        raw.extend(results)
    rows = []
    for p in protocols:
        name, slip = p[0], p[4]
        rs = [r for r in results if r["name"] == name]
        ok = [r for r in rs if "error" not in r]
        pred = preds[name]
        n = len(ok)
        decided = sum(r["selected"] == slip for r in ok) / max(n, 1)
        wrong = sum(r["selected"] not in (None, slip) for r in ok) / max(n, 1)
        row = {"name": name, "control": "displacement" if "disp" in name else "pressure", "slip": slip,
               "noise": p[5], "end": f"{p[2]} = {p[3]:g}", "n": n, "errors": len(rs) - n,
               "p_pred": pred["p"], "p_obs": decided, "p_se": math.sqrt(max(decided * (1 - decided), 0.25 / n) / n),
               "wrong_pred": pred["wrong"], "wrong_obs": wrong}
        for key in ("w", "mu"):  # coverage of the truth by the reported 95 % interval (binomial se)
            cov = [r[f"{key}_covers"] for r in ok if r[f"{key}_covers"] is not None]
            c = sum(cov) / max(len(cov), 1)
            row[f"{key}_coverage"], row[f"{key}_coverage_n"] = c, len(cov)
            row[f"{key}_coverage_se"] = math.sqrt(max(c * (1 - c), 0.05 * 0.95) / max(len(cov), 1))
            dec = [r[f"{key}_covers"] for r in ok if r[f"{key}_covers"] is not None and r["selected"] is not None]
            row[f"{key}_coverage_decided"] = (sum(dec), len(dec))
        checks = []
        for key in ("w", "mu"):
            widths = [r[key] for r in ok if r[key] is not None]
            row[f"{key}_pred"] = pred[key]
            row[f"{key}_obs"] = float(np.median(widths)) if widths else math.nan
            row[f"{key}_two_sided"] = len(widths)
            row[f"{key}_ratio"] = pred[key] / row[f"{key}_obs"] if widths else math.nan
            row[f"{key}_mean_ratio"] = pred[f"{key}_mean"] / float(np.mean(widths)) if widths else math.nan
            for cls, sel in (("decided", lambda r: r["selected"] is not None), ("undecided", lambda r: r["selected"] is None)):
                ws = [r[key] for r in ok if r[key] is not None and sel(r)]
                row[f"{key}_{cls}_n"] = len(ws)
                row[f"{key}_{cls}_pred"] = pred[f"{key}_{cls}"]
                row[f"{key}_{cls}_obs"] = float(np.median(ws)) if ws else math.nan
                row[f"{key}_{cls}_ratio"] = pred[f"{key}_{cls}"] / float(np.median(ws)) if ws else math.nan
                if len(ws) >= min(MIN_CLASS, len(rs)):
                    checks.append(abs(row[f"{key}_{cls}_ratio"] - 1) <= 0.2)
            # a diagnostic, not the check: the undecided fits whose every W_ad/μh profile side converged (a side
            # that does not reports its nearest probe beyond the limit, far out where the first probe overshot)
            conv = [r[key] for r in ok if r[key] is not None and r["selected"] is None and _profiles_converged(r, key)]
            row[f"{key}_undecided_converged_n"] = len(conv)
            row[f"{key}_undecided_converged_ratio"] = pred[f"{key}_undecided"] / float(np.median(conv)) if conv else math.nan
        # the width model is checked where the verdict's class has enough fits: the decided fits' median against
        # the true condition's width, the undecided ones' against the hull of both conditions' intervals
        row["pass_width"] = bool(checks) and all(checks)
        # the median over all fits: the mixture's median against the sample median; ill-conditioned where the
        # share of decided fits could be 0.5 (within two binomial standard errors), the median then in either mode
        share = sum(r["selected"] is not None for r in ok) / max(n, 1)
        row["share_decided"] = share
        row["median_ill_conditioned"] = abs(share - 0.5) < 2 * math.sqrt(0.25 / max(n, 1))
        row["pass_median"] = all(abs(row[f"{key}_ratio"] - 1) <= 0.2 for key in ("w", "mu"))
        row["pass_p"] = abs(row["p_pred"] - row["p_obs"]) <= 0.1
        rows.append(row)
    return rows


def _profiles_converged(r: dict, key: str) -> bool:
    """Whether both ends of the reported (hulled) interval of ``key`` come from converged profile sides: the end
    of the slip condition that sets it (fits recorded with the per-side convergence)."""
    par = {"w": "work_of_adhesion", "mu": "mu_h"}[key]
    by = r.get("by_slip") or {}
    cis = {s: b.get(f"{key}_ci") for s, b in by.items()}
    if not by or any(ci is None or None in ci for ci in cis.values()):
        return False
    lo = min(cis, key=lambda s: cis[s][0])
    hi = max(cis, key=lambda s: cis[s][1])
    conv = {s: b.get("profile_converged", {}).get(par, [False, False]) for s, b in by.items()}
    return bool(conv[lo][0] and conv[hi][1])


def _f(x, fmt=".2f") -> str:
    return "–" if x is None or (isinstance(x, float) and math.isnan(x)) else format(x, fmt)


def table(rows: list[dict]) -> str:
    head = ("| protocol | control | true slip | noise | loading end | fits | W_ad decided: pred / obs [J/m²] (fits) | "
            "W_ad undecided hull: pred / obs (fits) | ratios W_ad dec / und | μh decided: pred / obs [N/m] | "
            "μh undecided hull: pred / obs | ratios μh dec / und | per-class pass |\n"
            "|---|---|---|---|---|---|---|---|---|---|---|---|---|\n")
    lines = []
    for r in rows:
        cells = [r["name"], r["control"], r["slip"], f"{100 * r['noise']:g} %", r["end"],
                 f"{r['n']}{' (' + str(r['errors']) + ' failed)' if r['errors'] else ''}"]
        for key in ("w", "mu"):
            cells.append(f"{_f(r[f'{key}_decided_pred'], '.3g')} / {_f(r[f'{key}_decided_obs'], '.3g')} ({r[f'{key}_decided_n']})")
            cells.append(f"{_f(r[f'{key}_undecided_pred'], '.3g')} / {_f(r[f'{key}_undecided_obs'], '.3g')} ({r[f'{key}_undecided_n']})")
            und = _f(r[f"{key}_undecided_ratio"]) if r[f"{key}_undecided_n"] >= MIN_CLASS else \
                f"({_f(r[f'{key}_undecided_ratio'])})"
            cells.append(f"{_f(r[f'{key}_decided_ratio'])} / {und}")
        cells.append("yes" if r["pass_width"] else "**no**")
        lines.append("| " + " | ".join(cells) + " |")
    out = head + "\n".join(lines) + "\n"
    out += ("\n| protocol | W_ad all fits: mixture median pred / obs | ratio | μh all fits: pred / obs | ratio | "
            "decided share (obs) | all-fits median | undecided W_ad, hull ends from converged profiles: ratio (fits) | "
            "P(decided) pred / obs ± se | P(wrong) pred / obs | W_ad / μh coverage ± se (intervals) | P pass | pass |\n"
            "|---|---|---|---|---|---|---|---|---|---|---|---|---|\n")
    lines = []
    for r in rows:
        med = ("within 20 %" if r["pass_median"] else "**off**") + (" (ill-cond.)" if r["median_ill_conditioned"] else "")
        conv = f"{_f(r['w_undecided_converged_ratio'])} ({r['w_undecided_converged_n']})" if r["w_undecided_n"] else "–"
        verdict = "yes" if r["pass_width"] and r["pass_p"] else "**" + ("width" if not r["pass_width"] else "P") + " off**"
        lines.append(f"| {r['name']} | {r['w_pred']:.3g} / {r['w_obs']:.3g} | {r['w_ratio']:.2f} | {r['mu_pred']:.3g} / "
                     f"{r['mu_obs']:.3g} | {r['mu_ratio']:.2f} | {r['share_decided']:.2f} | {med} | {conv} | "
                     f"{r['p_pred']:.2f} / {r['p_obs']:.2f} ± {r['p_se']:.2f} | {r['wrong_pred']:.3f} / {r['wrong_obs']:.3f} | "
                     f"{r['w_coverage']:.2f} ± {r['w_coverage_se']:.2f} / {r['mu_coverage']:.2f} ± {r['mu_coverage_se']:.2f} "
                     f"({r['w_coverage_n']}) | {'yes' if r['pass_p'] else '**no**'} | {verdict} |")
    return out + "\n".join(lines) + "\n"


def pieces(path: Path) -> str:
    """The undecided hull's pieces, predicted against a run's undecided fits (its ``--json``): the other slip's
    shift ln(W_other/W_true) (median of the hull's undecided draws) and each slip's W_ad limits (ln, relative to
    its estimate; the main nuisance set's noiseless profile limits), against the medians over the fits."""
    import json  # noqa: PLC0415
    from adhfit.planning.evaluate import OTHER, _variant  # noqa: PLC0415
    from adhfit.planning.hull import hull_model  # noqa: PLC0415
    from adhfit.planning.information import jacobian  # noqa: PLC0415
    from adhfit.planning.protocols import Protocol  # noqa: PLC0415
    from adhfit.planning.truth import loading_end, noiseless_test  # noqa: PLC0415
    reps = json.loads(Path(path).read_text(encoding="utf-8"))["replicates"]
    out = ["| protocol | undecided fits | shift ln(W_other/W_true): pred / obs (sd) | true slip's W_ad limits [ln]: "
           "pred / obs | other slip's W_ad limits [ln]: pred / obs [fits whose side converged] |", "|---|---|---|---|---|"]
    md = lambda x: float(np.median(x))  # noqa: E731
    for name, scene, end, value, slip, noise in PROTOCOLS:
        rs = [r for r in reps if r["name"] == name and "error" not in r and r["selected"] is None and r.get("by_slip")]
        if len(rs) < MIN_CLASS:
            continue
        o = OTHER[slip]
        prot = Protocol(_scene(scene), end, value, ROWS, noise)
        truth = noiseless_test(prot, slip, W_AD, MU_H, loading_end(prot, slip, W_AD, MU_H))
        v = _variant(truth, slip, "large-stretch", None)
        m = v["m"]
        r_w, J_w, _ = jacobian(truth.model_of(o), truth.par, truth.sigma, m.values)
        hm = hull_model(v["r"], v["J_force"], truth.values, v["widths"], r_w, J_w, m.values, m.widths, m.lam, m.n,
                        m.chisqr_true, truth.model.curve.force.size)
        shift = md(hm.shift["work_of_adhesion"][hm.undecided])
        lnr = lambda r, s, i: math.log(r["by_slip"][s]["w_ci"][i] / r["by_slip"][s]["w_value"])  # noqa: E731
        sh = [math.log(r["by_slip"][o]["w_value"] / r["by_slip"][slip]["w_value"]) for r in rs]
        conv = [[r for r in rs if r["by_slip"][o]["profile_converged"]["work_of_adhesion"][i]] for i in (0, 1)]
        it, iw = v["widths"]["work_of_adhesion"]["interval"], m.widths["work_of_adhesion"]["interval"]
        out.append(f"| {name} | {len(rs)} | {shift:+.4f} / {md(sh):+.4f} ({np.std(sh):.4f}) | "
                   f"({it[0]:+.4f}, {it[1]:+.4f}) / ({md([lnr(r, slip, 0) for r in rs]):+.4f}, "
                   f"{md([lnr(r, slip, 1) for r in rs]):+.4f}) | ({iw[0]:+.4f}, {iw[1]:+.4f}) / "
                   f"({md([lnr(r, o, 0) for r in conv[0]]):+.4f} [{len(conv[0])}], "
                   f"{md([lnr(r, o, 1) for r in conv[1]]):+.4f} [{len(conv[1])}]) |")
    return "\n".join(out) + "\n"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--replicates", type=int, default=30)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--quick", action="store_true", help="two protocols (CI)")
    ap.add_argument("--out", type=Path, default=None, help="write the table (Markdown) here")
    ap.add_argument("--only", nargs="+", default=None, help="these protocols only (names)")
    ap.add_argument("--seed", type=int, default=1000, help="first replicate's seed (then +1 each)")
    ap.add_argument("--json", type=Path, default=None, help="write every replicate's fit summary here")
    ap.add_argument("--distinct-seeds", action="store_true",
                    help="independent noise per protocol (seed + 1000 x its index + k), not the same seeds in each")
    ap.add_argument("--pieces", type=Path, default=None,
                    help="print the undecided hull's pieces, predicted against this run's --json, and stop")
    args = ap.parse_args(argv)
    if args.pieces is not None:
        print(pieces(args.pieces))
        return 0
    t0 = time.perf_counter()
    protocols = QUICK if args.quick else PROTOCOLS
    if args.only:
        protocols = [p for p in PROTOCOLS if p[0] in args.only]
    raw: list = []
    rows = run(protocols, args.replicates, args.workers, seed=args.seed, raw=raw, distinct=args.distinct_seeds)
    if args.json is not None:
        import json  # noqa: PLC0415
        args.json.write_text(json.dumps({"rows": rows, "replicates": raw}, indent=1, default=str), encoding="utf-8")
    text = table(rows)
    n_pass = sum(r["pass_width"] and r["pass_p"] for r in rows)
    n_med = sum(r["pass_median"] for r in rows)
    n_ill = sum(r["median_ill_conditioned"] for r in rows)
    n_med_ok = sum(r["pass_median"] for r in rows if not r["median_ill_conditioned"])
    summary = (f"\n{n_pass} of {len(rows)} protocols pass (widths: the predicted width of each verdict class within 20 % "
               f"of the median width the fits of that class report, for W_ad and μh, classes of ≥ {MIN_CLASS} fits; "
               f"P(slip decided) within 0.1 of the observed rate); {time.perf_counter() - t0:.0f} s wall, "
               f"{args.workers} workers.\n"
               f"The median over all fits (the predicted mixture's median against the fits' median, W_ad and μh within "
               f"20 %): {n_med} of {len(rows)}; {n_ill} of them ill-conditioned (decided share within two standard errors "
               f"of 0.5: the median falls in either mode by chance), {n_med_ok} of the {len(rows) - n_ill} others within 20 %.\n"
               "Undecided ratios in parentheses: fewer than 5 fits, not checked.\n")
    print(text + summary)
    if args.out is not None:
        cmd = "python benchmarks/plan_check.py " + " ".join(argv if argv is not None else sys.argv[1:])
        args.out.write_text(f"# adhfit plan: predictions against fits\n\nCommand: `{cmd}`\n\n{__doc__.split(chr(10) + chr(10))[1]}\n\n"
                            f"W_ad = {W_AD} J/m², μh = {MU_H} N/m, {ROWS} rows, flat substrate, b = 2 mm, λ0 = 2, "
                            f"large-stretch membrane (the sample scenes).\n\n" + text + summary, encoding="utf-8")
    return 0


if __name__ == "__main__":
    sys.exit(main())
