"""The load-cell zero and its drift integrated out: the sampler walks W_ad, μh and the control offsets only.

The force offset β₀ and the drift β₁ of each curve enter its force linearly,
F = F_model(θ) + β₀ + β₁ t (t: the row's fraction of the test), so in residual units every force block
is r(θ, β) = r₀(θ) + A β with a constant matrix A.  Under their flat priors (uniform over ± the whole
force range, many standard errors wide) the Gaussian integral over β is exact:

* σ given (residuals in units of σ): ∫ exp(-|r₀ + Aβ|²/2) dβ = (2π)^(k/2) det(AᵀA)^(-1/2) exp(-S⊥/2);
* σ unknown, p(σ) ∝ 1/σ (residual unit u): L(θ) = ½ Γ((n-k)/2) (π u² S⊥)^(-(n-k)/2) u^(-k) det(AᵀA)^(-1/2);

with S⊥ = min_β |r₀ + Aβ|² (the residual with the best zero and drift for this θ) and k the block's linear
coordinates.  The sampler then explores k fewer dimensions per curve (one curve: 3 instead of 5; fewer
walkers, shorter autocorrelation), and after the run every sample gets its β drawn from the exact
conditional posterior, β | θ, σ ~ N(β̂(θ), σ²/u² (AᵀA)⁻¹) with σ² = u² S⊥ / χ²(n-k) when σ is unknown: the
completed chain samples the same joint posterior as sampling all coordinates would (Rao-Blackwell;
Gelman et al., *Bayesian Data Analysis*, 3rd ed., §14.2 for the linear-Gaussian block).

β̂(θ) and S⊥(θ) travel from the sampler's evaluations as emcee *blobs*, so completing the chain costs no
model evaluation.  Where the coordinates are not exactly linear (checked at the start point and at one
other point) or a prior edge is within :data:`EDGE_SD` conditional standard deviations of β̂, nothing is
integrated out and every coordinate is sampled as before.
"""
from __future__ import annotations

import math

import numpy as np
from scipy import special

from ..lsq import PENALTY

__all__ = ["Marginal", "LINEAR_PREFIXES", "EDGE_SD"]

#: θ coordinates that enter the force linearly (the load-cell zero and its drift, per curve)
LINEAR_PREFIXES = ("force_offset", "force_drift")
#: a prior edge closer than this many conditional standard deviations to β̂ keeps the coordinate sampled
EDGE_SD = 12.0
#: relative tolerance of the linearity check
LINEAR_RTOL = 1e-7


class Marginal:
    """The posterior of ``target`` with its linear force coordinates integrated out (module docstring).

    Build it with :meth:`of`, which returns ``None`` where the integral does not apply.  Calling it on
    the free coordinates returns ``(ln posterior, blob)`` as emcee expects with blobs; :meth:`complete`
    turns a chain of free coordinates and its blobs into a chain of every coordinate.
    """

    def __init__(self, target, theta0: np.ndarray, linear: list[int], blocks: list[tuple]) -> None:
        self.target = target
        self.theta0 = np.asarray(theta0, float)
        self.linear = list(linear)
        self.free = [k for k in range(target.ndim) if k not in linear]
        self.names = [target.names[k] for k in self.free]
        self.blocks = blocks  # (lo, hi, unit, given, columns, A_b, (AᵀA)⁻¹ Aᵀ, chol((AᵀA)⁻¹), ln det AᵀA)
        self.n_blob = sum(len(b[4]) + 1 for b in blocks)

    @property
    def ndim(self) -> int:
        return len(self.free)

    @classmethod
    def of(cls, target, theta0: np.ndarray, cov0: np.ndarray) -> "Marginal | None":
        """The marginal of ``target`` around ``theta0`` (``cov0`` its covariance), or ``None``."""
        theta0 = np.asarray(theta0, float)
        linear = [k for k, n in enumerate(target.names) if n.startswith(LINEAR_PREFIXES)]
        if not linear or len(linear) == target.ndim:
            return None
        r0 = target.residual(theta0)
        if np.any(r0 == PENALTY):
            return None
        step = np.sqrt(np.clip(np.diag(np.atleast_2d(cov0)), 1e-24, None))
        cols = []
        for k in linear:
            e = np.zeros(theta0.size)
            e[k] = step[k]
            d1, d2 = target.residual(theta0 + e) - r0, target.residual(theta0 + 2.0 * e) - r0
            if not np.allclose(d2, 2.0 * d1, rtol=LINEAR_RTOL, atol=LINEAR_RTOL * np.max(np.abs(d1))):
                return None
            cols.append(d1 / step[k])
        A = np.column_stack(cols)
        # the same A away from θ0 (a free coordinate moved by two standard errors)
        free = [k for k in range(theta0.size) if k not in linear]
        moved = theta0.copy()
        moved[free] += 2.0 * step[free]
        r1 = target.residual(moved)
        if np.any(r1 == PENALTY):
            return None
        for j, k in enumerate(linear):
            e = np.zeros(theta0.size)
            e[k] = step[k]
            if not np.allclose((target.residual(moved + e) - r1) / step[k], A[:, j], rtol=LINEAR_RTOL,
                               atol=LINEAR_RTOL * np.max(np.abs(A[:, j]))):
                return None
        blocks, owned = [], []
        for lo, hi, unit, given in target.blocks:
            Ab = A[lo:hi]
            columns = [j for j in range(len(linear)) if np.any(Ab[:, j] != 0.0)]
            owned += columns
            if not columns:
                blocks.append((lo, hi, unit, given, [], None, None, None, 0.0))
                continue
            Ab = Ab[:, columns]
            gram = Ab.T @ Ab
            if hi - lo <= len(columns) + 1 or np.linalg.cond(gram) > 1e12:
                return None
            inv = np.linalg.inv(gram)
            blocks.append((lo, hi, unit, given, columns, Ab, inv @ Ab.T, np.linalg.cholesky(inv),
                           float(np.linalg.slogdet(gram)[1])))
        if sorted(owned) != list(range(len(linear))):  # a coordinate in several blocks, or in none
            return None
        out = cls(target, theta0, linear, blocks)
        # β̂ must sit far inside its prior: the flat-prior integral is then exact to ~exp(-EDGE_SD²/2)
        beta, spread = out._conditional(r0)
        for j, k in enumerate(linear):
            p = target.priors[k]
            lo, hi = p.a / p.factor, p.b / p.factor
            b = theta0[k] + beta[j]
            if p.dist != "uniform" or min(b - lo, hi - b) < EDGE_SD * spread[j]:
                return None
        return out

    def _conditional(self, r0: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """β̂ - β(θ0) and the conditional standard deviations at residual ``r0`` (σ at its estimate)."""
        beta, sd = np.zeros(len(self.linear)), np.zeros(len(self.linear))
        for lo, hi, unit, given, columns, Ab, proj, chol, _ in self.blocks:
            if not columns:
                continue
            r = r0[lo:hi]
            bh = -proj @ r
            s_perp = float(np.sum((r + Ab @ bh) ** 2))
            scale = 1.0 if given else math.sqrt(s_perp / max(hi - lo - len(columns), 1))
            beta[columns] = bh
            sd[columns] = scale * np.sqrt(np.diag(chol @ chol.T))
        return beta, sd

    def _full(self, free: np.ndarray) -> np.ndarray:
        theta = self.theta0.copy()
        theta[self.free] = free
        return theta

    def __call__(self, free: np.ndarray):
        """(ln marginal posterior, blob): the blob holds each block's β̂ (absolute θ) and S⊥."""
        blob = np.full(self.n_blob, np.nan)
        theta = self._full(np.asarray(free, float))
        lp = self.target.log_prior(theta)  # the linear coordinates' flat densities at θ0: their constant
        if lp == -math.inf:
            return -math.inf, blob
        r = self.target.residual(theta)
        if np.any(r == PENALTY):
            return -math.inf, blob
        total, i = lp, 0
        for lo, hi, unit, given, columns, Ab, proj, chol, logdet in self.blocks:
            rb, n, k = r[lo:hi], hi - lo, len(columns)
            if k:
                bh = -proj @ rb
                ss = float(np.sum((rb + Ab @ bh) ** 2))
                blob[i:i + k] = self.theta0[[self.linear[j] for j in columns]] + bh
                blob[i + k] = ss
                i += k + 1
            else:
                ss = float(rb @ rb)
            total += _block_log_likelihood(ss, n, k, unit, given, logdet)
        return (total, blob) if math.isfinite(total) else (-math.inf, blob)

    def log_posterior(self, free: np.ndarray) -> float:
        return self(free)[0]

    def complete(self, chain: np.ndarray, log_prob: np.ndarray, blobs: np.ndarray,
                 rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
        """Every coordinate of every sample: the free ones from ``chain`` (…, ndim_free), the linear ones
        drawn from their conditional posterior given the blob; and the joint ln posterior of each."""
        shape = chain.shape[:-1]
        full = np.broadcast_to(self.theta0, shape + (self.theta0.size,)).copy()
        full[..., self.free] = chain
        joint = np.array(log_prob, float, copy=True)
        i = 0
        for lo, hi, unit, given, columns, Ab, proj, chol, logdet in self.blocks:
            k, n = len(columns), hi - lo
            if not k:
                continue
            bh, s_perp = blobs[..., i:i + k], blobs[..., i + k]
            i += k + 1
            ok = np.isfinite(s_perp)
            z = rng.standard_normal(shape + (k,))
            if given:
                scale = np.ones(shape)
            else:  # σ/u given θ: u² S⊥ / σ² ~ χ²(n - k)
                scale = np.sqrt(np.where(ok, s_perp, 1.0) / rng.chisquare(n - k, shape))
            beta = np.where(ok[..., None], bh, 0.0) + scale[..., None] * (z @ chol.T)
            for c, j in enumerate(columns):
                col = self.linear[j]
                full[..., col] = np.where(ok, beta[..., c], self.theta0[col])
            ss = np.where(ok, s_perp, 1.0) + scale**2 * np.sum(z**2, axis=-1)
            with np.errstate(invalid="ignore"):
                joint += np.where(ok, _block_log_likelihood(ss, n, 0, unit, given, 0.0)
                                  - _block_log_likelihood(np.where(ok, s_perp, 1.0), n, k, unit, given, logdet), 0.0)
        return full, joint


def _block_log_likelihood(ss, n: int, k: int, unit: float, given: bool, logdet: float):
    """ln of a block's likelihood with ``k`` linear coordinates integrated out (k = 0: not integrated)."""
    if given:
        return -0.5 * ss - 0.5 * n * np.log(2.0 * math.pi * unit**2) + 0.5 * k * math.log(2.0 * math.pi) \
            - 0.5 * logdet
    m = n - k
    return (math.log(0.5) + special.gammaln(0.5 * m) - 0.5 * m * np.log(math.pi * ss * unit**2)
            - k * math.log(unit) - 0.5 * logdet)
