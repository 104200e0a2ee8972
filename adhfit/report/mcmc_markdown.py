"""The MCMC sections of report.md: convergence verdict first, then the method, priors, slip
probabilities and the diagnostics table, with what to distrust said plainly."""
from __future__ import annotations

__all__ = ["mcmc_sections"]


def _f(x, fmt=".3g") -> str:
    return "n/a" if x is None else format(x, fmt)


def _diag_table(name: str, d: dict) -> list[str]:
    out = [f"### {name}: {'converged' if d['converged'] else '**NOT CONVERGED**'}", "",
           f"{d['n_ensembles']} independent ensembles × {d['n_walkers']} walkers, {d['steps']} steps after "
           f"{d['tune_steps']} tuning steps; burn-in {d['burn']} steps, thinning {d['thin']}, "
           f"{d['kept_samples']} kept samples. Acceptance fraction: mean {d['acceptance']['mean']:.2f} "
           f"(walkers {d['acceptance']['min']:.2f}–{d['acceptance']['max']:.2f}). Step cap hit: "
           f"{'**yes**' if d['cap_hit'] else 'no'}.", "",
           "| parameter | τ (steps) | N/τ | R-hat | ESS bulk | ESS tail |", "|---|---|---|---|---|---|"]
    for p in d["tau"]:
        out.append(f"| {p} | {_f(d['tau'][p])} | {_f(d['n_over_tau'][p], '.0f')} | {_f(d['rhat'][p], '.4f')} "
                   f"| {_f(d['ess_bulk'][p], '.0f')} | {_f(d['ess_tail'][p], '.0f')} |")
    out += [""] + [f"- ⚠ {w}" for w in d["warnings"]]
    return out


def mcmc_sections(result) -> list[str]:
    """Markdown lines describing an MCMC fit (:class:`~adhfit.fitting.result.FitResult` of an MCMC fit)."""
    m = result.mcmc
    probs = m["model_probabilities"]
    head = ("**The MCMC run converged** (stopping rule met, R-hat ≤ 1.01 for every parameter of every slip "
            "condition)." if m["converged"] else
            "**THE MCMC RUN HAS NOT CONVERGED**: the estimates and intervals below are not reliable "
            "(see the diagnostics; run longer or check the model).")
    out = ["## Bayesian fit (MCMC)", "", head, "",
           "Values are posterior medians ± posterior standard deviations; 95 % intervals are the 2.5 and 97.5 "
           "percentiles of the posterior (credible intervals).", "",
           f"- Likelihood: {m['noise_model']}; the residual is the least-squares one (every row and the "
           "pull-off position).",
           "- Priors: " + "; ".join(f"{k}: {v['description']}" for k, v in m["priors"].items())
           + ". Default priors are log-uniform from 1/100 of the least and 100 times the largest least-squares "
           "estimate (the same for both slip conditions); set them in the scene's [priors] table.",
           f"- Sampler: {m['sampler']}.",
           f"- Stopping rule: {m['stopping_rule']}; burn-in = tuning + 2 τ_max, thinning = τ_min/2.",
           f"- Seed {m['seed']} (numpy SeedSequence; per ensemble in report.json); chains: "
           f"`{m['chain_file'] or 'not saved'}`.", "",
           "### Slip condition", "",
           f"Posterior model probabilities ({probs['method']}, equal prior odds): "
           + ", ".join(f"{k} {v:.4g}" for k, v in probs["probabilities"].items())
           + f". Selected only when ≥ {probs['threshold']:g} after lowering ln B by two Monte-Carlo standard "
           f"errors: **{result.slip['selected'] or 'none'}**. {probs['explanation']}", ""]
    if result.slip.get("delta_bic") is not None:
        out += [f"Least squares for comparison: ΔBIC = {result.slip['delta_bic']:.1f} ({result.slip['lsq_verdict']}); "
                f"ln B ≈ ΔBIC/2 is expected for well-determined parameters.", ""]
    out += ["| slip | ln Z | MC s.e. | weights ESS | draws |", "|---|---|---|---|---|"]
    for s, v in m["slips"].items():
        e = v["evidence"]
        out.append(f"| {s} | {_f(e['log_evidence'], '.3f')} | {_f(e['stderr'], '.2g')} | {_f(e['weights_ess'], '.0f')} "
                   f"| {e['n_draws']} |")
    out += ["", "## MCMC diagnostics", ""]
    for s, v in m["slips"].items():
        out += _diag_table(s, v["diagnostics"]) + [""]
    eps = m.get("evaluations_per_second")
    out += [f"Cost: {m['model_evaluations']} posterior evaluations in the MCMC stage"
            + (f", {eps:.0f} model evaluations per second while sampling" if eps else "")
            + f"; least squares {m['lsq_seconds']:.1f} s.", ""]
    return out
