"""Tables of the slip-verdict calibration (``verdict_calibration.py``): how often each evidence word was wrong.

A record is one fit: the true slip, the ``favoured`` slip (lower BIC), the evidence word of the
ΔBIC scale (``adhfit.fitting.selection.SCALE``), ΔBIC and whether a slip was ``selected``.  A word's
use is *wrong* when the favoured slip is not the true one, whatever the word (a "cannot tell" is
wrong about half the time by construction: it says so).  A fit that raised has no word and is counted
apart.

The bound on a wrong-rate is the upper end of the two-sided 95 % Clopper-Pearson interval,
``beta.ppf(0.975, k + 1, n - k)`` for k wrong of n uses (1 when k = n): a rate that is in truth at that
bound would give k or fewer wrong uses with probability 2.5 %.
"""
from __future__ import annotations

from pathlib import Path

from scipy import stats

from adhfit.fitting.selection import SCALE

#: the evidence words, weakest first
WORDS = tuple(word for _, word in SCALE)
#: the promise of issue 20: largest acceptable wrong-rate per word
PROMISE = {"very strong": 0.01, "strong": 0.05}
LEVEL = 0.95
WRONG_FIELDS = ("case", "slip", "variant", "noise", "rep", "favoured", "evidence", "delta_bic", "spawn_key",
                "truth", "fits")


def clopper_pearson(k: int, n: int, level: float = LEVEL) -> tuple[float, float] | tuple[None, None]:
    """Two-sided Clopper-Pearson interval of a binomial proportion (dimensionless).

    Parameters
    ----------
    k, n : int
        Successes (here: wrong verdicts) and trials (uses); 0 <= k <= n.
    level : float
        Confidence level of the two-sided interval.

    Returns
    -------
    (lo, hi)
        The interval; ``(None, None)`` when n = 0 (no uses: no claim).
    """
    if not 0 <= k <= n:
        raise ValueError(f"The counts must satisfy 0 <= k <= n. Got k={k}, n={n} instead.")
    if n == 0:
        return None, None
    tail = (1.0 - level) / 2
    lo = 0.0 if k == 0 else float(stats.beta.ppf(tail, k, n - k + 1))
    hi = 1.0 if k == n else float(stats.beta.ppf(1.0 - tail, k + 1, n - k))
    return lo, hi


def is_wrong(rec: dict) -> bool:
    """The favoured slip is not the true one."""
    return rec["favoured"] != rec["slip"]


def word_row(recs: list[dict], word: str) -> dict:
    """Uses, wrong uses, wrong-rate, its Clopper-Pearson bounds and the promise check of one word."""
    used = [r for r in recs if r.get("evidence") == word]
    wrong = sum(is_wrong(r) for r in used)
    lo, hi = clopper_pearson(wrong, len(used))
    promise = PROMISE.get(word)
    return {"word": word, "uses": len(used), "wrong": wrong,
            "rate": wrong / len(used) if used else None, "cp_lo": lo, "cp_hi": hi, "promise": promise,
            "rate_within": None if promise is None or not used else wrong / len(used) <= promise,
            "bound_within": None if promise is None or not used else hi <= promise}


def word_table(recs: list[dict]) -> list[dict]:
    """:func:`word_row` of every word of the scale, weakest first."""
    return [word_row(recs, w) for w in WORDS]


def grouped(recs: list[dict], key: str) -> dict:
    """Per value of ``key`` (first-seen order): the fits, errors and the word table."""
    groups: dict = {}
    for r in recs:
        groups.setdefault(r[key], []).append(r)
    return {str(k): {"fits": len(v), "errors": sum(r.get("error") is not None for r in v),
                     "words": word_table(v)} for k, v in groups.items()}


def summarize(recs: list[dict]) -> dict:
    """Every table of the report: overall, per noise, per variant, per case x slip; wrong strong uses."""
    for r in recs:
        r["case_slip"] = f"{r['case']} / {r['slip']}"
        r["noise_pct"] = f"{100 * r['noise']:g}"
    ok = [r for r in recs if r.get("error") is None]
    selected = [r for r in ok if r.get("selected")]
    strong = [r for r in ok if r.get("evidence") in PROMISE and is_wrong(r)]
    return {"fits": len(recs), "errors": len(recs) - len(ok),
            "selected": len(selected), "selected_wrong": sum(r["selected"] != r["slip"] for r in selected),
            "words": word_table(ok),
            "by_noise": grouped(sorted(recs, key=lambda r: r["noise"]), "noise_pct"),
            "by_variant": grouped(recs, "variant"),
            "by_case_slip": grouped(recs, "case_slip"),
            "by_commit": grouped([dict(r, commit=r.get("commit") or "?") for r in recs], "commit"),
            "commands": _commands(recs),
            "wrong_strong": [{k: r.get(k) for k in WRONG_FIELDS} for r in strong]}


def _commands(recs: list[dict]) -> list[dict]:
    """The runs the records came from (commit, command, fits), in first-seen order; records of runs that did
    not record them count under ``?``."""
    seen: dict[tuple, int] = {}
    for r in recs:
        key = (r.get("commit") or "?", r.get("command") or "?")
        seen[key] = seen.get(key, 0) + 1
    return [{"commit": c, "command": m, "fits": n} for (c, m), n in seen.items()]


def _sources(t: dict) -> str:
    if [c["commit"] for c in t.get("commands", [])] in ([], ["?"]):
        return ""
    lines = "\n".join(f"- {c['fits']} fits at commit {c['commit']}: `{c['command']}`" for c in t["commands"])
    return ("## Per source (the commit each record came from)\n\n" + lines + "\n\n"
            + cross(t["by_commit"], "commit") + "\n")


def _run(run: dict | None) -> str:
    """The facts of the run that made the records, when the report was remade from them."""
    if not run:
        return ""
    return (f"\nThe fits: `{run['command']}`, {run['date_utc']} UTC (ended), {run['wall_s']} s on {run['workers']} "
            f"worker(s), load average {run['load_start']} at start, {run['load_end']} at end; commit {run['commit']} "
            f"at the end of the run, adhfit/ last changed in {run.get('adhfit_last_changed')}.\n")


def _pct(x) -> str:
    return "–" if x is None else f"{100 * x:.1f} %"


def _yes(x) -> str:
    return "–" if x is None else ("yes" if x else "**no**")


def headline(words: list[dict]) -> str:
    """Markdown: one row per word (uses, wrong, rate, 95 % CP interval, promise)."""
    lines = ["| evidence | uses | wrong | wrong-rate | CP 95 % interval | promise | rate within | "
             "upper bound within |", "|---|---|---|---|---|---|---|---|"]
    for w in words:
        ci = "–" if w["cp_hi"] is None else f"[{_pct(w['cp_lo'])}, {_pct(w['cp_hi'])}]"
        promise = "–" if w["promise"] is None else f"≤ {_pct(w['promise'])}"
        lines.append(f"| {w['word']} | {w['uses']} | {w['wrong']} | {_pct(w['rate'])} | {ci} | {promise} | "
                     f"{_yes(w['rate_within'])} | {_yes(w['bound_within'])} |")
    return "\n".join(lines)


def cross(groups: dict, label: str) -> str:
    """Markdown: one row per group, per word ``wrong/uses (upper bound)``."""
    lines = [f"| {label} | fits | errors | " + " | ".join(WORDS) + " |", "|---" * (3 + len(WORDS)) + "|"]
    for name, g in groups.items():
        cells = [f"{w['wrong']}/{w['uses']}" + ("" if w["cp_hi"] is None else f" (≤ {_pct(w['cp_hi'])})")
                 for w in g["words"]]
        lines.append(f"| {name} | {g['fits']} | {g['errors']} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def _wrong_list(rows: list[dict]) -> str:
    if not rows:
        return "None.\n"
    return "\n".join(f"- {r['case']}, true {r['slip']}, {r['variant']}, {100 * r['noise']:g} % noise, rep "
                     f"{r['rep']}: {r['favoured']} {r['evidence']} (ΔBIC = {r['delta_bic']:.1f}; spawn key "
                     f"{r['spawn_key']}){_facts(r)}" for r in rows) + "\n"


def _facts(r: dict) -> str:
    """Per slip: fitted σ / true σ, lag-1 residual autocorrelation, model's first detached row vs the truth's."""
    truth, fits = r.get("truth") or {}, r.get("fits") or {}
    if not fits or not truth.get("sigma"):
        return ""
    parts = []
    for slip, f in fits.items():
        sig = "–" if f.get("sigma") is None else f"{f['sigma'] / truth['sigma']:.2f}"
        ac = "–" if f.get("residual_autocorrelation") is None else f"{f['residual_autocorrelation']:.2f}"
        parts.append(f"{slip}: σ/σ_true {sig}, lag-1 autocorrelation {ac}, detaches at row "
                     f"{f.get('first_detached_row')}")
    return f"; true first detached row {truth.get('first_detached_row')}; " + "; ".join(parts)


def write_markdown(out: dict, path: Path) -> None:
    """OUT.md: command and machine, the headline table, the tables per noise / variant / case, wrong strong uses."""
    p, s, t = out["provenance"], out["settings"], out["summary"]
    text = [
        "# Slip-verdict calibration\n",
        f"Command: `{p['command']}`  \nadhfit commit {p['commit']} (adhfit/ last changed in "
        f"{p.get('adhfit_last_changed')}), {p['date_utc']} UTC, {t['fits']} fits "
        f"({t['errors']} raised)" + ("; " if p.get("run") else
                                      f" in {p['wall_s']} s on {p['workers']} worker(s); ") + "machine:"
        f" nproc {p['nproc']}, load average {p['load_start']} at start, {p['load_end']} at end; "
        f"Python {p['python']}, numpy {p['numpy']}, scipy {p['scipy']}.\n"
        + (f"\n**Partial: {p['partial']}**\n" if p.get("partial") else "")
        + (f"\nReport remade from the records of {p['remade_from']}.\n" if p.get("remade_from") else "")
        + _run(p.get("run")),
        f"Curves: `benchmarks/recovery_cases.py` (W_ad = {s['truth']['work_of_adhesion']} J/m², μh = "
        f"{s['truth']['mu_h']} N/m, large-stretch membrane, about {s['rows']} rows a test), written to CSV and "
        "fitted by `adhfit.fit(path, scene, slip='auto')` with default options. Variants: clean; drift (load-cell "
        f"zero drifting linearly from 0 to {100 * s['drift_fraction']:g} % of the peak force over the test); "
        "trunc-turn / trunc-pinning / trunc-delamination (test stopped 5–15 rows after the turn, inside pinning, "
        "inside delamination). Seeds: root seed "
        f"{s['seed']}, one `SeedSequence(root, spawn_key=(case, slip, variant, noise·1e4, rep))` per fit "
        "(recorded with each fit in the JSON).\n",
        "A use of a word is **wrong** when the favoured slip (lower BIC) is not the true one. The interval is the "
        "two-sided 95 % Clopper-Pearson interval of the wrong-rate; *upper bound within* says whether its upper "
        "end is within the promise, i.e. whether these fits show the promise rather than merely not contradict "
        "it (0 wrong of n uses gives an upper bound 1 − 0.025^(1/n): n ≥ 368 is needed to show ≤ 1 %).\n",
        "## Per evidence word\n", headline(t["words"]), "",
        f"A slip was `selected` (very strong) in {t['selected']} fits, the wrong one in {t['selected_wrong']}.\n",
        "## Per noise level (σ as a fraction of the peak force): wrong/uses (CP 95 % upper bound)\n",
        cross(t["by_noise"], "noise %"), "",
        "## Per variant\n", cross(t["by_variant"], "variant"), "",
        "## Per case and true slip\n", cross(t["by_case_slip"], "case / true slip"), "",
        _sources(t),
        "## Wrong strong and very strong verdicts\n", _wrong_list(t["wrong_strong"]),
        "## Fits that raised\n", _errors(out["records"])]
    path.write_text("\n".join(text), encoding="utf-8")


def _errors(recs: list[dict]) -> str:
    seen: dict[str, int] = {}
    for r in recs:
        if r.get("error"):
            seen[r["error"][:160]] = seen.get(r["error"][:160], 0) + 1
    return "\n".join(f"- `{m}`: {n}" for m, n in seen.items()) + "\n" if seen else "None.\n"
