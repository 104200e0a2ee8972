"""The sampled chains of one slip condition, and their one write to HDF5 in emcee's ``HDFBackend`` layout.

:func:`adhfit.fitting.bayes.mcmc.sample_posterior` samples on emcee's in-memory backend and returns
:class:`Chains`; :func:`save_chains` writes every ensemble once (an ``HDFBackend`` during sampling
writes at every step, a fifth of a run), and :func:`open_chain` reads one back with emcee's own reader.

**Diagnostics.** Convergence diagnostics of an MCMC run (:class:`.mcmc.Chains`), with plain-language warnings.

* **acceptance fraction** per walker (after tuning): mean, min, max over all walkers;
* **τ** per parameter: integrated autocorrelation time in steps (emcee's estimator, walkers pooled),
  and **N/τ** with N the steps after tuning — the run is long enough when N/τ > 50;
* **R-hat** per parameter (arviz ``rhat``, rank-normalised split R-hat) across the *independent
  ensembles*: one chain per ensemble, its draws the kept steps with all its walkers (step-major, so the
  split halves are early and late steps).  Never from the walkers of one ensemble, which start together
  and move together;
* **ESS** (arviz ``ess``, bulk and tail) with every walker of every ensemble as a chain.

Warning thresholds: R-hat > 1.01; N/τ < 50; mean acceptance < 0.15, or any walker below 0.05
(a stuck walker); mean acceptance > 0.7 is reported for the mixture of moves used here (an
independence proposal that matches the posterior is *meant* to accept often; a random-walk sampler
with such acceptance would be taking tiny steps, which τ would show) and earns a warning only when τ
is long (> 5 steps); the step cap hit; bulk ESS < 400.  ``converged`` is True only when the stopping
rule was met and no R-hat exceeds 1.01.
"""
from __future__ import annotations

import warnings
from dataclasses import dataclass, field

import emcee
import numpy as np


__all__ = ["Chains", "open_chain", "save_chains", "diagnose", "preload", "RHAT_MAX", "N_OVER_TAU_MIN",
           "ACCEPTANCE_RANGE", "ESS_MIN"]


@dataclass(frozen=True)
class Chains:
    """The sampled chains of one slip condition (θ coordinates), and how the run went.

    Attributes
    ----------
    chain : ndarray, shape (n_ensembles, n_steps, n_walkers, ndim)
        Every step, tuning included.
    log_prob : ndarray, shape (n_ensembles, n_steps, n_walkers)
    burn, thin : int
        Steps discarded at the start (tuning + 2 τ_max) and the thinning of the kept steps.
    tune_steps : int
    tau : ndarray (ndim,)
        Integrated autocorrelation times (steps) of the kept chain at the last check.
    tau_history : list of (steps, tau list)
    acceptance : ndarray, shape (n_ensembles, n_walkers)
        Acceptance fractions after tuning.
    converged : bool
        The stopping rule was met (else the cap was hit).
    cap_hit : bool
    seeds : list of int
        The emcee RandomState seed of each ensemble.
    n_evaluations : int
        Posterior evaluations inside the support (what costs).
    wall_time : float
        Seconds.
    groups : list of str
        HDF5 groups of the ensembles (empty when not saved).
    accepted_counts : ndarray, shape (n_ensembles, n_walkers)
        Accepted proposals over the whole run, tuning included (emcee's ``accepted``).
    random_states : list
        Each ensemble's final emcee random state (written with the chain, to resume it).
    integrated : list of str
        Coordinates integrated out analytically while sampling and drawn back from their conditional
        posterior afterwards (:mod:`.linear`); empty when every coordinate was sampled.
    """

    chain: np.ndarray
    log_prob: np.ndarray
    burn: int
    thin: int
    tune_steps: int
    tau: np.ndarray
    tau_history: list
    acceptance: np.ndarray
    converged: bool
    cap_hit: bool
    seeds: list
    n_evaluations: int
    wall_time: float
    groups: list = field(default_factory=list)
    accepted_counts: np.ndarray | None = None
    random_states: list = field(default_factory=list)
    integrated: list = field(default_factory=list)

    @property
    def kept(self) -> np.ndarray:
        """Kept samples, shape (n_ensembles, n_kept_steps, n_walkers, ndim)."""
        return self.chain[:, self.burn::self.thin]

    @property
    def flat(self) -> np.ndarray:
        """Kept samples of every ensemble and walker, shape (n, ndim)."""
        k = self.kept
        return k.reshape(-1, k.shape[-1])

    @property
    def n_production(self) -> int:
        """Steps after tuning."""
        return self.chain.shape[1] - self.tune_steps


def open_chain(path, group: str):
    """emcee's ``HDFBackend`` of a saved ensemble (read-only), e.g. ``open_chain(p, "no-slip/ensemble_0")``.

    ``backend.get_chain(discard=..., thin=...)``, ``backend.get_log_prob()``; the run's burn-in and
    thinning are in the group's attributes ``adhfit_burn`` and ``adhfit_thin``.
    """
    return emcee.backends.HDFBackend(str(path), name=group, read_only=True)


def _save(path, group: str, chain: np.ndarray, log_prob: np.ndarray, accepted: np.ndarray,
          random_state, attrs: dict) -> str | None:
    """Write one ensemble's whole run to ``path`` once, as emcee's ``HDFBackend`` lays it out.

    The sampler runs on emcee's in-memory backend: an ``HDFBackend`` during sampling opens the file
    and writes at every step, which took a fifth of a run.  Here the group is made by the backend's
    own ``reset``/``grow`` and its datasets filled in one write each, so :func:`open_chain` (emcee's
    reader) reads it back.  ``None`` when h5py is missing.
    """
    try:
        import h5py  # noqa: F401, PLC0415 - emcee's HDF5 backend needs it
    except ImportError:
        return None
    n_steps, n_walkers, ndim = chain.shape
    backend = emcee.backends.HDFBackend(str(path), name=group)
    backend.reset(n_walkers, ndim)  # a fresh run replaces an older group of the same name
    backend.grow(n_steps, None)
    with backend.open("a") as f:
        g = f[group]
        g["chain"][...] = chain
        g["log_prob"][...] = log_prob
        g["accepted"][...] = accepted
        for i, v in enumerate(random_state or ()):
            g.attrs[f"random_state_{i}"] = v
        g.attrs["iteration"] = n_steps
        g.attrs.update(attrs)
    return group


def save_chains(path, group: str, chains: Chains, names) -> list[str]:
    """Write every ensemble of ``chains`` to HDF5 file ``path``, group ``"<group>/ensemble_<k>"``
    (emcee's ``HDFBackend`` layout, with the run's burn-in, thinning and parameter names as
    attributes); returns the groups written (none without h5py)."""
    attrs = {"adhfit_burn": chains.burn, "adhfit_thin": chains.thin, "adhfit_tune_steps": chains.tune_steps,
             "adhfit_parameters": ",".join(names)}
    written = []
    for k in range(chains.chain.shape[0]):
        state = chains.random_states[k] if k < len(chains.random_states) else None
        name = _save(path, f"{group}/ensemble_{k}", chains.chain[k], chains.log_prob[k],
                     chains.accepted_counts[k], state, attrs)
        if name:
            written.append(name)
    return written


RHAT_MAX = 1.01
N_OVER_TAU_MIN = 50.0
ACCEPTANCE_RANGE = (0.15, 0.7)
STUCK_WALKER = 0.05
#: τ (steps) above which high acceptance means small steps (the independence move gives τ ≈ 1-3)
LONG_TAU = 5.0
ESS_MIN = 400.0


def preload() -> None:
    """Import arviz now (1-3 s), e.g. in a thread while the sampler runs in other processes."""
    _arviz()


def _arviz():
    with warnings.catch_warnings():  # arviz 0.2x announces its refactor at import
        warnings.simplefilter("ignore", FutureWarning)
        import arviz  # noqa: PLC0415
    return arviz


def _rhat_ess(kept: np.ndarray, names: list[str]) -> tuple[dict, dict, dict]:
    az = _arviz()
    n_ens, n_steps, n_walk, ndim = kept.shape
    by_ensemble = kept.reshape(n_ens, n_steps * n_walk, ndim)  # step-major within each ensemble
    by_walker = kept.transpose(0, 2, 1, 3).reshape(n_ens * n_walk, n_steps, ndim)
    d_ens = az.convert_to_dataset({n: by_ensemble[..., k] for k, n in enumerate(names)})
    d_walk = az.convert_to_dataset({n: by_walker[..., k] for k, n in enumerate(names)})
    rhat = az.rhat(d_ens, method="rank") if n_ens > 1 else None
    bulk = az.ess(d_walk, method="bulk")
    tail = az.ess(d_walk, method="tail")
    get = lambda ds, n: float(ds[n].values) if ds is not None else float("nan")  # noqa: E731
    return ({n: get(rhat, n) for n in names}, {n: get(bulk, n) for n in names}, {n: get(tail, n) for n in names})


def diagnose(chains, names: list[str]) -> dict:
    """Diagnostics of one slip condition's run.

    Parameters
    ----------
    chains : adhfit.fitting.bayes.mcmc.Chains
    names : list of str
        Parameter names (SI names, in θ order).

    Returns
    -------
    dict
        ``acceptance`` {mean, min, max}, ``tau`` {name: steps}, ``n_over_tau`` {name}, ``rhat`` {name},
        ``ess_bulk`` {name}, ``ess_tail`` {name}, ``n_ensembles``, ``n_walkers``, ``steps`` (after
        tuning), ``tune_steps``, ``burn``, ``thin``, ``kept_samples``, ``cap_hit``, ``stopping_rule_met``,
        ``converged``, ``warnings`` (list of str), ``tau_history``.
    """
    kept = chains.kept
    n_ens, _, n_walk, _ = chains.chain.shape
    acc = chains.acceptance
    n = chains.n_production
    tau = {k: float(t) for k, t in zip(names, chains.tau)}
    n_tau = {k: (n / t if t > 0 else float("nan")) for k, t in tau.items()}
    rhat, ess_b, ess_t = _rhat_ess(kept, names) if kept.shape[1] >= 4 else (
        {k: float("nan") for k in names},) * 3
    out = []
    if chains.cap_hit:
        out.append(f"the step cap was hit ({n} steps after tuning) before the stopping rule (chain > "
                   f"{N_OVER_TAU_MIN:g} τ and τ settled) was met")
    bad_rhat = {k: v for k, v in rhat.items() if not v <= RHAT_MAX}
    if bad_rhat:
        out.append("R-hat above %.2f across the independent ensembles: %s" % (
            RHAT_MAX, ", ".join(f"{k} {v:.3f}" for k, v in bad_rhat.items())))
    short = {k: v for k, v in n_tau.items() if not v >= N_OVER_TAU_MIN}
    if short:
        out.append(f"chain shorter than {N_OVER_TAU_MIN:g} autocorrelation times: "
                   + ", ".join(f"{k} N/τ = {v:.3g}" for k, v in short.items()))
    mean_acc = float(np.mean(acc))
    if mean_acc < ACCEPTANCE_RANGE[0]:
        out.append(f"low acceptance fraction ({mean_acc:.2f} < {ACCEPTANCE_RANGE[0]})")
    elif mean_acc > ACCEPTANCE_RANGE[1] and max(tau.values()) > LONG_TAU:
        out.append(f"high acceptance fraction ({mean_acc:.2f} > {ACCEPTANCE_RANGE[1]}) with long "
                   f"autocorrelation times: the walkers take small steps")
    if float(np.min(acc)) < STUCK_WALKER:
        out.append(f"{int(np.sum(acc < STUCK_WALKER))} walker(s) accepted fewer than {STUCK_WALKER:.0%} of "
                   f"their moves (stuck)")
    low_ess = {k: v for k, v in ess_b.items() if not v >= ESS_MIN}
    if low_ess:
        out.append(f"small effective sample size (bulk ESS < {ESS_MIN:g}): "
                   + ", ".join(f"{k} {v:.0f}" for k, v in low_ess.items()))
    converged = bool(chains.converged and not bad_rhat)
    return {"acceptance": {"mean": mean_acc, "min": float(np.min(acc)), "max": float(np.max(acc))},
            "tau": tau, "n_over_tau": n_tau, "rhat": rhat, "ess_bulk": ess_b, "ess_tail": ess_t,
            "n_ensembles": int(n_ens), "n_walkers": int(n_walk), "steps": int(n), "tune_steps": chains.tune_steps,
            "burn": chains.burn, "thin": chains.thin, "kept_samples": int(kept.shape[0] * kept.shape[1] * kept.shape[2]),
            "cap_hit": chains.cap_hit, "stopping_rule_met": chains.converged, "converged": converged,
            "warnings": out, "tau_history": chains.tau_history}
