"""MCMC of a test series (issue 13, docs/contracts.md A7): ``fit_global(..., method="mcmc")``.

The single-curve MCMC (:mod:`.mcmc_fit`) on the joint model of :mod:`.series`:

1. **least squares first**: :func:`.global_stage.joint_stage` (each curve alone, the joint fit per slip
   condition, each curve's noise levels, the row splits, ΔBIC).  Its optimum and covariance start the
   walkers and the first proposal; its row splits are kept.
2. **the joint posterior** of each slip condition (:class:`SeriesTarget`), sampled by
   :func:`.mcmc.sample_posterior`: θ = (ln W_ad, ln μh, then per curve its offsets in the single-curve
   internal units).  The likelihood is Gaussian per *block* (one curve's force rows with its pull-off
   term, one curve's contact-radius rows), each block with its own σ: given (``sigma``,
   ``sigma_contact_radius``) or integrated out under p(σ) ∝ 1/σ, block by block, exactly as the
   single-curve posterior does for its one σ (:mod:`.posterior`).  Priors: :func:`.posterior.default_priors`
   per curve (the shared values' prior from the joint least-squares estimates of both slip
   conditions, or the scenes' ``[priors]``, which must then agree).
3. **slip condition**: each evidence by importance sampling (:mod:`.evidence`); model probabilities
   and the verdict as for one curve; undecided -> the reported estimates average both posteriors.  A
   condition the joint least-squares fit already rejects (ΔBIC > :data:`REJECT_DBIC`) gets a short run
   (:data:`SHORT_RUN` steps) for its evidence; its chains need not converge when its probability stays
   below 1e-6 (the misfit posterior of the wrong condition is what mixes slowly).
4. **estimates**: posterior median, sd and 2.5/97.5 percentiles of the shared W_ad and μh (status from
   the prior edges, as for one curve); each curve's offsets likewise in ``curves[].offsets``.  The
   per-curve checks (χ², pull, contribution) are the least-squares joint fit's.
"""
from __future__ import annotations

import dataclasses
import math
import time

import numpy as np

from ..errors import InputError
from .diagnostics import diagnose
from .evidence import StudentT, importance_evidence, model_probabilities
from .global_posterior import SHARED, SeriesTarget, checked_covariance, series_priors
from .global_stage import joint_stage
from .mcmc import ParallelMap, default_workers, sample_posterior
from .mcmc_fit import CI_METHOD, _estimates, _mixture, _verdict
from .model import OFFSET_NAME
from .options import DEFAULT_POINTS
from .result import FitResult
from .selection import compare

__all__ = ["DEFAULTS", "SeriesTarget", "checked_covariance", "fit_global_mcmc", "series_priors"]

#: run settings: n_walkers is raised to 2·ndim (16 for three curves), so two ensembles make the 32 walkers a
#: step of the single-curve default (4 x 8); R-hat compares the two independent ensembles.  The proposal
#: is refitted after each of up to ``tune_rounds`` rounds, until it settles (:func:`.mcmc.sample_posterior`):
#: with the contact radius the posterior is skewed near each curve's fold, the least-squares start scales
#: can be 2-7 times too small, and one refit from 7 steps left τ at ~10-30 steps (not converged at 400);
#: 3-7 rounds of 20 steps give τ 3-4, so 200-400 kept steps (800 is the cap)
DEFAULTS = {"n_walkers": 8, "n_ensembles": 2, "tune_steps": 20, "tune_rounds": 12, "check_every": 5,
            "max_steps": 800, "evidence_draws": 300}

#: a slip condition whose joint least-squares BIC is this far above the other's (a Bayes factor near
#: e^-50) gets a short run (:data:`SHORT_RUN` steps): enough for its evidence, whose only use is to
#: confirm the verdict; its chains are not required to converge (:func:`_converged`)
REJECT_DBIC = 100.0
SHORT_RUN = 60


def _rejected(joint_bic: dict) -> set:
    best = min(joint_bic.values())
    return {s for s, b in joint_bic.items() if b - best > REJECT_DBIC}


def _converged(diags: dict, probs: dict, rejected: set) -> bool:
    """Every condition's chains converged, except a rejected one (:data:`REJECT_DBIC`) whose posterior
    probability stays below 1e-6 even with its log evidence raised by 20 Monte-Carlo standard errors."""
    p = probs["probabilities"]
    se = probs.get("log_bayes_factor_stderr") or 0.0
    return all(d["converged"] or (s in rejected and p[s] * math.exp(min(20.0 * se, 50.0)) < 1e-6)
               for s, d in diags.items())


def _run(targets, joint, cfg, root, path, pmap, progress, rejected=frozenset()) -> tuple[dict, dict, dict, dict]:
    """Sample and weigh every slip condition: (chains, diagnostics, SI samples, evidences)."""
    chains, diags, samples, evid = {}, {}, {}, {}
    for (s, tg), ss in zip(targets.items(), root.spawn(len(targets))):
        best = joint[s].best
        theta0 = np.array([best.params[n].value for n in tg.internal])
        cov0 = best.covar if best.covar is not None else np.diag(np.full(tg.ndim, 0.05**2))
        cov0, ratios = checked_covariance(tg, theta0, cov0)
        ss_run, ss_ev = ss.spawn(2)
        chains[s] = sample_posterior(tg, theta0, cov0, seed=int(ss_run.generate_state(1)[0]),
                                     n_walkers=cfg["n_walkers"], n_ensembles=cfg["n_ensembles"],
                                     tune_steps=cfg["tune_steps"], tune_rounds=cfg["tune_rounds"],
                                     check_every=cfg["check_every"],
                                     max_steps=min(cfg["max_steps"], SHORT_RUN) if s in rejected else cfg["max_steps"],
                                     path=path, group=s, pmap=pmap, progress=progress)
        diags[s] = diagnose(chains[s], tg.names)
        diags[s]["short_run"] = s in rejected
        diags[s]["start_scale_corrections"] = {n: float(x) for n, x in zip(tg.names, ratios) if x != 1.0}
        flat = chains[s].flat
        samples[s] = tg.to_si(flat)
        ll = pmap.register(tg.log_likelihood)
        evid[s] = importance_evidence(tg.log_prior, lambda th, ll=ll: np.array(pmap.map(ll, list(th))),
                                      StudentT.fit(flat, df=5.0, inflate=1.2), cfg["evidence_draws"],
                                      np.random.default_rng(ss_ev))
    return chains, diags, samples, evid


def _reported(samples, probs, verdict, fits, targets, rng) -> dict:
    """The reported shared estimates: the selected condition's, or the probability-weighted mixture."""
    rep = verdict["parameters_from"]
    if verdict["selected"] is not None or len(samples) == 1:
        return dict(fits[rep].parameters)
    mixed = _mixture({s: x[:, :2] for s, x in samples.items()}, probs["probabilities"], rng)
    note = CI_METHOD + ", averaged over both slip conditions (weights = model probabilities)"
    return {k: dataclasses.replace(e, ci_method=note)
            for k, e in _estimates(mixed, list(SHARED), {}, targets[rep].priors[:2]).items()}


def _offset_entries(curves: tuple, target: SeriesTarget, samples: np.ndarray) -> list[dict]:
    """``curves`` with each offset replaced by its posterior median, sd and 2.5/97.5 percentiles."""
    out = []
    for i, c in enumerate(curves):
        c = dict(c, offsets={k: dict(v) for k, v in c["offsets"].items()})
        for k, name in enumerate(target.names):
            base, _, idx = name.rpartition("_")
            if idx != str(i) or base not in (*OFFSET_NAME.values(), "force_offset"):
                continue
            lo, med, hi = np.percentile(samples[:, k], [2.5, 50.0, 97.5])
            short = base.removesuffix("_offset")
            c["offsets"][short] = dict(c["offsets"].get(short, {}), value=float(med), ci95=[float(lo), float(hi)],
                                       stderr=float(np.std(samples[:, k], ddof=1)), method=CI_METHOD)
        out.append(c)
    return out


def _warnings(lsq_result, reported, verdict, diags, probs, fits, converged) -> list[str]:
    from .series_checks import _status_warnings  # noqa: PLC0415
    drop = ("The series cannot decide", "The series only bounds", "The series does not determine",
            "The force noise of at least one curve is correlated")
    out = [w for w in lsq_result.warnings if not w.startswith(drop)]
    bad = [s for s, d in diags.items() if not d["converged"]]
    if bad and not converged:
        out.insert(0, "MCMC NOT CONVERGED for: " + ", ".join(bad) + " — do not trust these intervals "
                      "(see the diagnostics)")
    elif bad:
        out.append(f"The chains of {', '.join(bad)} were a short run and did not converge: the joint least-squares "
                   f"fit already rejects it (ΔBIC > {REJECT_DBIC:g}) and its posterior probability stays below 1e-6 "
                   f"whatever the sampling error, so the verdict and the reported values do not depend on it.")
    if not probs["reliable"]:
        out.append("the evidence estimate is unreliable (few effective importance weights)")
    if verdict["selected"] is None and len(fits) > 1:
        out.append(f"The series cannot decide between no-slip and frictionless contact "
                   f"({verdict['explanation'].rstrip('.')}). The estimates average both conditions' posteriors, "
                   f"weighted by their probabilities.")
    rep = fits[verdict["parameters_from"]]
    if rep.widening > 1.0:
        out.append(f"The force noise of at least one curve is correlated from row to row (lag-1 autocorrelation "
                   f"{rep.autocorrelation:.2f}); the posterior assumes independent noise, so its intervals may be "
                   f"about {rep.widening:.2g}-fold too narrow.")
    return out + _status_warnings(reported)


def _summary(targets, chains, diags, evid, probs, cfg, seed, workers, stage, path, t_lsq, n_evals,
             converged) -> dict:
    rep = probs["favoured"]
    mc_time = sum(c.wall_time for c in chains.values())
    mc_evals = sum(c.n_evaluations for c in chains.values())
    return {
        "seed": seed, "noise_model": targets[rep].noise_model, "converged": converged,
        "priors": {k: p.as_dict() for k, p in zip(targets[rep].names, targets[rep].priors)},
        "settings": cfg | {"workers": workers},
        "sampler": "emcee EnsembleSampler; moves: independence Metropolis-Hastings from a Student-t refitted "
                   f"after each of up to {cfg['tune_rounds']} tuning rounds (90 %) + differential evolution (10 %); "
                   "see adhfit.fitting.mcmc",
        "stopping_rule": "kept chain > 50 tau_max and every tau changed < 1 % between checks, or the step cap "
                         f"({SHORT_RUN} steps for a condition the least-squares fit rejects by ΔBIC > {REJECT_DBIC:g})",
        "short_runs": sorted(s for s, d in diags.items() if d.get("short_run")),
        "likelihood": "joint: every curve's force rows (and pull-off term) and contact-radius rows, one sigma per "
                      "block; row splits fixed at the least-squares joint optimum",
        "model_probabilities": probs,
        "slips": {s: {"parameters": targets[s].names, "diagnostics": diags[s], "evidence": evid[s].as_dict(),
                      "ensemble_seeds": chains[s].seeds, "chain_groups": chains[s].groups,
                      "mcmc_seconds": chains[s].wall_time, "posterior_evaluations": chains[s].n_evaluations}
                  for s in targets},
        "chain_file": str(path) if path is not None and any(c.groups for c in chains.values()) else None,
        "lsq_estimates": {s: {k: e.value for k, e in f.parameters.items()} for s, f in stage.fits.items()},
        "lsq_seconds": t_lsq, "model_evaluations": n_evals,
        "evaluations_per_second": mc_evals / mc_time if mc_time > 0 else None,
    }


def fit_global_mcmc(curves, scenes, *, slip: str = "auto", sigma: float | None = None,
                    sigma_contact_radius: float | None = None, contact_radius: bool = True,
                    fit_x_offset: bool | None = None, fit_force_offset: bool = True, seed: int | None = None,
                    points: int = DEFAULT_POINTS, outdir=None, workers: int | None = None,
                    progress: bool | None = None, **settings) -> FitResult:
    """Bayesian global fit of a test series: shared W_ad and μh, offsets per curve, the slip condition's
    probability on the joint fit (module docstring).

    Parameters
    ----------
    curves, scenes, slip, sigma, sigma_contact_radius, contact_radius, fit_x_offset, fit_force_offset, points
        As for :func:`.global_fit.fit_global`.
    seed : int, optional
        Root seed of every random number; drawn from fresh entropy and recorded when not given.
    outdir : path, optional
        Where ``chain.h5`` is written (one group per slip condition).
    workers : int, optional
        Processes for likelihood evaluations (default: up to 2); results do not depend on it.
    progress : bool, optional
        tqdm bar on standard error (default: only on a terminal).
    **settings
        Override :data:`DEFAULTS`.

    Returns
    -------
    FitResult
        With ``sampling`` (the run's summary and samples) and ``curves``.
        With ``curves`` (offsets as posterior summaries) and ``mcmc``.
    """
    from .series_checks import assemble  # noqa: PLC0415
    t0 = time.perf_counter()
    if set(settings) - set(DEFAULTS):
        bad = sorted(set(settings) - set(DEFAULTS))[0]
        raise InputError(bad, settings[bad], "one of " + ", ".join(DEFAULTS))
    cfg = DEFAULTS | settings
    seed = int(np.random.SeedSequence().entropy % 2**63) if seed is None else int(seed)
    stage = joint_stage(curves, scenes, slip=slip, sigma=sigma, sigma_contact_radius=sigma_contact_radius,
                        contact_radius=contact_radius, fit_x_offset=fit_x_offset, fit_force_offset=fit_force_offset,
                        points=points, profile=False)
    t_lsq = time.perf_counter() - t0
    lsq_verdict = compare({s: f.bic for s, f in stage.fits.items()}, {s: f.aic for s, f in stage.fits.items()})
    names, priors = series_priors(stage.joint, stage.scenes)
    targets = {s: SeriesTarget(sf, names, priors) for s, sf in stage.joint.items()}
    path = _chain_path(outdir)
    root = np.random.SeedSequence(seed)
    run_seed, rest = root.spawn(2)
    n_workers = default_workers() if workers is None else int(workers)
    with ParallelMap(n_workers) as pmap:
        rejected = _rejected({s: f.bic for s, f in stage.fits.items()})
        chains, diags, samples, evid = _run(targets, stage.joint, cfg, run_seed, path, pmap, progress, rejected)
        n_evals = pmap.n_evaluations
    probs = model_probabilities(evid)
    verdict = _verdict(probs, lsq_verdict)
    fits = _posterior_fits(stage, samples, names, priors, diags)
    rep = verdict["parameters_from"]
    reported = _reported(samples, probs, verdict, fits, targets, np.random.default_rng(rest))
    lsq_result = assemble(stage.curves, stage.scenes, stage.joint, stage.fits, dict(stage.verdict, parameters_from=rep),
                          stage.singles, options=stage.options, seed=seed, t0=t0)
    converged = _converged(diags, probs, rejected)
    summary = _summary(targets, chains, diags, evid, probs, cfg, seed, n_workers, stage, path, t_lsq, n_evals,
                       converged)
    base = {f.name: getattr(lsq_result, f.name) for f in dataclasses.fields(lsq_result)}
    base.update(method="mcmc", slip=verdict, parameters=reported, fits=fits,
                provenance=dict(lsq_result.provenance, method="mcmc", options=dict(stage.options, **cfg, profile=None)),
                curves=tuple(_offset_entries(lsq_result.curves, targets[rep], samples[rep])),
                warnings=tuple(_warnings(lsq_result, reported, verdict, diags, probs, fits, converged)),
                n_evaluations=lsq_result.n_evaluations + n_evals, wall_time=time.perf_counter() - t0,
                raw=dict(lsq_result.raw, chains=chains),
                sigma_source=lsq_result.sigma_source + "; in the posterior: " + targets[rep].noise_model)
    base["sampling"] = {"summary": summary, "samples": samples, "predictive": {}}
    return FitResult(**base)


def _chain_path(outdir):
    """``OUTDIR/chain.h5`` (its folder made), or None."""
    if outdir is None:
        return None
    from pathlib import Path  # noqa: PLC0415
    path = Path(outdir) / "chain.h5"
    path.parent.mkdir(parents=True, exist_ok=True)
    return path


def _posterior_fits(stage, samples, names, priors, diags) -> dict:
    """Each condition's least-squares :class:`SlipFit` with the posterior estimates of W_ad and μh."""
    return {s: dataclasses.replace(f, parameters={k: e for k, e in _estimates(samples[s], names, f.parameters,
                                                                             priors).items() if k in SHARED},
                                   diagnostics=tuple(f.diagnostics) + tuple(diags[s]["warnings"]))
            for s, f in stage.fits.items()}
