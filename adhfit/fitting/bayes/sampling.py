"""``method="mcmc"``: the posterior of every slip condition, their model probabilities, one curve or a series.

1. **Least squares first** (:mod:`.stage`: the same objective, membrane model and row splits): the
   optimum and its covariance start the walkers and the first proposal; ΔBIC is reported next to the
   evidence.  A condition the least-squares fit already rejects (ΔBIC > :data:`REJECT_DBIC`) gets a short
   run (:data:`SHORT_RUN` steps) for its evidence; its chains need not converge when its probability stays
   below 1e-6.
2. **Each slip condition's posterior** (:class:`.posterior.Target`: Gaussian per block, σ known or
   integrated out; log-uniform priors by default) is sampled by :func:`.mcmc.sample_posterior` (several
   independent ensembles, run length from the autocorrelation time), each condition in a process of
   its own when two cores are there; the chains go to ``OUTDIR/chain.h5``.
3. **Evidence** by importance sampling from a Student-t fitted to the samples (:mod:`.selection`); the
   posterior model probabilities (equal prior odds) select a condition only when decisive; otherwise the
   reported estimates average the two posteriors with their probabilities as weights.
4. **Estimates**: posterior median (``value``), sd (``stderr``), 2.5/97.5 percentiles (``ci95``), status
   from the prior's edges; a series' offsets likewise in ``curves[].offsets``.
"""
from __future__ import annotations

import dataclasses
import math
import time
from typing import Mapping

import numpy as np

from ..stage import assemble
from .chains import diagnose
from ..selection import StudentT, importance_evidence, model_probabilities
from .mcmc import ParallelMap, default_workers, sample_posterior, save_chains
from ..model import OFFSET_NAME, ModelDomainError
from .posterior import SHARED, Target, checked_covariance, objective_priors
from ..stand_in import check, stand_in
from ..result import Estimate, FitResult
from ..selection import SCALE, evidence_word

__all__ = ["sample", "DEFAULTS", "SERIES_DEFAULTS", "CI_METHOD", "REJECT_DBIC", "SHORT_RUN"]

#: default run settings for one curve and its force (the 330-row sample curve, both slips, the zero and
#: drift integrated out: ~9,500 evaluations of ~0.3 ms); check_every = 5 steps is ~3 τ here, as emcee's own
#: example checks every ~2.5 τ.  Tuning: 3 to 6 rounds until the proposal settles: with one round 8 of 120
#: replicate curves ended unconverged at the step cap (τ 6-19 steps, acceptance down to 0.06), with the rounds
#: those curves converge at τ 1.3-3 (benchmarks/results/mcmc_linear_coverage.md)
DEFAULTS = {"n_walkers": 8, "n_ensembles": 4, "tune_steps": 15, "tune_rounds": 6, "check_every": 5,
            "max_steps": 300, "evidence_draws": 300, "predictive_draws": 60}
#: several blocks (a series, or the contact radius): n_walkers is raised to 2·ndim, so two ensembles of
#: 16 walkers (three curves); the proposal is refitted after each of up to ``tune_rounds`` rounds until it
#: settles: with the contact radius the posterior is skewed near each curve's fold, and one refit left τ
#: at ~10-30 steps; 3-7 rounds of 20 steps give τ 3-4, so 200-400 kept steps (800 is the cap)
SERIES_DEFAULTS = DEFAULTS | {"n_ensembles": 2, "tune_steps": 20, "tune_rounds": 12, "max_steps": 800}
CI_METHOD = "posterior 2.5/97.5 percentiles"
#: a posterior percentile within this fraction of the prior's range from its edge is prior-limited
PRIOR_EDGE = 0.05
#: a condition whose least-squares BIC is this far above the other's (a Bayes factor near e^-50) gets a
#: short run: enough for its evidence, whose only use is to confirm the verdict
REJECT_DBIC = 100.0
SHORT_RUN = 60


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


def estimates(samples: np.ndarray, names: list[str], lsq: Mapping[str, Estimate],
              priors: list | None = None) -> dict[str, Estimate]:
    """Posterior median, sd, 95 % interval and status of every column of ``samples``."""
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
    """θ -> predicted force at every row of the first curve (a picklable job for the worker map)."""

    def __init__(self, target: Target) -> None:
        self.target = target

    def __call__(self, theta):
        fit = self.target.fit
        m = fit.members[0]
        v = dict(zip(self.target.internal, map(float, theta)))
        si = m.par.si(fit.spar.member_values(v, 0))
        try:
            return m.model.predict(si["work_of_adhesion"], si["mu_h"], si["x_offset"], si["force_offset"],
                                   si["force_drift"])
        except ModelDomainError:
            return np.full(m.model.force.shape, np.nan)


def _band(target: Target, flat: np.ndarray, sigma: float, n: int, rng: np.random.Generator) -> dict:
    """The posterior-predictive band of the first curve's force."""
    pick = flat[rng.choice(len(flat), min(n, len(flat)), replace=False)]
    preds = np.array([_Predict(target)(th) for th in pick])
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
    lsq_note = (f" Least squares: ΔBIC = {lsq_verdict['delta_bic']:.1f} ({lsq_verdict['verdict']})."
                if lsq_verdict.get("delta_bic") is not None else "")
    return {"selected": sel, "verdict": verdict, "evidence": word,
            "evidence_basis": "posterior model probability (2 ln B on the ΔBIC scale)",
            "scale": [{"two_ln_bayes_factor_from": lo, "word": w} for lo, w in SCALE],
            "favoured": fav, "probabilities": probs["probabilities"],
            "probability_lower": probs["probability_lower"], "threshold": probs["threshold"],
            "log_bayes_factor": probs["log_bayes_factor"], "log_bayes_factor_stderr": probs["log_bayes_factor_stderr"],
            "method": probs["method"] + "; equal prior model probabilities",
            "explanation": probs["explanation"] + lsq_note,
            "delta_aic": lsq_verdict["delta_aic"], "delta_bic": lsq_verdict["delta_bic"],
            "lsq_verdict": lsq_verdict["verdict"], "lsq_selected": lsq_verdict["selected"],
            "parameters_from": sel or fav,
            "thresholds": {"probability": probs["threshold"], "criterion": "posterior model probability, "
                           "with ln B lowered by 2 Monte-Carlo standard errors"}}


@dataclasses.dataclass
class _SlipJob:
    """Sampling one slip condition's posterior and its evidence (runs in a process of its own)."""

    target: Target
    seed: np.random.SeedSequence
    cfg: dict
    short: bool
    progress: bool | None
    use_stand_in: bool = True

    def __call__(self) -> dict:
        tg, cfg = self.target, self.cfg
        best = tg.fit.best
        theta0 = tg.theta0()
        cov0 = best.covar if best.covar is not None else np.diag(np.full(tg.ndim, 0.05 ** 2))
        cov0, ratios = checked_covariance(tg, theta0, cov0)
        ss_run, ss_ev, ss_check = self.seed.spawn(3)
        stand = self._stand_in(tg, cov0) if self.use_stand_in else None
        with ParallelMap(1) as pmap:
            chains = self._sample(stand or tg, theta0, cov0, ss_run, pmap)
            check_info = None
            if stand is not None:
                check_info = check(tg, stand, chains.flat, *self._units(tg), np.random.default_rng(ss_check))
                if not check_info["passed"]:  # the exact posterior itself, at the exact model's cost
                    chains = self._sample(tg, theta0, cov0, ss_run, pmap)
            used = stand if check_info is not None and check_info["passed"] else tg
            flat = chains.flat
            evidence = importance_evidence(used.log_prior, lambda th: np.array(pmap.map(used.log_likelihood, list(th))),
                                           StudentT.fit(flat, df=5.0, inflate=1.2), cfg["evidence_draws"],
                                           np.random.default_rng(ss_ev))
            if used is stand:  # ln Z_E = ln Z_S + ln E_S[L_E / L_S] (stand_in.py)
                evidence = dataclasses.replace(evidence, log_evidence=evidence.log_evidence
                                               + check_info["log_mean_ratio"])
            return {"chains": chains, "samples": tg.to_si(flat), "evidence": evidence,
                    "evaluations": pmap.n_evaluations, "stand_in": check_info,
                    "scale_corrections": {n: float(x) for n, x in zip(tg.names, ratios) if x != 1.0}}

    def _sample(self, target, theta0, cov0, ss_run, pmap):
        cfg = self.cfg
        return sample_posterior(target, theta0, cov0, seed=int(ss_run.generate_state(1)[0]),
                                n_walkers=cfg["n_walkers"], n_ensembles=cfg["n_ensembles"],
                                tune_steps=cfg["tune_steps"], tune_rounds=cfg["tune_rounds"],
                                check_every=cfg["check_every"],
                                max_steps=min(cfg["max_steps"], SHORT_RUN) if self.short else cfg["max_steps"],
                                group=target.fit.slip, pmap=pmap, progress=self.progress)

    @staticmethod
    def _stand_in(tg: Target, cov0: np.ndarray) -> Target | None:
        """The exact membrane's stand-in target (stand_in.py), or None where it does not apply."""
        sd = np.sqrt(np.clip(np.diag(cov0), 0.0, None))
        fit = stand_in(tg.fit, stderr=dict(zip(tg.internal, map(float, sd))))
        return None if fit is None else Target(fit, tg.names, tg.priors)

    @staticmethod
    def _units(tg: Target) -> tuple[float, float]:
        """(σ, residual unit) of the force rows: the deviation in σ is Δr · unit / σ."""
        fit = tg.fit
        if fit.joint:
            return 1.0, 1.0
        return float(fit.sigma), float(fit.single.scale)


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
    from .chains import preload  # noqa: PLC0415
    try:
        with multiprocessing.get_context("fork").Pool(processes) as pool:
            # the parent only waits while the jobs run: it loads the diagnostics' library (arviz, 1-3 s)
            # meanwhile, in a thread started after the workers were forked (a fork while a thread
            # imports would copy its import locks, and a worker could wait on them for ever)
            threading.Thread(target=preload, daemon=True).start()
            return pool.map(_run_job, range(len(jobs)), chunksize=1)
    finally:
        _JOBS.clear()


def _rejected(summaries: dict) -> set:
    best = min(f.bic for f in summaries.values())
    return {s for s, f in summaries.items() if f.bic - best > REJECT_DBIC}


def _converged(diags: dict, probs: dict, rejected: set) -> bool:
    """Every condition's chains converged, except a rejected one whose posterior probability stays below
    1e-6 even with its log evidence raised by 20 Monte-Carlo standard errors."""
    p = probs["probabilities"]
    se = probs.get("log_bayes_factor_stderr") or 0.0
    return all(d["converged"] or (s in rejected and p[s] * math.exp(min(20.0 * se, 50.0)) < 1e-6)
               for s, d in diags.items())


def _offset_entries(curves: tuple, target: Target, samples: np.ndarray) -> list[dict]:
    """``curves`` with each offset replaced by its posterior median, sd and 2.5/97.5 percentiles."""
    out = []
    for i, c in enumerate(curves):
        c = dict(c, offsets={k: dict(v) for k, v in c["offsets"].items()})
        for k, name in enumerate(target.names):
            base, _, idx = name.rpartition("_")
            if idx != str(i) or base not in (*OFFSET_NAME.values(), "force_offset", "force_drift"):
                continue
            lo, med, hi = np.percentile(samples[:, k], [2.5, 50.0, 97.5])
            short = base.removesuffix("_offset")
            c["offsets"][short] = dict(c["offsets"].get(short, {}), value=float(med), ci95=[float(lo), float(hi)],
                                       stderr=float(np.std(samples[:, k], ddof=1)), method=CI_METHOD)
        out.append(c)
    return out


#: least-squares sentences that an MCMC fit words anew from its own estimates
_LSQ_ONLY = ("The series cannot decide", "The slip condition is undecided", "The data only bound",
             "The data do not determine", "The force noise")


def _warnings(lsq_result, reported, verdict, diags, probs, rep_fit, converged, chains_saved: bool) -> list[str]:
    from ..summary import status_warnings  # noqa: PLC0415
    out = [w for w in lsq_result.warnings if not w.startswith(_LSQ_ONLY)]
    bad = [s for s, d in diags.items() if not d["converged"]]
    if bad and not converged:
        out.insert(0, "MCMC NOT CONVERGED for: " + ", ".join(bad) + " — do not trust these intervals "
                      "(see the diagnostics)")
    elif bad:
        out.append(f"The chains of {', '.join(bad)} were a short run and did not converge: the least-squares fit "
                   f"already rejects it (ΔBIC > {REJECT_DBIC:g}) and its posterior probability stays below 1e-6 "
                   f"whatever the sampling error, so the verdict and the reported values do not depend on it.")
    if not chains_saved:
        out.append("the chains were not saved (emcee's HDF5 backend needs h5py, which is not installed)")
    if not probs["reliable"]:
        out.append("the evidence estimate is unreliable (few effective importance weights)")
    if verdict["selected"] is None and len(diags) > 1:
        out.append(f"The slip condition is undecided: the data cannot tell no-slip from frictionless contact "
                   f"for sure ({verdict['explanation'].rstrip('.')}). The estimates average both conditions' "
                   f"posteriors, weighted by their probabilities.")
    if rep_fit.widening > 1.0:
        out.append(f"The force noise is correlated from row to row (lag-1 autocorrelation {rep_fit.autocorrelation:.2f}); "
                   f"the posterior assumes independent noise, so its intervals may be about "
                   f"{rep_fit.widening:.2g}-fold too narrow.")
    return out + status_warnings(reported)


def _config(problem, stage, opts) -> dict:
    one_block = all(not f.joint for f in stage.fits.values())
    return (DEFAULTS if one_block else SERIES_DEFAULTS) | opts.mcmc


def _chain_path(outdir):
    """``OUTDIR/chain.h5`` (its folder made), or None."""
    if outdir is None:
        return None
    from pathlib import Path  # noqa: PLC0415
    path = Path(outdir) / "chain.h5"
    path.parent.mkdir(parents=True, exist_ok=True)
    return path


def sample(problem, stage, opts, t0: float) -> FitResult:
    """The MCMC :class:`FitResult` of ``problem``, from its least-squares ``stage`` (module docstring)."""
    cfg = _config(problem, stage, opts)
    seed = int(np.random.SeedSequence().entropy % 2**63) if opts.seed is None else int(opts.seed)
    opts = dataclasses.replace(opts, seed=seed)
    t_lsq = time.perf_counter() - t0
    lsq_verdict = dict(stage.verdict)
    names, priors = objective_priors(stage.fits, problem.scenes)
    targets = {s: Target(f, names, priors) for s, f in stage.fits.items()}
    slips = list(targets)
    rejected = _rejected(stage.summaries)
    root = np.random.SeedSequence(seed)
    seeds = dict(zip(slips, root.spawn(len(slips))))
    jobs = [_SlipJob(targets[s], seeds[s], cfg, s in rejected, opts.progress, opts.stand_in) for s in slips]
    n_proc = min(len(slips), default_workers() if opts.workers is None else int(opts.workers))
    runs = dict(zip(slips, _run_jobs(jobs, n_proc)))
    chains = {s: r["chains"] for s, r in runs.items()}
    diags = {s: diagnose(chains[s], targets[s].names) | {"short_run": s in rejected,
                                                        "start_scale_corrections": runs[s]["scale_corrections"],
                                                        "exact_stand_in": runs[s]["stand_in"]}
             for s in slips}
    samples = {s: r["samples"] for s, r in runs.items()}
    evid = {s: r["evidence"] for s, r in runs.items()}
    path = _chain_path(opts.outdir)
    if path is not None:
        chains = {s: dataclasses.replace(c, groups=save_chains(path, s, c, targets[s].names)) for s, c in chains.items()}
    probs = model_probabilities(evid)
    verdict = _verdict(probs, lsq_verdict)
    rep = verdict["parameters_from"]
    rng = np.random.default_rng(root.spawn(len(slips) + 1)[-1])
    shown = [n for n in names if n in SHARED or not problem.series]
    fits = {s: dataclasses.replace(f, parameters={k: e for k, e in estimates(samples[s], names, f.parameters,
                                                                             priors).items() if k in shown},
                                   diagnostics=tuple(f.diagnostics) + tuple(diags[s]["warnings"]), raw=chains[s])
            for s, f in stage.summaries.items()}
    if verdict["selected"] is None and len(slips) > 1:
        cols = [names.index(n) for n in shown]
        mixed = _mixture({s: x[:, cols] for s, x in samples.items()}, probs["probabilities"], rng)
        note = CI_METHOD + ", averaged over both slip conditions (weights = model probabilities)"
        reported = {k: dataclasses.replace(e, ci_method=note)
                    for k, e in estimates(mixed, shown, {}, [priors[c] for c in cols]).items()}
    else:
        reported = dict(fits[rep].parameters)
    band = {}
    if not problem.series:
        band = _band(targets[rep], chains[rep].flat, stage.summaries[rep].sigma, cfg["predictive_draws"], rng)
        band["slip"] = rep
    lsq_result = assemble(problem, dataclasses.replace(stage, verdict=dict(lsq_verdict, parameters_from=rep)),
                          opts, t0, method="mcmc")
    converged = _converged(diags, probs, rejected)
    n_evals = sum(r["evaluations"] for r in runs.values())
    saved = path is None or any(c.groups for c in chains.values())
    summary = _summary(targets, chains, diags, evid, probs, cfg | {"workers": n_proc}, seed, stage, path,
                       t_lsq, n_evals, converged, rejected)
    options = dict(lsq_result.provenance["options"], **cfg, profile=None)
    base = {f.name: getattr(lsq_result, f.name) for f in dataclasses.fields(lsq_result)}
    base.update(slip=verdict, parameters=reported, fits=fits,
                provenance=dict(lsq_result.provenance, method="mcmc", seed=seed, options=options),
                curves=tuple(_offset_entries(lsq_result.curves, targets[rep], samples[rep])),
                warnings=tuple(_warnings(lsq_result, reported, verdict, diags, probs, stage.summaries[rep],
                                         converged, saved)),
                n_evaluations=lsq_result.n_evaluations + n_evals, wall_time=time.perf_counter() - t0,
                raw=dict(lsq_result.raw, **chains) if not problem.series else dict(lsq_result.raw, chains=chains),
                sigma_source=("given" if opts.sigma is not None else "integrated out (prior ∝ 1/σ); the value "
                              "shown is the least-squares estimate") if not problem.series else
                lsq_result.sigma_source + "; in the posterior: " + targets[rep].noise_model,
                sampling={"summary": summary, "samples": samples, "predictive": band})
    return FitResult(**base)


def _summary(targets, chains, diags, evid, probs, cfg, seed, stage, path, t_lsq, n_evals, converged,
             rejected) -> dict:
    rep = probs["favoured"]
    mc_time = sum(c.wall_time for c in chains.values())
    mc_evals = sum(c.n_evaluations for c in chains.values())
    return {
        "seed": seed, "noise_model": targets[rep].noise_model, "converged": converged,
        "priors": {k: p.as_dict() for k, p in zip(targets[rep].names, targets[rep].priors)},
        "settings": cfg,
        "sampler": "emcee EnsembleSampler; moves: independence Metropolis-Hastings from a Student-t refitted "
                   f"after each of up to {cfg['tune_rounds']} tuning rounds (90 %) + differential evolution (10 %); "
                   "see adhfit.fitting.bayes.mcmc",
        "stopping_rule": "kept chain > 50 tau_max and every tau changed < 1 % between checks, or the step cap "
                         f"({SHORT_RUN} steps for a condition the least-squares fit rejects by ΔBIC > {REJECT_DBIC:g})",
        "short_runs": sorted(rejected),
        "likelihood": "every curve's force rows (and pull-off term) and each secondary observable's rows, one "
                      "sigma per block; row splits fixed at the least-squares optimum",
        "linear_nuisances": "each curve's load-cell zero and drift enter its force linearly: they are integrated "
                            "out analytically while sampling (flat priors, exact Gaussian integral) and drawn from "
                            "their conditional posterior afterwards, so the chains hold every parameter "
                            "(slips.*.integrated_out lists them); see adhfit.fitting.bayes.linear",
        "exact_membrane": "sampled through the large-stretch model plus the exact model's difference, linear "
                          "about the least-squares optimum, and checked on posterior draws against the exact "
                          "model (diagnostics.exact_stand_in: the log-likelihood ratio's spread and the largest "
                          "force deviation in units of sigma; the exact posterior is sampled directly when the "
                          "check fails); see adhfit.fitting.stand_in",
        "model_probabilities": probs,
        "slips": {s: {"parameters": targets[s].names, "diagnostics": diags[s], "evidence": evid[s].as_dict(),
                      "ensemble_seeds": chains[s].seeds, "chain_groups": chains[s].groups,
                      "integrated_out": list(chains[s].integrated),
                      "mcmc_seconds": chains[s].wall_time, "posterior_evaluations": chains[s].n_evaluations}
                  for s in targets},
        "chain_file": str(path) if path is not None and any(c.groups for c in chains.values()) else None,
        "lsq_estimates": {s: {k: e.value for k, e in f.parameters.items()} for s, f in stage.summaries.items()},
        "lsq_seconds": t_lsq, "model_evaluations": n_evals,
        "evaluations_per_second": mc_evals / mc_time if mc_time > 0 else None,
    }
