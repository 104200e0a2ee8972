"""MCMC of a test series (issue 13, docs/contracts.md A7): ``fit_global(..., method="mcmc")``.

The single-curve MCMC (:mod:`.mcmc_fit`) on the joint model of :mod:`.series`:

1. **least squares first**: :func:`.global_fit.joint_stage` (each curve alone, the joint fit per slip
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
   and the verdict as for one curve; undecided -> the reported estimates average both posteriors.
4. **estimates**: posterior median, sd and 2.5/97.5 percentiles of the shared W_ad and μh (status from
   the prior edges, as for one curve); each curve's offsets likewise in ``curves[].offsets``.  The
   per-curve checks (χ², pull, contribution) are the least-squares joint fit's.
"""
from __future__ import annotations

import dataclasses
import math
import time

import numpy as np
from scipy import special

from ..errors import InputError
from .diagnostics import diagnose
from .evidence import StudentT, importance_evidence, model_probabilities
from .lsq import PENALTY
from .mcmc import ParallelMap, default_workers, sample_posterior
from .mcmc_fit import CI_METHOD, McmcFitResult, _estimates, _mixture, _verdict
from .model import OFFSET_NAME
from .options import DEFAULT_POINTS
from .posterior import Prior, default_priors
from .selection import compare
from .series import Values, block_sizes, series_residual

__all__ = ["SeriesTarget", "series_priors", "fit_global_mcmc", "DEFAULTS"]

#: run settings: n_walkers is raised to 2·ndim (16 for three curves), so two ensembles make the 32 walkers a
#: step of the single-curve default (4 x 8); R-hat compares the two independent ensembles
DEFAULTS = {"n_walkers": 8, "n_ensembles": 2, "tune_steps": 15, "check_every": 5, "max_steps": 300,
            "evidence_draws": 300}
SHARED = ("work_of_adhesion", "mu_h")


class SeriesTarget:
    """Log prior, log likelihood and log posterior of one slip condition's joint fit, in θ.

    The same interface as :class:`.posterior.Target` (``names``, ``ndim``, ``priors``, ``log_prior``,
    ``log_likelihood``, ``__call__``, ``to_si``), so the sampler and the evidence take either.

    Parameters
    ----------
    sf : SeriesFit
        The least-squares joint fit (members with their settled σ's, row splits, parametrisation).
    names : list of str
        SI names of θ's coordinates (offsets suffixed with the curve's index).
    priors : list of Prior
        One per coordinate.
    """

    def __init__(self, sf, names: list[str], priors: list[Prior]) -> None:
        self.internal = list(sf.best.var_names)
        if len(names) != len(self.internal) or len(priors) != len(names):
            raise ValueError(f"{len(names)} names and {len(priors)} priors for {len(self.internal)} parameters")
        self.names, self.priors, self.given = list(names), list(priors), dict(sf.given)
        self._residual = series_residual(sf.members, sf.spar)
        self.blocks = []  # (start, stop, σ, σ given)
        k = 0
        for m, (nf, na) in zip(sf.members, block_sizes(sf.members)):
            self.blocks.append((k, k + nf, m.sigma_f, sf.given["force"]))
            if na:
                self.blocks.append((k + nf, k + nf + na, m.sigma_a, sf.given["contact_radius"]))
            k += nf + na

    @property
    def ndim(self) -> int:
        return len(self.names)

    @property
    def noise_model(self) -> str:
        known = [k for k, v in self.given.items() if v]
        head = "Gaussian, one sigma per curve and observable"
        if len(known) == len(self.given):
            return head + ", all given"
        tail = "integrated out analytically under p(sigma) ∝ 1/sigma (block by block)"
        return head + (f"; {', '.join(known)} given, the others " if known else "; ") + tail

    def log_prior(self, theta: np.ndarray) -> float:
        total = 0.0
        for prior, t in zip(self.priors, theta):
            total += prior.logpdf(float(t))
            if total == -math.inf:
                break
        return total

    def residual(self, theta: np.ndarray) -> np.ndarray:
        """The joint least-squares residual at θ (each block in units of its σ)."""
        return self._residual(Values(zip(self.internal, map(float, theta))))

    def log_likelihood(self, theta: np.ndarray) -> float:
        r = self.residual(theta)
        if np.any(r == PENALTY):  # a curve outside the model's domain (the residual's marker)
            return -math.inf
        total = 0.0
        for lo, hi, sigma, given in self.blocks:
            ss, n = float(r[lo:hi] @ r[lo:hi]), hi - lo
            if given:
                total += -0.5 * ss - 0.5 * n * math.log(2.0 * math.pi * sigma**2)
            else:
                total += math.log(0.5) + special.gammaln(0.5 * n) - 0.5 * n * math.log(math.pi * ss * sigma**2)
        return total

    def __call__(self, theta: np.ndarray) -> float:
        """ln posterior (unnormalised): what emcee samples."""
        lp = self.log_prior(theta)
        if lp == -math.inf:
            return -math.inf
        ll = self.log_likelihood(theta)
        return lp + ll if math.isfinite(ll) else -math.inf

    def to_si(self, theta: np.ndarray) -> np.ndarray:
        """θ samples (..., ndim) -> SI values of ``self.names``."""
        theta = np.asarray(theta, float)
        out = np.empty_like(theta)
        for k, prior in enumerate(self.priors):
            out[..., k] = np.exp(theta[..., k]) if prior.log else theta[..., k] * prior.factor
        return out


def _scene_priors(scenes) -> dict:
    first = dict(scenes[0].priors)
    for sc in scenes[1:]:
        if dict(sc.priors) != first:
            raise InputError("[priors]", f"{sc.source}", "the same [priors] table in every curve's scene "
                             "(the shared W_ad and μh have one prior); remove it or make them agree")
    return first


def series_priors(joint: dict, scenes) -> tuple[list[str], list[Prior]]:
    """Coordinate names and priors of the joint posterior (the same for every slip condition).

    Per curve :func:`.posterior.default_priors` with that curve's least-squares offsets and the joint
    W_ad and μh of every slip condition; the shared values' priors are curve 0's (they use only the
    shared estimates, so every curve gives the same)."""
    scene_priors = _scene_priors(scenes)
    first = next(iter(joint.values()))
    si = [sf.spar.si(sf.best.params) for sf in joint.values()]
    names, priors = [], []
    for i, m in enumerate(first.members):
        pri = default_priors(m.par, [{**shared, **offs[i]} for shared, offs in si], scene_priors)
        for name in m.par.names:
            if name in SHARED and i > 0:
                continue
            names.append(name if name in SHARED else f"{name}_{i}")
            priors.append(pri[name])
    return names, priors


#: the start covariance's scale along a coordinate is corrected when the posterior's own curvature
#: differs from it by more than this factor (either way)
SCALE_CHECK = 2.0


def checked_covariance(target, theta0: np.ndarray, cov0: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The start covariance with every coordinate's scale checked against the log posterior itself.

    Least squares gives the covariance from a finite-difference Jacobian; a kink in the contact-radius
    model or a rugged objective can make one standard error far too small or too large, and the
    sampler's start ball and first proposal would inherit it.  Along each coordinate k the drop of the
    log posterior d(h) = ln π(θ0) - ½[ln π(θ0 + h e_k) + ln π(θ0 - h e_k)] is evaluated at h = the
    conditional standard deviation s_k = 1/sqrt((C⁻¹)_kk) (and once more at the new estimate);
    a Gaussian gives d = h²/(2 s²).  Where the estimate differs from s_k by more than
    :data:`SCALE_CHECK`, that row and column of C are rescaled (correlations kept).  Costs 2–4
    evaluations per coordinate.

    Returns
    -------
    (covariance, ratios) : the corrected covariance and the per-coordinate scale factors applied.
    """
    cov0 = np.atleast_2d(np.asarray(cov0, float))
    lp0 = target(theta0)
    ratio = np.ones(theta0.size)
    if not math.isfinite(lp0):
        return cov0, ratio
    cond = 1.0 / np.sqrt(np.clip(np.diag(np.linalg.pinv(cov0)), 1e-300, None))
    for k in range(theta0.size):
        h, r, d = cond[k], 1.0, float("nan")
        for _ in range(2):
            e = np.zeros(theta0.size)
            e[k] = h
            d = lp0 - 0.5 * (target(theta0 + e) + target(theta0 - e))
            if not math.isfinite(d):
                break
            est = h / math.sqrt(2.0 * d) if d > 1e-3 else 10.0 * h  # flat: look further out
            r = float(np.clip(est / cond[k], 0.1, 30.0))
            if abs(math.log(est / h)) < math.log(1.3):
                break
            h = r * cond[k]
        ratio[k] = r if math.isfinite(d) and (r > SCALE_CHECK or r < 1.0 / SCALE_CHECK) else 1.0
    return cov0 * np.outer(ratio, ratio), ratio


def _run(targets, joint, cfg, root, path, pmap, progress) -> tuple[dict, dict, dict, dict]:
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
                                     tune_steps=cfg["tune_steps"], check_every=cfg["check_every"],
                                     max_steps=cfg["max_steps"], path=path, group=s, pmap=pmap, progress=progress)
        diags[s] = diagnose(chains[s], tg.names)
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


def _warnings(lsq_result, reported, verdict, diags, probs, fits) -> list[str]:
    from .series_checks import _status_warnings  # noqa: PLC0415
    drop = ("The series cannot decide", "The series only bounds", "The series does not determine",
            "The force noise of at least one curve is correlated")
    out = [w for w in lsq_result.warnings if not w.startswith(drop)]
    bad = [s for s, d in diags.items() if not d["converged"]]
    if bad:
        out.insert(0, "MCMC NOT CONVERGED for: " + ", ".join(bad) + " — do not trust these intervals "
                      "(see the diagnostics)")
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


def _summary(targets, chains, diags, evid, probs, cfg, seed, workers, stage, path, t_lsq, n_evals) -> dict:
    rep = probs["favoured"]
    mc_time = sum(c.wall_time for c in chains.values())
    mc_evals = sum(c.n_evaluations for c in chains.values())
    return {
        "seed": seed, "noise_model": targets[rep].noise_model, "converged": all(d["converged"] for d in diags.values()),
        "priors": {k: p.as_dict() for k, p in zip(targets[rep].names, targets[rep].priors)},
        "settings": cfg | {"workers": workers},
        "sampler": "emcee EnsembleSampler; moves: independence Metropolis-Hastings from a tuned Student-t "
                   "(90 %) + differential evolution (10 %); see adhfit.fitting.mcmc",
        "stopping_rule": "kept chain > 50 tau_max and every tau changed < 1 % between checks, or the step cap",
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
                    progress: bool | None = None, **settings) -> McmcFitResult:
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
    McmcFitResult
        With ``curves`` (offsets as posterior summaries) and ``mcmc``.
    """
    from .global_fit import joint_stage  # noqa: PLC0415
    from .series_checks import assemble  # noqa: PLC0415
    t0 = time.perf_counter()
    unknown = sorted(set(settings) - set(DEFAULTS))
    if unknown:
        raise InputError(unknown[0], settings[unknown[0]], "one of " + ", ".join(DEFAULTS))
    cfg = DEFAULTS | settings
    seed = int(np.random.SeedSequence().entropy % 2**63) if seed is None else int(seed)
    stage = joint_stage(curves, scenes, slip=slip, sigma=sigma, sigma_contact_radius=sigma_contact_radius,
                        contact_radius=contact_radius, fit_x_offset=fit_x_offset, fit_force_offset=fit_force_offset,
                        points=points, profile=False)
    t_lsq = time.perf_counter() - t0
    lsq_verdict = compare({s: f.bic for s, f in stage.fits.items()}, {s: f.aic for s, f in stage.fits.items()})
    names, priors = series_priors(stage.joint, stage.scenes)
    targets = {s: SeriesTarget(sf, names, priors) for s, sf in stage.joint.items()}
    path = None
    if outdir is not None:
        from pathlib import Path  # noqa: PLC0415
        path = Path(outdir) / "chain.h5"
        path.parent.mkdir(parents=True, exist_ok=True)
    root = np.random.SeedSequence(seed)
    run_seed, rest = root.spawn(2)
    n_workers = default_workers() if workers is None else int(workers)
    with ParallelMap(n_workers) as pmap:
        chains, diags, samples, evid = _run(targets, stage.joint, cfg, run_seed, path, pmap, progress)
        n_evals = pmap.n_evaluations
    probs = model_probabilities(evid)
    verdict = _verdict(probs, lsq_verdict)
    fits = {s: dataclasses.replace(f, parameters={k: e for k, e in _estimates(samples[s], names, f.parameters,
                                                                             priors).items() if k in SHARED},
                                   diagnostics=tuple(f.diagnostics) + tuple(diags[s]["warnings"]))
            for s, f in stage.fits.items()}
    rep = verdict["parameters_from"]
    reported = _reported(samples, probs, verdict, fits, targets, np.random.default_rng(rest))
    lsq_result = assemble(stage.curves, stage.scenes, stage.joint, stage.fits, dict(stage.verdict, parameters_from=rep),
                          stage.singles, options=stage.options, seed=seed, t0=t0)
    summary = _summary(targets, chains, diags, evid, probs, cfg, seed, n_workers, stage, path, t_lsq, n_evals)
    prov = dict(lsq_result.provenance, method="mcmc", options=dict(stage.options, **cfg, profile=None))
    base = {f.name: getattr(lsq_result, f.name) for f in dataclasses.fields(lsq_result)}
    base.update(method="mcmc", slip=verdict, parameters=reported, fits=fits, provenance=prov,
                curves=tuple(_offset_entries(lsq_result.curves, targets[rep], samples[rep])),
                warnings=tuple(_warnings(lsq_result, reported, verdict, diags, probs, fits)),
                n_evaluations=lsq_result.n_evaluations + n_evals, wall_time=time.perf_counter() - t0,
                raw=dict(lsq_result.raw, chains=chains),
                sigma_source=lsq_result.sigma_source + "; in the posterior: " + targets[rep].noise_model)
    return McmcFitResult(**base, mcmc=summary, samples=samples, predictive={})
