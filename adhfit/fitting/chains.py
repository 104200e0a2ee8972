"""The sampled chains of one slip condition, and their one write to HDF5 in emcee's ``HDFBackend`` layout.

:func:`adhfit.fitting.mcmc.sample_posterior` samples on emcee's in-memory backend and returns
:class:`Chains`; :func:`save_chains` writes every ensemble once (an ``HDFBackend`` during sampling
writes at every step, a fifth of a run), and :func:`open_chain` reads one back with emcee's own reader.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import emcee
import numpy as np

__all__ = ["Chains", "open_chain", "save_chains"]


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
