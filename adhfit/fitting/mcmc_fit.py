"""``adhfit fit --method mcmc``: Bayesian fit of both slip conditions, and their model probabilities.

1. Least squares first (:func:`.lsq.fit_slip`, the same residual and model): the optimum and its
   covariance start the walkers and the first proposal; ΔBIC is reported next to the evidence.
2. Each slip condition's posterior (:mod:`.posterior`: Gaussian likelihood, σ known or integrated
   out; log-uniform priors by default) is sampled by :func:`.mcmc.sample_posterior` (4 independent
   ensembles, run length from the autocorrelation time, chain saved to ``OUTDIR/chain.h5``).
3. Each evidence is estimated by importance sampling from a Student-t fitted to the posterior
   samples (:mod:`.evidence`); the posterior model probabilities (equal prior odds) decide the slip
   condition only when decisive (≥ 0.95, conservatively); otherwise ``selected`` is null and the
   reported estimates average the two posteriors with their probabilities as weights.
4. Estimates: posterior median (``value``), posterior sd (``stderr``), 2.5/97.5 percentiles
   (``ci95``); diagnostics (:mod:`.diagnostics`) and plain warnings.
"""
from __future__ import annotations

import dataclasses
import math
import time
from typing import Mapping

import numpy as np

from .diagnostics import diagnose
from .evidence import StudentT, importance_evidence, model_probabilities
from .prepare import check_options, provenance, read_inputs, segments_report
from .lsq import fit_slip
from .mcmc import ParallelMap, default_workers, sample_posterior, save_chains
from .model import DEFAULT_POINTS, CurveModel, ModelDomainError, segment
from .posterior import Target, default_priors
from .result import Estimate, FitResult
from .selection import SCALE, compare, evidence_word
from .summary import summarize

__all__ = ["fit_curve_mcmc", "DEFAULTS"]

#: default run settings (a 200-row curve, both slips: ~12,000 evaluations of ~0.3 ms, a few seconds per core)
#: check_every = 5 steps is ~3 τ here, as emcee's own example checks every ~2.5 τ (100 steps, τ ≈ 40)
DEFAULTS = {"n_walkers": 8, "n_ensembles": 4, "tune_steps": 15, "check_every": 5, "max_steps": 300,
            "evidence_draws": 300, "predictive_draws": 60}
CI_METHOD = "posterior 2.5/97.5 percentiles"

#: a posterior percentile within this fraction of the prior's range from its edge is prior-limited
PRIOR_EDGE = 0.05


def _edge(col: np.ndarray, prior) -> tuple[bool, bool]:
    """(at lower edge, at upper edge): whether the 2.5 / 97.5 percentiles reach the prior's bounds, so
    that the data bound the parameter from one side only (docs/contracts.md A5b)."""
    if prior is None or prior.dist == "normal":
        return False, False
    f = (np.log if prior.log else (lambda v: v))
    lo, hi = float(f(prior.a)), float(f(prior.b))
    vals = f(col) if prior.log else col
    p_lo, p_hi = np.percentile(vals, [2.5, 97.5])
    span = hi - lo
    return bool(p_lo < lo + PRIOR_EDGE * span), bool(p_hi > hi - PRIOR_EDGE * span)


def _estimates(samples: np.ndarray, names: list[str], lsq: Mapping[str, Estimate],
               priors: list | None = None) -> dict[str, Estimate]:
    out = {}
    for k, name in enumerate(names):
        col = samples[:, k]
        lo, med, hi = np.percentile(col, [2.5, 50.0, 97.5])
        at_lo, at_hi = _edge(col, priors[k] if priors else None)
        ci, status = (float(lo), float(hi)), "determined"
        if at_lo and at_hi:
            ci, status = None, "undetermined"
        elif at_hi:  # one-sided 95 %: the 5th percentile
            ci, status = (float(np.percentile(col, 5.0)), None), "lower_bound"
        elif at_lo:
            ci, status = (None, float(np.percentile(col, 95.0))), "upper_bound"
        out[name] = Estimate(name, float(med), float(np.std(col, ddof=1)), ci, CI_METHOD,
                             lsq[name].ci95 if name in lsq else None, status)
    return out


def _mixture(samples: dict[str, np.ndarray], probs: dict[str, float], rng: np.random.Generator) -> np.ndarray:
    """Samples of the model-averaged posterior: each slip's samples resampled in proportion to P(slip)."""
    n = min(len(s) for s in samples.values())
    parts = [s[rng.choice(len(s), int(round(n * probs[k])), replace=True)] for k, s in samples.items()]
    return np.concatenate([p for p in parts if len(p)])


class _Predict:
    """θ -> predicted force at every row (a picklable job for the worker map)."""

    def __init__(self, target: Target) -> None:
        self.target = target

    def __call__(self, theta):
        si = self.target.par.si(dict(zip(self.target.internal, map(float, theta))))
        try:
            return self.target.model.predict(si["work_of_adhesion"], si["mu_h"], si["x_offset"], si["force_offset"])
        except ModelDomainError:
            return np.full(self.target.model.force.shape, np.nan)


def _band(pmap: ParallelMap, target: Target, flat: np.ndarray, sigma: float, n: int,
          rng: np.random.Generator) -> dict:
    pick = flat[rng.choice(len(flat), min(n, len(flat)), replace=False)]
    preds = np.array(pmap.map(pmap.register(_Predict(target)), list(pick)))
    preds = preds[np.all(np.isfinite(preds), axis=1)]
    obs = preds + rng.normal(0.0, sigma, preds.shape)
    lo, med, hi = np.percentile(preds, [2.5, 50, 97.5], axis=0)
    lo_o, hi_o = np.percentile(obs, [2.5, 97.5], axis=0)
    return {"median": med, "lo": lo, "hi": hi, "lo_obs": lo_o, "hi_obs": hi_o, "draws": int(len(preds))}


def _verdict(probs: dict, lsq_verdict: dict) -> dict:
    sel, fav = probs["selected"], probs["favoured"]
    word = "imposed"
    if len(probs["probabilities"]) == 1:
        verdict = lsq_verdict["verdict"]
    else:  # the same scale as least squares, on 2 ln B (ln B lowered by 2 Monte-Carlo standard errors)
        lbf, se = probs["log_bayes_factor"], probs["log_bayes_factor_stderr"]
        two_ln_b = 2.0 * (lbf - 2.0 * se) if lbf is not None and se is not None else float("nan")
        word = evidence_word(two_ln_b if math.isfinite(two_ln_b) else float("nan"))
        p_fav = probs["probabilities"][fav]
        if word == "cannot tell" and not sel:
            verdict = "the data cannot tell them apart"
        else:
            verdict = f"{fav}: {word} evidence{'' if sel else ', not selected'} (P = {p_fav:.3g})"
    return {"selected": sel, "verdict": verdict, "evidence": word,
            "evidence_basis": "posterior model probability (2 ln B on the ΔBIC scale)",
            "scale": [{"two_ln_bayes_factor_from": lo, "word": w} for lo, w in SCALE],
            "favoured": probs["favoured"], "probabilities": probs["probabilities"],
            "probability_lower": probs["probability_lower"], "threshold": probs["threshold"],
            "log_bayes_factor": probs["log_bayes_factor"], "log_bayes_factor_stderr": probs["log_bayes_factor_stderr"],
            "method": probs["method"] + "; equal prior model probabilities",
            "explanation": probs["explanation"] + (f" Least squares: ΔBIC = {lsq_verdict['delta_bic']:.1f} "
                                                   f"({lsq_verdict['verdict']})." if lsq_verdict.get("delta_bic")
                                                   is not None else ""),
            "delta_aic": lsq_verdict["delta_aic"], "delta_bic": lsq_verdict["delta_bic"],
            "lsq_verdict": lsq_verdict["verdict"], "lsq_selected": lsq_verdict["selected"],
            "parameters_from": sel or probs["favoured"],
            "thresholds": {"probability": probs["threshold"], "criterion": "posterior model probability, "
                           "with ln B lowered by 2 Monte-Carlo standard errors"}}


@dataclasses.dataclass
class _SlipJob:
    """Sampling one slip condition's posterior and its evidence (runs in a process of its own)."""

    target: Target
    raw: object
    seed: np.random.SeedSequence
    cfg: dict
    progress: bool | None

    def __call__(self) -> dict:
        tg, raw, cfg = self.target, self.raw, self.cfg
        theta0 = tg.from_si(raw.par.si(raw.best.params))
        cov0 = raw.best.covar if raw.best.covar is not None else np.diag((0.05 * np.ones(tg.ndim)) ** 2)
        ss_run, ss_ev = self.seed.spawn(2)
        with ParallelMap(1) as pmap:
            chains = sample_posterior(tg, theta0, cov0, seed=int(ss_run.generate_state(1)[0]),
                                      n_walkers=cfg["n_walkers"], n_ensembles=cfg["n_ensembles"],
                                      tune_steps=cfg["tune_steps"], check_every=cfg["check_every"],
                                      max_steps=cfg["max_steps"], group=raw.model.slip, pmap=pmap,
                                      progress=self.progress)
            flat = chains.flat
            evidence = importance_evidence(tg.log_prior, lambda th: np.array(pmap.map(tg.log_likelihood, list(th))),
                                           StudentT.fit(flat, df=5.0, inflate=1.2), cfg["evidence_draws"],
                                           np.random.default_rng(ss_ev))
            return {"chains": chains, "samples": tg.to_si(flat), "evidence": evidence,
                    "evaluations": pmap.n_evaluations}


_JOBS: list = []  # read by forked workers (see _run_jobs)


def _run_job(i: int) -> dict:
    return _JOBS[i]()


def _run_jobs(jobs: list, processes: int) -> list[dict]:
    """Run ``jobs`` (callables), in ``processes`` forked processes when more than one (the jobs and
    everything they hold are inherited, only the results travel back)."""
    import multiprocessing  # noqa: PLC0415
    if processes < 2 or len(jobs) < 2 or "fork" not in multiprocessing.get_all_start_methods():
        return [job() for job in jobs]
    _JOBS[:] = jobs
    import threading  # noqa: PLC0415
    from .diagnostics import preload  # noqa: PLC0415
    try:
        with multiprocessing.get_context("fork").Pool(processes) as pool:
            # the parent only waits while the jobs run: it loads the diagnostics' library (arviz, 1-3 s)
            # meanwhile, in a thread started after the workers were forked (a fork while a thread
            # imports would copy its import locks, and a worker could wait on them for ever)
            threading.Thread(target=preload, daemon=True).start()
            return pool.map(_run_job, range(len(jobs)), chunksize=1)
    finally:
        _JOBS.clear()


def fit_curve_mcmc(data, scene, *, slip: str | None = None, sigma: float | None = None,
                   fit_x_offset: bool | None = None, fit_force_offset: bool = True, seed: int | None = None,
                   points: int = DEFAULT_POINTS, outdir=None, workers: int | None = None,
                   progress: bool | None = None, membrane: str | None = None, read_options: dict | None = None,
                   **settings) -> FitResult:
    """Bayesian fit of W_ad, μh (and offsets) under each slip condition, and the slip condition's probability.

    Parameters
    ----------
    data, scene, slip, sigma, fit_x_offset, fit_force_offset, points
        As for :func:`adhfit.fitting.fit.fit_curve`.  ``sigma`` given: known noise; else integrated out.
    seed : int, optional
        Root seed of every random number (walker starts, emcee, evidence draws, band); drawn from
        fresh entropy and recorded when not given.
    outdir : path, optional
        Where ``chain.h5`` is written (one group per slip condition; not written when None).
    workers : int, optional
        Processes: with both slip conditions, each is sampled in its own process when this is 2 or
        more (default: up to 2, the usable cores).  Results do not depend on it.
    progress : bool, optional
        tqdm bar on standard error (default: only on a terminal).
    membrane : {"auto", "large-stretch", "exact"}, optional
        As for :func:`adhfit.fitting.fit.fit_curve` (the sampler then uses the chosen membrane).
    read_options : dict, optional
        As for :func:`adhfit.fitting.fit.fit_curve`.
    **settings
        Override :data:`DEFAULTS` (``n_walkers``, ``n_ensembles``, ``tune_steps``, ``check_every``,
        ``max_steps``, ``evidence_draws``, ``predictive_draws``).

    Returns
    -------
    FitResult
        With :attr:`~.result.FitResult.sampling`: the run's summary, the samples and the band.
    """
    t0 = time.perf_counter()
    unknown = set(settings) - set(DEFAULTS)
    if unknown:
        from ..errors import InputError  # noqa: PLC0415
        raise InputError(sorted(unknown)[0], settings[sorted(unknown)[0]], "one of " + ", ".join(DEFAULTS))
    cfg = DEFAULTS | settings
    curve, scene = read_inputs(data, scene, read_options)
    from .plausibility import check_curve  # noqa: PLC0415
    curve, checks = check_curve(curve, scene)  # the same checks as a least-squares fit
    slip = scene.slip if slip is None else slip
    membrane = scene.membrane_model if membrane is None else membrane
    check_options("mcmc", slip, sigma, points, membrane)
    seed = int(np.random.SeedSequence().entropy % 2**63) if seed is None else int(seed)
    root = np.random.SeedSequence(seed)
    slips = ("no-slip", "frictionless") if slip == "auto" else (slip,)
    seg = segment(curve)
    raws = {}
    for s in slips:
        model = CurveModel(curve, scene, s, points=points, segments=seg)
        raws[s] = fit_slip(model, sigma=sigma, fit_x_offset=fit_x_offset, fit_force_offset=fit_force_offset,
                           extra_starts=[r.par.si(r.best.params) for r in raws.values()])
    from .membrane_fit import choose_and_refit  # noqa: PLC0415
    raws, model_info, _ = choose_and_refit(raws, scene, membrane)
    lsq_fits = {s: summarize(r, profile=False) for s, r in raws.items()}
    lsq_verdict = compare({s: f.bic for s, f in lsq_fits.items()}, {s: f.aic for s, f in lsq_fits.items()})
    t_lsq = time.perf_counter() - t0
    lsq_values = [r.par.si(r.best.params) for r in raws.values()]
    targets = {s: Target(r.model, r.par, default_priors(r.par, lsq_values, scene.priors), sigma)
               for s, r in raws.items()}
    path = None
    if outdir is not None:
        from pathlib import Path  # noqa: PLC0415
        path = Path(outdir) / "chain.h5"
        path.parent.mkdir(parents=True, exist_ok=True)
    seeds = dict(zip(slips, root.spawn(len(slips))))
    jobs = {s: _SlipJob(targets[s], raws[s], seeds[s], cfg, progress) for s in slips}
    n_proc = min(len(slips), default_workers() if workers is None else int(workers))
    runs = dict(zip(slips, _run_jobs([jobs[s] for s in slips], n_proc)))
    chains = {s: r["chains"] for s, r in runs.items()}
    diags = {s: diagnose(chains[s], targets[s].names) for s in slips}
    samples = {s: r["samples"] for s, r in runs.items()}
    evid = {s: r["evidence"] for s, r in runs.items()}
    if path is not None:
        chains = {s: dataclasses.replace(c, groups=save_chains(path, s, c, targets[s].names))
                  for s, c in chains.items()}
    with ParallelMap(1) as pmap:
        pmap.n_evaluations = sum(r["evaluations"] for r in runs.values())
        probs = model_probabilities(evid)
        verdict = _verdict(probs, lsq_verdict)
        rng = np.random.default_rng(root.spawn(len(slips) + 1)[-1])
        rep = verdict["parameters_from"]
        fits = {s: dataclasses.replace(lsq_fits[s], parameters=_estimates(samples[s], targets[s].names,
                                                                          lsq_fits[s].parameters,
                                                                          targets[s].priors),
                                       diagnostics=tuple(lsq_fits[s].diagnostics) + tuple(diags[s]["warnings"]),
                                       raw=chains[s]) for s in slips}
        if verdict["selected"] is None and len(slips) > 1:
            mixed = _mixture(samples, probs["probabilities"], rng)
            reported = {k: dataclasses.replace(e, ci_method=CI_METHOD + ", averaged over both slip conditions "
                                                "(weights = model probabilities)")
                        for k, e in _estimates(mixed, targets[rep].names, {}, targets[rep].priors).items()}
        else:
            reported = dict(fits[rep].parameters)
        band = _band(pmap, targets[rep], chains[rep].flat, lsq_fits[rep].sigma, cfg["predictive_draws"], rng)
        n_evals = pmap.n_evaluations
    band["slip"] = rep
    wall = time.perf_counter() - t0
    converged = all(d["converged"] for d in diags.values())
    warn = list(scene.warnings()) if model_info["membrane"] != "exact" else []
    if not converged:
        warn.append("MCMC NOT CONVERGED for: " + ", ".join(s for s, d in diags.items() if not d["converged"])
                    + " — do not trust these intervals (see the diagnostics)")
    warn += list(fits[rep].warnings)
    diagnostics = [f"[{s}] {d}" for s in slips for d in fits[s].diagnostics]
    if path is not None and not any(c.groups for c in chains.values()):
        warn.append("the chains were not saved (emcee's HDF5 backend needs h5py, which is not installed)")
    if not probs["reliable"]:
        warn.append("the evidence estimate is unreliable (few effective importance weights)")
    if verdict["selected"] is None and len(slips) > 1:
        warn.append(f"The slip condition is undecided: the data cannot tell no-slip from frictionless contact "
                    f"for sure ({verdict['explanation'].rstrip('.')}). The estimates average both conditions' "
                    f"posteriors, weighted by their probabilities.")
    mc_time = sum(c.wall_time for c in chains.values())
    mc_evals = sum(c.n_evaluations for c in chains.values())
    summary = {
        "seed": seed, "noise_model": targets[rep].noise_model, "converged": converged,
        "priors": {k: p.as_dict() for k, p in zip(targets[rep].names, targets[rep].priors)},
        "settings": cfg | {"workers": n_proc},
        "sampler": "emcee EnsembleSampler; moves: independence Metropolis-Hastings from a tuned Student-t "
                   "(90 %) + differential evolution (10 %); see adhfit.fitting.mcmc",
        "stopping_rule": "kept chain > 50 tau_max and every tau changed < 1 % between checks, or the step cap",
        "model_probabilities": probs,
        "slips": {s: {"parameters": targets[s].names, "diagnostics": diags[s], "evidence": evid[s].as_dict(),
                      "ensemble_seeds": chains[s].seeds, "chain_groups": chains[s].groups,
                      "mcmc_seconds": chains[s].wall_time, "posterior_evaluations": chains[s].n_evaluations}
                  for s in slips},
        "chain_file": str(path) if path is not None and any(c.groups for c in chains.values()) else None,
        "lsq_estimates": {s: {k: e.value for k, e in lsq_fits[s].parameters.items()} for s in slips},
        "lsq_seconds": t_lsq, "model_evaluations": n_evals,
        "evaluations_per_second": mc_evals / mc_time if mc_time > 0 else None,
    }
    options = {"slip": slip, "sigma": sigma, "fit_x_offset": raws[slips[0]].par.fit_x_offset,
               "fit_force_offset": fit_force_offset, "points": points, "membrane": membrane} | cfg
    rep_fit = fits[rep]
    return FitResult(
        method="mcmc", slip=verdict, parameters=reported, fits=fits, n_points=len(curve.x),
        n_excluded=len(curve.excluded), sigma=rep_fit.sigma,
        sigma_source="given" if sigma is not None else "integrated out (prior ∝ 1/σ); the value shown is the "
                                                       "least-squares estimate",
        warnings=tuple(checks + list(warn)), diagnostics=tuple(diagnostics), n_evaluations=n_evals + sum(f.n_evaluations for f in lsq_fits.values()),
        n_histories=sum(f.n_histories for f in lsq_fits.values()), wall_time=wall,
        provenance=provenance(curve, scene, seed, "mcmc", options), segments=segments_report(seg, lsq_fits[rep]),
        excluded=tuple(curve.excluded), curve=curve, raw=dict(chains), model=model_info,
        sampling={"summary": summary, "samples": samples, "predictive": band})
