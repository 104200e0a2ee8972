"""The Bayesian fit (MCMC) in a report: whether the run converged (said first), the likelihood, sampler and
stopping rule, the priors, each slip condition's evidence and probability, and per slip condition the
convergence diagnostics (τ, N/τ, R-hat, bulk and tail ESS, acceptance).  Reads the report.json ``mcmc``,
``converged``, ``model_probabilities`` and ``diagnostics`` keys; empty for least squares."""
from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from .view import Bullets, Note, Section, Table, display, fmt

__all__ = ["convergence_note", "diagnostics_by_slip", "mcmc_section", "probabilities"]


def _converged(d: Mapping[str, Any]) -> bool | None:
    if d.get("method") != "mcmc" and not isinstance(d.get("mcmc"), Mapping):
        return None
    return d.get("converged", (d.get("mcmc") or {}).get("converged"))


def convergence_note(d: Mapping[str, Any], *, first: bool = False) -> Note | None:
    """``None`` for least squares; else whether the run converged (at the top, ``first``: only when it did not)."""
    conv = _converged(d)
    if conv is None or (first and conv):
        return None
    if conv:
        return Note(("The MCMC run converged (stopping rule met, R-hat ≤ 1.01 for every parameter).",), "ok")
    return Note(("The MCMC run has NOT CONVERGED: do not trust these values and intervals. See the convergence "
                 "diagnostics below; run longer or check the model.",), "bad")


def probabilities(d: Mapping[str, Any]) -> dict[str, Any]:
    """Posterior probability of each slip condition (empty for least squares)."""
    m = d.get("mcmc") or {}
    return dict((m.get("model_probabilities") or {}).get("probabilities") or d.get("model_probabilities")
                or (d.get("slip") or {}).get("probabilities") or {})


def diagnostics_by_slip(d: Mapping[str, Any]) -> dict[str, Any]:
    """Per slip condition, the MCMC convergence diagnostics (from ``mcmc.slips`` or a dict ``diagnostics``)."""
    m = d.get("mcmc") or {}
    out = {s: v.get("diagnostics") for s, v in (m.get("slips") or {}).items() if isinstance(v, Mapping)}
    diag = d.get("diagnostics")
    if not any(out.values()) and isinstance(diag, Mapping):
        out = {s: v for s, v in diag.items() if isinstance(v, Mapping) and "tau" in v}
    return {s: v for s, v in out.items() if v}


def _sym(name: str) -> str:
    sym, _, _, unit = display(name)
    return sym + (f" ({unit})" if unit else "")


def _diagnostics(slip: str, g: Mapping[str, Any]) -> Section:
    acc = g.get("acceptance") or {}
    facts = (("ensembles × walkers", f"{fmt(g.get('n_ensembles'))} × {fmt(g.get('n_walkers'))}"),
             ("steps (after tuning)", f"{fmt(g.get('steps'))} (+{fmt(g.get('tune_steps'))} tuning)"),
             ("burn-in, thinning", f"{fmt(g.get('burn'))} steps, every {fmt(g.get('thin'))} "
                                   "(burn-in = tuning + 2 τ_max, thinning = τ_min/2)"),
             ("kept samples", fmt(g.get("kept_samples"))),
             ("acceptance fraction", f"mean {fmt(acc.get('mean'), 2)} (walkers {fmt(acc.get('min'), 2)}–"
                                     f"{fmt(acc.get('max'), 2)})"),
             ("step cap hit", "YES" if g.get("cap_hit") else "no"))
    tau = g.get("tau") or {}
    rows = tuple((_sym(p), fmt(tau.get(p), 3), fmt((g.get("n_over_tau") or {}).get(p), 3),
                  fmt((g.get("rhat") or {}).get(p), 5), fmt((g.get("ess_bulk") or {}).get(p), 3),
                  fmt((g.get("ess_tail") or {}).get(p), 3)) for p in tau)
    blocks: list[Any] = [Table(("", ""), facts),
                         Table(("parameter", "τ (steps)", "N/τ", "R-hat", "ESS bulk", "ESS tail"), rows,
                               numeric=(1, 2, 3, 4, 5))]
    if g.get("warnings"):
        blocks.append(Bullets(tuple(str(w) for w in g["warnings"]), "warn"))
    return Section(f"{slip}: {'converged' if g.get('converged') else 'NOT CONVERGED'}", tuple(blocks))


def _priors(m: Mapping[str, Any]) -> Section | None:
    pri = m.get("priors") or {}
    if not pri:
        return None
    rows = []
    for name, p in pri.items():
        p = p if isinstance(p, Mapping) else {"description": p}
        text = p.get("description") or "; ".join(f"{k} {v}" for k, v in p.items())
        rows.append((_sym(name), str(text)))
    return Section("Priors", (Table(("parameter", "prior (SI units)"), tuple(rows)),
                              Note(("Set them in the scene's [priors] table (docs/contracts.md). The default is "
                                    "log-uniform on W_ad and μh, from 1/100 of the least to 100 times the largest "
                                    "least-squares estimate (the same for both slip conditions).",), "muted")))


def _evidence(d: Mapping[str, Any], m: Mapping[str, Any]) -> Section | None:
    probs = m.get("model_probabilities") or {}
    p = probabilities(d)
    rows = tuple((s, fmt(p.get(s), 4), fmt(ev.get("log_evidence"), 6), fmt(ev.get("stderr"), 2),
                  fmt(ev.get("weights_ess"), 3), fmt(ev.get("n_draws")))
                 for s, v in (m.get("slips") or {}).items() for ev in [(v or {}).get("evidence") or {}])
    if not rows:
        return None
    note = []
    if probs.get("method"):
        note.append(f"Posterior model probabilities by {probs['method']}, equal prior odds")
    if probs.get("threshold") is not None:
        note.append(f"a slip condition is selected when its probability is ≥ {fmt(probs['threshold'])} after "
                    "lowering ln B by two Monte-Carlo standard errors")
    slip = d.get("slip") or {}
    text = "; ".join(note) + "." + (f" {probs['explanation']}" if probs.get("explanation") else "")
    if slip.get("delta_bic") is not None:
        text += (f" Least squares for comparison: ΔBIC = {fmt(slip['delta_bic'], 4)}"
                 + (f" ({slip['lsq_verdict']})" if slip.get("lsq_verdict") else "")
                 + "; ln B ≈ ΔBIC/2 is expected for well-determined parameters.")
    return Section("Slip condition: evidence", (
        Table(("slip", "probability", "ln Z (log evidence)", "MC std. error", "weights ESS", "draws"), rows,
              numeric=(1, 2, 3, 4, 5)), Note((text,), "muted")))


def _how(m: Mapping[str, Any]) -> Table:
    eps = m.get("evaluations_per_second")
    rows = (("likelihood", m.get("noise_model")), ("sampler", m.get("sampler")),
            ("stopping rule", m.get("stopping_rule")), ("seed", m.get("seed")),
            ("chains saved in", m.get("chain_file") or "not saved"),
            ("posterior evaluations", fmt(m.get("model_evaluations"))),
            ("model evaluations per second while sampling", f"{eps:.0f}" if eps else None),
            ("least-squares stage", f"{fmt(m.get('lsq_seconds'), 3)} s" if m.get("lsq_seconds") is not None
             else None))
    return Table(("", ""), tuple((k, str(v)) for k, v in rows if v not in (None, "", "n/a")))


def mcmc_section(d: Mapping[str, Any]) -> Section | None:
    """The Bayesian fit (MCMC) section; ``None`` for least squares."""
    m = d.get("mcmc")
    if not isinstance(m, Mapping):
        return None
    diags = tuple(_diagnostics(s, g) for s, g in diagnostics_by_slip(d).items())
    parts = [convergence_note(d),
             Note(("Values are posterior medians; 95 % intervals are the 2.5 and 97.5 percentiles of the posterior "
                   "(credible intervals). The likelihood uses the least-squares residual (every row and the "
                   "pull-off position).",)),
             _how(m), _priors(m), _evidence(d, m),
             Section("Convergence diagnostics", diags) if diags else None]
    return Section("Bayesian fit (MCMC)", tuple(p for p in parts if p is not None))
