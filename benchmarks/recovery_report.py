"""Markdown tables of the recovery study (``recovery.py``); also read by notebook 04."""
from __future__ import annotations

from pathlib import Path


ABBREV = {"determined": "det", "lower_bound": "lb", "upper_bound": "ub", "undetermined": "und", "error": "err"}
_HEAD = ("n | W bias % | W sd % | W coverage | W status | μh bias % | μh sd % | μh coverage | μh status "
         "| slip right/wrong/undecided | errors")

LEGEND = """\
Columns: **bias** = mean of (estimate/truth − 1) over the fits that gave a value, **sd** its scatter;
**coverage** = fraction of the claims that hold the truth, with covered/claims (a two-sided interval
covers when it holds the truth, a `lower_bound` when the truth is at or above it; `undetermined`
makes no claim); `!` marks coverage below the 1 % lower binomial quantile of Bin(claims, 0.95), i.e.
too low to be chance at that replicate count; **status** counts det(ermined), lb (lower_bound),
ub (upper_bound), und(etermined), err (the fit raised); **slip** = selected condition right / wrong /
undecided (null). Noise is σ as % of the peak force.
"""


def _pct(x) -> str:
    return "–" if x is None else f"{100 * x:+.1f}"


def _sd(x) -> str:
    return "–" if x is None else f"{100 * x:.1f}"


def _cov(p: dict) -> str:
    if not p["claims"]:
        return "–"
    flag = " !" if p["below_binomial"] else ""
    return f"{p['coverage']:.2f} ({p['covered']}/{p['claims']}){flag}"


def _status(p: dict) -> str:
    return " ".join(f"{ABBREV[s]}{c}" for s, c in p["status"].items() if c) or "–"


def row(cell: dict) -> str:
    """The table columns of one cell (after its key columns)."""
    w, m, s = cell["work_of_adhesion"], cell["mu_h"], cell["slip_outcomes"]
    return (f"{cell['n']} | {_pct(w['bias'])} | {_sd(w['scatter'])} | {_cov(w)} | {_status(w)} | "
            f"{_pct(m['bias'])} | {_sd(m['scatter'])} | {_cov(m)} | {_status(m)} | "
            f"{s['right']}/{s['wrong']}/{s['undecided']} | {cell['errors']}")


def table(cells: list[dict], keys: tuple[str, ...]) -> str:
    """A markdown table: key columns, then :func:`row`."""
    head = " | ".join(k if k != "noise" else "noise %" for k in keys)
    lines = [f"| {head} | {_HEAD} |", "|" + "---|" * (len(keys) + _HEAD.count("|") + 1)]
    for c in sorted(cells, key=lambda c: tuple(_order(k, c[k]) for k in keys)):
        vals = " | ".join(f"{100 * c[k]:g}" if k == "noise" else str(c[k]) for k in keys)
        lines.append(f"| {vals} | {row(c)} |")
    return "\n".join(lines)


def _order(key: str, value):
    from recovery_cases import CASES, SLIPS, VARIANTS  # noqa: PLC0415
    order = {"case": list(CASES), "slip": list(SLIPS), "variant": list(VARIANTS)}.get(key)
    return order.index(value) if order and value in order else value


def _errors(out: dict) -> str:
    errs = [r for r in out["replicates"] if r.get("error")]
    if not errs:
        return "No fit raised.\n"
    seen: dict[str, int] = {}
    for r in errs:
        seen[r["error"][:160]] = seen.get(r["error"][:160], 0) + 1
    return "Fits that raised (message: count):\n\n" + "\n".join(f"- `{m}`: {n}" for m, n in seen.items()) + "\n"


def _bounds(out: dict) -> str:
    """Per variant: how tight the one-sided W_ad bounds are, against the largest G the test reached."""
    lines = []
    for variant in dict.fromkeys(r["variant"] for r in out["replicates"]):
        rr = [r for r in out["replicates"] if r["variant"] == variant
              and r["work_of_adhesion"]["status"] == "lower_bound"]
        if rr:
            t = rr[0]["truth"]["work_of_adhesion"]
            ratio = sorted(r["work_of_adhesion"]["lo"] / t for r in rr)
            g = sorted(r["truth"]["G_max_reached"] / t for r in rr)
            lines.append(f"- {variant}: {len(rr)} lower bounds, bound/truth median {ratio[len(ratio) // 2]:.3f} "
                         f"(range {ratio[0]:.3f}–{ratio[-1]:.3f}); largest G reached/truth median "
                         f"{g[len(g) // 2]:.3f}")
    return ("W_ad reported as a lower bound:\n\n" + "\n".join(lines) + "\n") if lines else "No lower bounds.\n"


def _duplicates(out: dict) -> str:
    dup = [c for c in out["cells"] if c["variant"] == "duplicated"]
    if not dup:
        return "Not run.\n"
    warned, n = sum(c["warned_duplicates"] for c in dup), sum(c["n"] for c in dup)
    return f"A warning names the duplicated rows in {warned} of {n} fits of the duplicated variant.\n"


def write_markdown(out: dict, path: Path) -> None:
    """OUT.md: provenance, the pooled table (variant x noise), the per-cell table, failures."""
    p, st = out["provenance"], out["settings"]
    text = [f"# Parameter recovery ({st['method']})\n",
            f"Command: `{p['command']}`  \nadhfit commit {p['commit']}, "
            f"{p['date_utc']} UTC, {len(out['replicates'])} fits in "
            f"{'?' if p['wall_s'] is None else round(p['wall_s'])} s on {p['workers']} "
            f"worker(s), Python {p['python']}, {p['nproc']} cores.\n" + (f"\n**{p['partial']}**\n" if p.get("partial") else ""),
            f"Truth: W_ad = {st['truth']['work_of_adhesion']} J/m², μh = {st['truth']['mu_h']} N/m; "
            "every curve is written to CSV and fitted with default options (`fit_curve(path, scene)`, "
            "both slip conditions compared). Variants: clean; baseline (+"
            f"{100 * st['baseline_fraction']:g} % of the peak force on every row); trunc-turn (stopped 5–15 "
            "rows after the end of loading); trunc-pinning (stopped inside pinning); trunc-delamination "
            "(stopped inside delamination before pull-off; not for pressure control on a flat substrate, "
            "where pull-off ends pinning); duplicated (every row twice); drift (a load-cell zero drifting "
            f"linearly from 0 to {100 * st.get('drift_fraction', 0.01):g} % of the peak force over the "
            "test).\n", LEGEND,
            issue20_markdown(out),
            "## Pooled over cases and slip conditions\n", table(out["pooled"], ("variant", "noise")), "",
            "## Per case\n", table(out["cells"], ("case", "slip", "variant", "noise")), "",
            "## Failures\n", _errors(out), "## Duplicated rows\n", _duplicates(out),
            "## One-sided bounds\n", _bounds(out)]
    path.write_text("\n".join(text), encoding="utf-8")


# --- issue 20's "Done when" ---------------------------------------------------------------------------
ISSUE20_LEGEND = """\
Per noise level, pooled over the cases and both true slips. **pooled** = the reported intervals (the
slip verdict's parameters, as a user reads them) holding the truth, k/n, with the two-sided 95 %
Clopper–Pearson interval; target ≥ {pooled:.2f} (✓ the rate meets it, ✓✓ the whole CP interval is above
it, ✗ the rate is below it). **own slip** = the per-slip fit of the TRUE slip condition (report `fits`),
its W_ad interval; target ≥ {own:.2f}. **early** = fits whose model detaches ≥ {early} rows before the
data's jump: the fit's `fits[slip].first_detached_row` (the model's first detached row) against the
first row past the true turning point (where the generated force drops to zero; `detect_jump` on the
CSV's force is recorded too but misses real jumps at 3–5 % noise, see below), counted over both slips'
fits of a curve (curves with any early fit; in brackets: those where the reported fit is early).
**1 row early**: curves with a fit detaching exactly one row early (within what a W_ad change of
about one standard error can do; not counted as early). **words** = uses of each evidence word, right/wrong
(the favoured slip against the true one). **selected** = slip `selected` (very strong only) right / wrong
/ null.
"""

_WORD_ORDER = ("very strong", "strong", "positive", "cannot tell", "none")


def _prop(p: dict, target: float | None = None) -> str:
    if not p["n"]:
        return "–"
    lo, hi = p["cp"]
    mark = ""
    if target is not None:
        mark = " ✓✓" if lo >= target else " ✓" if p["rate"] >= target else " ✗"
    return f"{p['rate']:.3f} ({p['k']}/{p['n']}) [{lo:.3f}, {hi:.3f}]{mark}"


def _words(words: dict) -> str:
    return ", ".join(f"{w} {words[w]['right']}/{words[w]['wrong']}" for w in _WORD_ORDER if w in words) or "–"


def _issue20_table(cells: list[dict], keys: tuple[str, ...], pooled: float, own: float) -> str:
    head = " | ".join(k if k != "noise" else "noise %" for k in keys)
    cols = ("n | W_ad pooled | μh pooled | W_ad own slip | μh own slip | early (reported) | 1 row early "
            "| words right/wrong | selected r/w/null")
    lines = [f"| {head} | {cols} |", "|" + "---|" * (len(keys) + cols.count("|") + 1)]
    for c in sorted(cells, key=lambda c: tuple(_order(k, c[k]) for k in keys)):
        vals = " | ".join(f"{100 * c[k]:g}" if k == "noise" else str(c[k]) for k in keys)
        e, s = c["early"], c["selected"]
        lines.append(f"| {vals} | {c['n']} | {_prop(c['pooled']['work_of_adhesion'], pooled)} | "
                     f"{_prop(c['pooled']['mu_h'], pooled)} | {_prop(c['own_slip']['work_of_adhesion'], own)} | "
                     f"{_prop(c['own_slip']['mu_h'])} | {len(e['any'])} ({len(e['reported'])}) | "
                     f"{len(e['one_row'])} | {_words(c['words'])} | {s['right']}/{s['wrong']}/{s['undecided']} |")
    return "\n".join(lines)


def issue20_markdown(out: dict) -> str:
    """The section of OUT.md that checks issue 20's replicate-study targets."""
    from recovery_stats import EARLY_ROWS, TARGET_OWN_SLIP, TARGET_POOLED  # noqa: PLC0415
    i20 = out.get("issue20")
    if not i20:
        return ""
    text = ["## Issue 20 targets\n", ISSUE20_LEGEND.format(pooled=TARGET_POOLED, own=TARGET_OWN_SLIP,
                                                          early=EARLY_ROWS),
            _issue20_table(i20["pooled"], ("variant", "noise"), TARGET_POOLED, TARGET_OWN_SLIP), "",
            "### Per case and true slip\n",
            _issue20_table(i20["cells"], ("case", "slip", "variant", "noise"), TARGET_POOLED, TARGET_OWN_SLIP), ""]
    early = [x for c in i20["cells"] for x in c["early"]["any"]]
    late = [x for c in i20["cells"] for x in c["early"]["late"]]
    nodet = [x for c in i20["cells"] for x in c["early"]["no_detected_jump"]]
    diff = [x for c in i20["cells"] for x in c["early"]["vs_detected_differs"]]
    off = [x for c in i20["cells"] for x in c["early"]["detected_not_true"]]
    fail = [x for c in i20["cells"] for x in c["early"]["not_success"]]
    text.append("### Early-detachment optima (case, true slip, noise, replicate, rows early per slip fit)\n")
    text.append("\n".join(f"- `{x}`" for x in early) if early else "None.")
    text.append(f"\nFits detaching ≥ {EARLY_ROWS} rows after the data's jump: "
                + (", ".join(f"`{x}`" for x in late) if late else "none") + ".")
    n_ok = sum(c["with_fits"] for c in i20["cells"])
    text.append(f"`detect_jump` found no jump in {len(nodet)} of {n_ok} curves (per cell: "
                + ", ".join(f"{c['case']} {c['slip']} {100 * c['noise']:g} %: {len(c['early']['no_detected_jump'])}"
                            for c in i20["cells"] if c["early"]["no_detected_jump"]) + ")"
                + f"; where it found one, a fit's row differs from it otherwise than from the true row in {len(diff)}"
                + "; where its row differs from the first row past the true turning point (detected, true): "
                + (", ".join(f"`{x}`" for x in off) if off else "none") + ".")
    text.append("Per-slip fits with `success` false: " + (", ".join(f"`{x}`" for x in fail) if fail else "none")
                + ".\n")
    return "\n".join(text)
