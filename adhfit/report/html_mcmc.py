"""The MCMC and solver-detail sections of report.html: convergence, priors, evidence and diagnostics as
tables (the report.json ``mcmc`` and ``diagnostics`` keys)."""
from __future__ import annotations

from typing import Any, Mapping

from .html_parts import details, e, num, table, value_html
from .text import display

__all__ = ["section_mcmc", "section_solver_details", "mcmc_diagnostics_by_slip"]


def _sym(name: str) -> str:
    sym, _, _, unit = display(name)
    return f"{e(sym)}" + (f" <span class=\"muted\">({e(unit)})</span>" if unit else "")


def mcmc_diagnostics_by_slip(d: Mapping[str, Any]) -> dict[str, Any]:
    """Per slip condition, the MCMC convergence diagnostics (from ``mcmc.slips`` or a dict ``diagnostics``)."""
    m = d.get("mcmc") or {}
    out = {s: v.get("diagnostics") for s, v in (m.get("slips") or {}).items() if isinstance(v, Mapping)}
    diag = d.get("diagnostics")
    if not out and isinstance(diag, Mapping):
        out = {s: v for s, v in diag.items() if isinstance(v, Mapping) and "tau" in v}
    return {s: v for s, v in out.items() if v}


def _diag_table(slip: str, g: Mapping[str, Any]) -> str:
    ok = g.get("converged")
    acc = g.get("acceptance") or {}
    head = (f"<h3>{e(slip)}: " + ("converged" if ok else "<span class=\"status-failed\">NOT CONVERGED</span>")
            + "</h3>")
    facts = [["ensembles × walkers", f"{num(g.get('n_ensembles'))} × {num(g.get('n_walkers'))}"],
             ["steps (after tuning)", f"{num(g.get('steps'))} (+{num(g.get('tune_steps'))} tuning)"],
             ["burn-in, thinning", f"{num(g.get('burn'))} steps, every {num(g.get('thin'))}"],
             ["kept samples", num(g.get("kept_samples"))],
             ["acceptance fraction", f"mean {num(acc.get('mean'), 2)} (walkers {num(acc.get('min'), 2)}–"
                                     f"{num(acc.get('max'), 2)})"],
             ["step cap hit", "<b>yes</b>" if g.get("cap_hit") else "no"]]
    rows = []
    for p in g.get("tau") or {}:
        rows.append([_sym(p), num((g.get("tau") or {}).get(p), 3), num((g.get("n_over_tau") or {}).get(p), 3),
                     num((g.get("rhat") or {}).get(p), 5), num((g.get("ess_bulk") or {}).get(p), 3),
                     num((g.get("ess_tail") or {}).get(p), 3)])
    warn = "".join(f"<div class=\"warn\">⚠ {e(w)}</div>" for w in g.get("warnings") or [])
    return (head + table([], facts, cls="inner")
            + table(["parameter", "τ (steps)", "N/τ", "R-hat", "ESS bulk", "ESS tail"], rows,
                    numeric=(1, 2, 3, 4, 5)) + warn)


def _priors(m: Mapping[str, Any]) -> str:
    pri = m.get("priors") or {}
    if not pri:
        return ""
    rows = []
    for name, p in pri.items():
        p = p if isinstance(p, Mapping) else {"description": p}
        rest = {k: v for k, v in p.items() if k not in ("description",)}
        rows.append([_sym(name), e(p["description"]) if p.get("description") else value_html(rest)])
    return ("<h3>Priors</h3>" + table(["parameter", "prior (SI units)"], rows)
            + "<p class=\"muted\">Set them in the scene's <code>[priors]</code> table (docs/contracts.md); the "
              "default is log-uniform on W_ad and μh.</p>")


def _evidence(d: Mapping[str, Any], m: Mapping[str, Any]) -> str:
    probs = m.get("model_probabilities") or {}
    p = probs.get("probabilities") or d.get("model_probabilities") or {}
    rows = []
    for s, v in (m.get("slips") or {}).items():
        ev = (v or {}).get("evidence") or {}
        rows.append([e(s), num(p.get(s), 4), num(ev.get("log_evidence"), 6), num(ev.get("stderr"), 2),
                     num(ev.get("weights_ess"), 3), num(ev.get("n_draws"))])
    if not rows:
        return ""
    note = []
    if probs.get("method"):
        note.append(f"Posterior model probabilities by {e(probs['method'])}, equal prior odds")
    if probs.get("threshold") is not None:
        note.append(f"a slip condition is selected when its probability is ≥ {num(probs['threshold'])} after "
                    "lowering ln B by two Monte-Carlo standard errors")
    expl = f" {e(probs['explanation'])}" if probs.get("explanation") else ""
    return ("<h3>Slip condition: evidence</h3>"
            + table(["slip", "probability", "ln Z (log evidence)", "MC std. error", "weights ESS", "draws"],
                    rows, numeric=(1, 2, 3, 4, 5))
            + f"<p class=\"muted\">{'; '.join(note)}.{expl}</p>")


def section_mcmc(d: Mapping[str, Any]) -> str:
    """MCMC: verdict, how it ran, priors, evidence and per-slip diagnostics (empty for least squares)."""
    m = d.get("mcmc")
    if not isinstance(m, Mapping):
        return ""
    conv = m.get("converged", d.get("converged"))
    head = ("<p class=\"ok\">The MCMC run converged (stopping rule met, R-hat ≤ 1.01 for every parameter).</p>"
            if conv else "<p class=\"bad\"><b>The MCMC run has not converged</b>: the estimates and intervals "
                         "are not reliable. See the diagnostics; run longer or check the model.</p>")
    how = [["likelihood", e(m.get("noise_model"))], ["sampler", e(m.get("sampler"))],
           ["stopping rule", e(m.get("stopping_rule"))], ["seed", e(m.get("seed"))],
           ["chains saved in", f"<code>{e(m.get('chain_file') or 'not saved')}</code>"],
           ["posterior evaluations", num(m.get("model_evaluations"))],
           ["least-squares stage", f"{num(m.get('lsq_seconds'), 3)} s"]]
    how = [r for r in how if r[1] not in ("", "n/a", " s")]
    diags = "".join(_diag_table(s, g) for s, g in mcmc_diagnostics_by_slip(d).items())
    return "\n".join(["<h2>Bayesian fit (MCMC)</h2>", head,
                      "<p>Values are posterior medians; 95 % intervals are the 2.5 and 97.5 percentiles of the "
                      "posterior (credible intervals).</p>", table([], how, cls="inner"), _priors(m),
                      _evidence(d, m), "<h3>Convergence diagnostics</h3>" + diags if diags else ""])


def section_solver_details(d: Mapping[str, Any]) -> str:
    """The ``diagnostics`` list (solver details) and each fit's optimiser message, collapsed."""
    diag = d.get("diagnostics")
    items = []
    if isinstance(diag, (list, tuple)):
        for x in diag:
            items.append(f"<li>{value_html(x)}</li>")
    rows = []
    for s, f in (d.get("fits") or {}).items():
        if not isinstance(f, Mapping):
            continue
        rows.append([e(s), "yes" if f.get("success", True) else "<b>no</b>", e(f.get("message", "")),
                     num(f.get("model_evaluations")), num(f.get("histories")),
                     "<br>".join(e(w) for w in f.get("warnings") or []) or "none"])
    body = ""
    if items:
        body += "<ul>" + "".join(items) + "</ul>"
    if rows:
        body += table(["slip", "converged", "optimiser message", "model evaluations", "histories",
                       "notes"], rows, numeric=(3, 4))
    if not body:
        return ""
    n = len(items)
    return "<h2>Solver details</h2>" + details(
        f"What the solver did{f' ({n} notes)' if n else ''} — for checking, not needed to read the results", body)
