"""MCMC sampling of one slip condition's posterior with emcee (:mod:`.posterior` gives the target).

Sampler
-------
``n_ensembles`` independent emcee ``EnsembleSampler`` ensembles of ``n_walkers`` walkers (default 4 × 16),
each with its own seed, are run side by side so that R-hat compares independent ensembles
(:mod:`.chains`).  Walkers start in a ball around the least-squares optimum: θ_lsq plus one
least-squares standard error times a standard normal draw per coordinate.

Moves (a mixture; each step picks one): an *independence* Metropolis-Hastings move (90 %) proposing
from a multivariate Student-t, and emcee's differential-evolution move (10 %) as a local safety net.
A model evaluation costs milliseconds, so steps are precious: an independence proposal that matches
the posterior gives integrated autocorrelation times of ~1.5 steps, where the default stretch move
needs tens.  The proposal is set in two stages: during the first ``tune_steps`` steps it is the
least-squares Laplace approximation with wide tails (5 degrees of freedom, standard deviations × 1.55);
then, once per ensemble, it is replaced by the best of four Student-t candidates (fitted to that
ensemble's tuning samples, or the Laplace approximation; standard deviations × 1 or × 1.15; the one
whose ln π - ln q varies least over the tuning samples, :func:`_tuned_proposal`) and frozen.  With
``tune_rounds`` > 1 (the default) the tuning is repeated (:func:`_tune`): after each further round of
``tune_steps`` steps the proposal is refitted to the later half of the tuning samples (the previous
fit being one more candidate), the walkers propose from it widened 1.5-fold during the next round,
and tuning stops once the fit has settled (at least 3 rounds, at most ``tune_rounds``).  On a
three-curve series with the contact radius, whose posterior is skewed near each curve's fold and whose
least-squares scales can be 2-7 times too small, one refit from the first round's few correlated
samples left the acceptance at 0.3 and τ at 10-30 steps (not converged at 400-800 steps); the rounds
give 0.4-0.6 and τ 3-6 steps (benchmarks/results/recovery_series.md).  The tuning steps are always
discarded, so the kept chain comes from one fixed, valid Markov kernel.

Linear coordinates
------------------
Each curve's load-cell zero and drift enter its force linearly: they are integrated out analytically
while sampling and drawn back from their exact conditional posterior afterwards (:mod:`.linear`), so the
walkers move in fewer dimensions (one curve: 3 instead of 5; ~2x fewer evaluations on the sample curve)
and the chain returned still holds every coordinate.

Run length from the data
------------------------
After tuning, every ``check_every`` steps the integrated autocorrelation time τ of every parameter
is estimated (emcee's ``integrated_time(tol=0)``, pooled over all walkers of all ensembles).  The
run stops when the kept chain is longer than ``n_tau`` (50) τ_max and every τ changed by less than
``tau_rtol`` since the previous check, or at ``max_steps`` (then a warning says the cap was hit).
Burn-in = all tuning steps + ceil(2 τ_max); thinning = max(1, floor(τ_min / 2)).

Randomness and storage
----------------------
Seeds for the ensembles come from ``numpy.random.SeedSequence(seed)``; each ensemble's emcee
internals get ``numpy.random.RandomState(seed_k)`` through ``sampler.random_state``; nothing global
is seeded.  The chains are kept in memory while sampling; with ``path`` given, every ensemble is then
written once, in emcee's ``HDFBackend`` layout, to group ``"<slip>/ensemble_<k>"`` of that file
(:mod:`.chains`; inspect with :func:`open_chain`).  Likelihood evaluations run
on ``workers`` processes (fork) when more than one is asked for; results do not depend on it.
"""
from __future__ import annotations

import dataclasses
import math
import multiprocessing
import os
import sys
import time
from typing import Any

import emcee
import numpy as np

from ...errors import InputError
from .chains import Chains, open_chain, save_chains
from ..selection import StudentT
from .linear import Marginal
from .posterior import Target

__all__ = ["Chains", "IndependenceMove", "sample_posterior", "save_chains", "open_chain", "ParallelMap",
           "default_workers",
           "N_TAU", "TAU_RTOL"]

N_TAU = 50.0
TAU_RTOL = 0.01
#: independence-move share of the move mixture (the rest: differential evolution)
INDEPENDENCE_SHARE = 0.9

#: the tuned independence proposal: Student-t degrees of freedom, and the factor on the posterior sd
PROPOSAL_DF = 10.0
PROPOSAL_INFLATE = 1.15
#: tuning rounds (``tune_rounds`` > 1): at least this many, then stop once the proposal has settled
TUNE_MIN_ROUNDS = 3
TUNE_SETTLED = 0.2
#: factor on the proposal's standard deviations while tuning (between rounds)
TUNE_EXPLORE = 1.5

_TARGETS: dict[int, Any] = {}  # read by forked workers (see ParallelMap)


def default_workers() -> int:
    """Processes for likelihood evaluations: the usable cores, at most 2 (the target machine's count)."""
    try:
        n = len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        n = os.cpu_count() or 1
    return max(1, min(2, n))


class _Remote:
    """A picklable handle on a registered function (forked workers look it up in their copy)."""

    def __init__(self, key: int) -> None:
        self.key = key

    def __call__(self, theta):
        return _TARGETS[self.key](theta)


class ParallelMap:
    """``map`` for emcee (``pool=``) that counts evaluations and can use forked worker processes.

    Register every function before the first parallel call (workers are forked then); use as a
    context manager so the workers are closed.
    """

    def __init__(self, workers: int = 1) -> None:
        self.workers = int(workers)
        self.n_evaluations = 0
        self._pool = None
        self._keys: list[int] = []

    def register(self, fn) -> _Remote:
        """Make ``fn`` callable in the workers; returns its picklable handle (re-forks on next use)."""
        if self._pool is not None:  # workers only see functions registered before they were forked
            self._pool.close()
            self._pool.join()
            self._pool = None
        key = id(fn)
        _TARGETS[key] = fn
        self._keys.append(key)
        return _Remote(key)

    def map(self, fn, items):
        items = list(items)
        self.n_evaluations += len(items)
        if self.workers > 1 and len(items) > 1 and "fork" in multiprocessing.get_all_start_methods():
            if self._pool is None:
                self._pool = multiprocessing.get_context("fork").Pool(self.workers)
            return self._pool.map(fn, items, chunksize=max(1, len(items) // (2 * self.workers)))
        return list(map(fn, items))

    def close(self) -> None:
        if self._pool is not None:
            self._pool.close()
            self._pool.join()
            self._pool = None
        for k in self._keys:
            _TARGETS.pop(k, None)
        self._keys.clear()

    def __enter__(self) -> "ParallelMap":
        return self

    def __exit__(self, *exc) -> None:
        self.close()


class IndependenceMove(emcee.moves.MHMove):
    """Independence Metropolis-Hastings: every walker proposes a fresh draw from ``proposal``.

    The log proposal ratio is ln q(x) - ln q(x'); ``proposal`` may be replaced between steps
    (only during tuning: the kept chain must come from one kernel).
    """

    def __init__(self, proposal: StudentT) -> None:
        self.proposal = proposal
        super().__init__(self._propose)

    def _propose(self, coords: np.ndarray, random):
        new = self.proposal.draw(len(coords), random)
        return new, self.proposal.logpdf(coords) - self.proposal.logpdf(new)


def _tuned_proposal(sampler, discard: int, theta0: np.ndarray, cov0: np.ndarray,
                    fallback: StudentT, current: StudentT | None = None) -> StudentT:
    """The proposal for the kept chain, chosen on the ensemble's tuning samples.

    Candidates: Student-t fits (:data:`PROPOSAL_DF` degrees of freedom) to the second half of the
    tuning samples, and to the least-squares Laplace approximation, each with the standard
    deviations times 1 and :data:`PROPOSAL_INFLATE`.  The winner has the least spread of
    ln π(θ) - ln q(θ) over the tuning samples (the importance log-weights under the posterior: a
    flat ratio means high acceptance, and a proposal too narrow for the posterior shows as a wide
    spread).  Uses the log posteriors already computed: no extra evaluations.
    """
    x = sampler.get_chain(discard=discard, flat=True)
    lp = sampler.get_log_prob(discard=discard, flat=True)
    ok = np.isfinite(lp)
    x, lp = x[ok], lp[ok]
    if len(x) <= x.shape[1] + 1:
        return fallback
    cands = []
    for inflate in (1.0, PROPOSAL_INFLATE):
        cands.append(StudentT.fit(x, df=PROPOSAL_DF, inflate=inflate))
        cands.append(StudentT(theta0, cov0 * inflate**2 * (PROPOSAL_DF - 2.0) / PROPOSAL_DF, PROPOSAL_DF))
    if current is not None:
        cands.append(current)
    spread = []
    for q in cands:
        try:
            spread.append(float(np.std(lp - q.logpdf(x))))
        except np.linalg.LinAlgError:
            spread.append(np.inf)
    return cands[int(np.argmin(spread))] if np.isfinite(min(spread)) else fallback


def _settled(old: StudentT, new: StudentT) -> bool:
    """Two proposals agree: every mean within :data:`TUNE_SETTLED` standard deviations of the other's,
    every standard deviation within a factor 1 + :data:`TUNE_SETTLED`."""
    sd_old, sd_new = np.sqrt(np.diag(old.scale)), np.sqrt(np.diag(new.scale))
    return bool(np.all(np.abs(new.mean - old.mean) < TUNE_SETTLED * sd_new)
                and np.all(np.abs(np.log(sd_new / sd_old)) < math.log1p(TUNE_SETTLED)))


def _tune(samplers, moves, advance, tune_steps: int, tune_rounds: int, theta0, cov0, first) -> int:
    """Tuning rounds (module docstring); returns the tuning steps run (all discarded).

    After round r the proposal is refitted to the later half of that ensemble's tuning samples (round 1:
    its second half); from :data:`TUNE_MIN_ROUNDS` rounds on, tuning stops once no ensemble's
    proposal moved (:func:`_settled`) in the last round, else after ``tune_rounds`` rounds.  Between
    rounds the walkers propose from the refitted proposal widened by :data:`TUNE_EXPLORE` (a start
    covariance several times too narrow is then outgrown in a few rounds); the kept chain uses the
    refitted proposal itself.
    """
    fitted = [None] * len(samplers)
    for r in range(tune_rounds):
        advance(tune_steps)
        done = (r + 1) * tune_steps
        discard = tune_steps // 2 if r == 0 else max(tune_steps, done // 2)
        old = list(fitted)
        fitted = [_tuned_proposal(smp, discard, theta0, cov0, first, current=old[k])
                  for k, smp in enumerate(samplers)]
        last = r + 1 == tune_rounds or (r + 1 >= TUNE_MIN_ROUNDS and all(map(_settled, old, fitted)))
        for m, q in zip(moves, fitted):
            m.proposal = q if last else StudentT(q.mean, q.scale * TUNE_EXPLORE**2, q.df)
        if last:
            break
    return done


def _log_posterior(target, theta) -> float:
    """ln posterior of ``target`` at ``theta`` (a :class:`.linear.Marginal` also returns its blob)."""
    out = target(theta)
    return out[0] if isinstance(out, tuple) else out


def _pooled_tau(chains: list[np.ndarray]) -> np.ndarray:
    """τ per parameter of the production chains of every ensemble (walkers pooled), emcee's estimator."""
    x = np.concatenate(chains, axis=1)  # (steps, all walkers, ndim)
    with np.errstate(invalid="ignore", divide="ignore"):  # a parameter no walker has moved yet: τ is NaN
        return emcee.autocorr.integrated_time(x, tol=0)


def sample_posterior(target: Target, theta0: np.ndarray, cov0: np.ndarray, *, seed: int,
                     n_walkers: int = 16, n_ensembles: int = 4, tune_steps: int = 20,
                     check_every: int = 10, max_steps: int = 400, n_tau: float = N_TAU, tune_rounds: int = 1,
                     tau_rtol: float = TAU_RTOL, path=None, group: str = "posterior",
                     pmap: ParallelMap | None = None, progress: bool | None = None,
                     integrate_linear: bool = True) -> Chains:
    """Sample the posterior ``target`` (module docstring).

    Parameters
    ----------
    target : Target
        ln posterior in θ.
    theta0, cov0 : ndarray
        Least-squares optimum and covariance in θ (start ball and first proposal).
    seed : int
        Root seed; ensemble k uses the k-th child of ``SeedSequence(seed)``.
    n_walkers, n_ensembles : int
        ``n_walkers`` is raised to 2·ndim when smaller (emcee's differential-evolution move needs it).
    tune_steps : int
        Steps with the least-squares proposal before it is refitted (always discarded).
    tune_rounds : int
        Most tuning rounds of ``tune_steps`` steps each; after each the proposal is refitted (the
        previous proposal is one more candidate), so a poor start covariance is corrected; from
        :data:`TUNE_MIN_ROUNDS` rounds on tuning stops once the proposal has settled (:func:`_tune`).
        Every tuning step is discarded.
    check_every : int
        Steps between autocorrelation checks.
    max_steps : int
        Cap on the steps after tuning.
    n_tau, tau_rtol : float
        Stopping rule: kept chain > n_tau · τ_max and |Δτ|/τ < tau_rtol between checks.
    path : path, optional
        HDF5 file (emcee ``HDFBackend``), one group per ensemble: ``"<group>/ensemble_<k>"``.
    pmap : ParallelMap, optional
        Evaluation map (serial when not given).
    progress : bool, optional
        tqdm bar on standard error; default: only when standard error is a terminal.
    integrate_linear : bool
        Integrate the load-cell zero and drift out analytically and sample the other coordinates
        (:mod:`.linear`; the chain returned holds every coordinate, the linear ones drawn from their
        exact conditional posterior).  Where the integral does not apply, everything is sampled.

    Returns
    -------
    Chains
    """
    for name, value in (("n_walkers", n_walkers), ("n_ensembles", n_ensembles), ("tune_steps", tune_steps),
                        ("tune_rounds", tune_rounds), ("check_every", check_every), ("max_steps", max_steps)):
        if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 1:
            raise InputError(name, value, "a positive integer (an MCMC setting)")
    t0 = time.perf_counter()
    pmap = pmap if pmap is not None else ParallelMap(1)
    theta0 = np.asarray(theta0, float)
    cov0 = np.atleast_2d(np.asarray(cov0, float))
    marginal = Marginal.of(target, theta0, cov0) if integrate_linear else None
    run = target
    if marginal is not None:
        run, theta0, cov0 = marginal, theta0[marginal.free], cov0[np.ix_(marginal.free, marginal.free)]
    fn = pmap.register(run)
    evals0 = pmap.n_evaluations
    ndim = run.ndim
    # emcee's differential-evolution move needs at least 2·ndim walkers (the load-cell zero, fitted by
    # default, makes ndim 4)
    n_walkers = max(int(n_walkers), 2 * ndim)
    children = np.random.SeedSequence(seed).spawn(n_ensembles + 1)  # the last draws the linear coordinates
    seeds = [int(c.generate_state(1)[0]) for c in children[:n_ensembles]]
    sd0 = np.sqrt(np.clip(np.diag(cov0), 1e-16, None))
    first = StudentT(np.asarray(theta0, float), cov0 * 4.0 * 3.0 / 5.0 + 1e-14 * np.eye(ndim), 5.0)
    samplers, moves, states = [], [], []
    for k, s in enumerate(seeds):
        move = IndependenceMove(first)
        sampler = emcee.EnsembleSampler(n_walkers, ndim, fn, pool=pmap,
                                        moves=[(move, INDEPENDENCE_SHARE),
                                               (emcee.moves.DEMove(), 1.0 - INDEPENDENCE_SHARE)])
        sampler.random_state = np.random.RandomState(s).get_state()
        ball = np.random.default_rng(children[k]).standard_normal((n_walkers, ndim))
        p0 = theta0 + ball * sd0
        # walkers must start where the posterior is finite
        lp = np.array([_log_posterior(run, p) for p in p0])
        p0[~np.isfinite(lp)] = theta0
        samplers.append(sampler), moves.append(move), states.append(p0)
    show = sys.stderr.isatty() if progress is None else progress
    bar = None
    if show:
        from tqdm import tqdm  # noqa: PLC0415
        bar = tqdm(total=tune_rounds * tune_steps + max_steps, desc=f"MCMC {group}", unit="step", file=sys.stderr,
                   leave=False)

    def advance(n: int) -> None:
        for k, smp in enumerate(samplers):
            states[k] = smp.run_mcmc(states[k], n, progress=False, skip_initial_state_check=True)
        if bar is not None:
            bar.update(n)

    tune_steps = _tune(samplers, moves, advance, tune_steps, tune_rounds, theta0, cov0, first)
    acc0 = [smp.backend.accepted.copy() for smp in samplers]
    tau_prev, history, done, steps = None, [], False, 0
    tau = np.full(ndim, np.nan)
    while steps < max_steps:
        n = min(check_every, max_steps - steps)
        advance(n)
        steps += n
        tau = _pooled_tau([smp.get_chain(discard=tune_steps) for smp in samplers])
        history.append((steps, tau.tolist()))
        settled = tau_prev is not None and bool(np.all(np.abs(tau - tau_prev) < tau_rtol * tau))
        if np.all(np.isfinite(tau)) and steps > n_tau * np.max(tau) and settled:
            done = True
            break
        tau_prev = tau
    if bar is not None:
        bar.close()
    chain = np.stack([smp.get_chain() for smp in samplers])
    log_prob = np.stack([smp.get_log_prob() for smp in samplers])
    acceptance = np.stack([(smp.backend.accepted - a) / max(steps, 1) for smp, a in zip(samplers, acc0)])
    if marginal is not None:  # every coordinate, the linear ones from their conditional posterior
        blobs = np.stack([smp.get_blobs() for smp in samplers])
        chain, log_prob = marginal.complete(chain, log_prob, blobs, np.random.default_rng(children[-1]))
        tau = _pooled_tau([c[tune_steps:] for c in chain])
    tau_max = float(np.nanmax(tau)) if np.isfinite(tau).any() else float(steps)
    burn = min(tune_steps + int(math.ceil(2.0 * tau_max)), chain.shape[1] - 1)
    thin = max(1, int(np.nanmin(tau) // 2)) if np.isfinite(tau).any() else 1
    out = Chains(chain=chain, log_prob=log_prob, burn=burn, thin=thin, tune_steps=tune_steps, tau=tau,
                 tau_history=history, acceptance=acceptance, converged=done, cap_hit=not done, seeds=seeds,
                 n_evaluations=pmap.n_evaluations - evals0, wall_time=time.perf_counter() - t0,
                 accepted_counts=np.stack([smp.backend.accepted for smp in samplers]),
                 random_states=[smp.random_state for smp in samplers],
                 integrated=[target.names[k] for k in marginal.linear] if marginal is not None else [])
    if path is None:
        return out
    return dataclasses.replace(out, groups=save_chains(path, group, out, target.names))
