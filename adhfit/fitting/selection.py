"""Slip selection: compare the no-slip and frictionless fits by AIC and BIC (docs/numerics.md B4).

A single fit's χ² cannot tell the slip condition (at 0.5 % noise the wrong model's reduced χ² can
still look acceptable); the comparison of the two fits can.  Both fits have the same data and the
same number of parameters k, so ΔAIC = ΔBIC = Δ(-2 ln L):

* σ estimated:  -2 ln L = n ln(RSS/n) (+ const), AIC = n ln(RSS/n) + 2k, BIC = n ln(RSS/n) + k ln n;
* σ given:      -2 ln L = χ² (+ const),          AIC = χ² + 2k,          BIC = χ² + k ln n.

Evidence scale on ΔBIC (Kass & Raftery 1995, on 2 ln B), the one the report prints
(:data:`SCALE`): < 2 **cannot tell**, 2 – 6 **positive**, 6 – 10 **strong**, > 10 **very strong**.
Only very strong evidence selects: a wrong selection then needs the wrong model to win by more than
10, which (for models whose predictions differ by s in units of σ², Δ ~ N(s, 4s)) happens with a
probability below 0.1 % for any s.  Below that the better condition is named with its evidence word
and ``selected`` is null.  The verdict always carries the scale's word, e.g. ``"no-slip: very
strong evidence (ΔBIC = 1071)"``; when the data cannot tell it is ``"the data cannot tell them apart"``.

**Evidence (MCMC).** Evidence (marginal likelihood) by importance sampling, and posterior model probabilities.

Method
------
A multivariate Student-t proposal q (``df`` degrees of freedom) is fitted to posterior samples: its
location is their mean and its scale matrix makes its covariance ``inflate**2`` times theirs (heavier
tails than the posterior keep the importance weights bounded).  With M draws θ_j ~ q,

    Z = E_q[ π(θ) L(θ) / q(θ) ] ≈ (1/M) Σ_j w_j,      w_j = π(θ_j) L(θ_j) / q(θ_j),

an unbiased estimate whatever q is (as long as q covers the posterior).  Its Monte-Carlo standard
error is sd(w)/sqrt(M); on the log scale SE(ln Z) ≈ sd(w) / (sqrt(M) mean(w)) (delta method).  The
effective sample size of the weights, (Σ w)² / Σ w², says how well q matches the posterior: near M
for a good match, a few for a bad one (the estimate is then flagged).

:func:`model_probabilities` turns the log-evidences of competing models (equal prior model
probabilities) into posterior probabilities and decides: a model is *selected* only when its
probability is at least ``threshold`` (0.95) even after moving its log Bayes factor down by two
Monte-Carlo standard errors; otherwise ``selected`` is ``None`` (never a silent pick).

The estimator is checked against analytic evidences (Gaussian-linear models) in
``tests/test_mcmc_evidence.py``.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable

import numpy as np
from scipy import special, stats


__all__ = ["information_criteria", "compare", "evidence_word", "DECISIVE", "POSITIVE", "STRONG", "VERDICTS",
           "SCALE", "StudentT", "EvidenceEstimate", "importance_evidence", "model_probabilities",
           "DECISIVE_PROBABILITY", "MIN_WEIGHT_ESS"]

DECISIVE = 10.0
POSITIVE = 2.0
STRONG = 6.0
VERDICTS = ("no-slip favoured", "frictionless favoured", "the data cannot tell them apart")
#: (lower ΔBIC, word) of the evidence scale, weakest first
SCALE = ((0.0, "cannot tell"), (POSITIVE, "positive"), (STRONG, "strong"), (DECISIVE, "very strong"))


def evidence_word(delta_bic: float) -> str:
    """The scale's word for a ΔBIC (>= 0; not finite: "cannot tell")."""
    if not math.isfinite(delta_bic) or delta_bic < POSITIVE:
        return "cannot tell"
    if delta_bic < STRONG:
        return "positive"
    return "strong" if delta_bic <= DECISIVE else "very strong"


def information_criteria(chisqr: float, ndata: int, nvarys: int, *, sigma_given: bool) -> tuple[float, float]:
    """(AIC, BIC) of a least-squares fit (see the module docstring for the definitions)."""
    if sigma_given:
        m2lnl = chisqr
    else:
        m2lnl = ndata * math.log(max(chisqr, 1e-300) / ndata)
    return m2lnl + 2 * nvarys, m2lnl + nvarys * math.log(ndata)


def compare(bic: dict[str, float], aic: dict[str, float]) -> dict:
    """Verdict on the slip condition from the two fits' BIC (and AIC, reported alongside).

    Parameters
    ----------
    bic, aic : dict slip -> float
        Both conditions' criteria (one entry only when the user imposed the condition).

    Returns
    -------
    dict
        ``selected`` (None unless decisive), ``verdict``, ``evidence``, ``favoured``, ``delta_aic``,
        ``delta_bic`` (the other condition's minus the favoured one's, >= 0), ``thresholds``,
        ``parameters_from`` (the condition whose estimates are reported).
    """
    thresholds = {"decisive": DECISIVE, "strong": STRONG, "positive": POSITIVE, "criterion": "delta_bic"}
    if len(bic) == 1:
        (only,) = bic
        return {"selected": only, "verdict": f"{only} (set by the user; not compared)", "evidence": "imposed",
                "favoured": only, "delta_aic": None, "delta_bic": None, "thresholds": thresholds,
                "parameters_from": only}
    ranked = sorted(bic, key=lambda k: bic[k])
    best, other = ranked[0], ranked[1]
    d_bic = bic[other] - bic[best]
    d_aic = aic[other] - aic[best]
    word = evidence_word(d_bic)
    selected = best if word == "very strong" else None
    if word == "cannot tell":
        verdict = VERDICTS[2]
        explanation = f"ΔBIC = {d_bic:.1f} < {POSITIVE:g}: the data cannot tell the slip conditions apart."
    elif selected:
        verdict = f"{best}: very strong evidence (ΔBIC = {d_bic:.3g})"
        explanation = f"ΔBIC = {d_bic:.1f} > {DECISIVE:g}: very strong evidence for {best}, which is selected."
    else:
        verdict = f"{best}: {word} evidence, not selected (ΔBIC = {d_bic:.2g})"
        explanation = (f"ΔBIC = {d_bic:.1f}: {word} evidence for {best}; only ΔBIC > {DECISIVE:g} (very strong) "
                       f"selects a slip condition.")
    return {"selected": selected, "verdict": verdict, "evidence": word, "favoured": best,
            "delta_aic": d_aic, "delta_bic": d_bic, "explanation": explanation, "thresholds": thresholds,
            "scale": [{"delta_bic_from": lo, "word": w} for lo, w in SCALE],
            "parameters_from": best}


#: a slip condition is selected when its posterior probability reaches this (module docstring)
DECISIVE_PROBABILITY = 0.95
#: below this effective sample size of the importance weights the evidence is flagged unreliable
MIN_WEIGHT_ESS = 50.0


@dataclass(frozen=True)
class StudentT:
    """Multivariate Student-t distribution (location ``mean``, scale matrix ``scale``, ``df``).

    Its covariance is ``scale * df / (df - 2)`` for df > 2.
    """

    mean: np.ndarray
    scale: np.ndarray
    df: float = 5.0

    @classmethod
    def fit(cls, samples: np.ndarray, *, df: float = 5.0, inflate: float = 1.2) -> "StudentT":
        """The t whose covariance is ``inflate**2`` times the sample covariance, centred on the mean.

        Parameters
        ----------
        samples : ndarray, shape (n, ndim)
        df : float
            Degrees of freedom (> 2).
        inflate : float
            Scale factor of the standard deviations (>= 1 gives heavier-than-posterior tails).
        """
        x = np.atleast_2d(np.asarray(samples, float))
        cov = np.atleast_2d(np.cov(x, rowvar=False))
        cov = cov + 1e-12 * np.diag(np.diag(cov)).clip(min=1e-300)
        return cls(x.mean(axis=0), cov * inflate**2 * (df - 2.0) / df, float(df))

    @property
    def ndim(self) -> int:
        return int(self.mean.size)

    def _chol(self) -> np.ndarray:
        return np.linalg.cholesky(self.scale)

    def draw(self, n: int, random) -> np.ndarray:
        """``n`` draws, shape (n, ndim); ``random`` is a numpy Generator or RandomState."""
        z = random.standard_normal((n, self.ndim))
        g = random.chisquare(self.df, n) / self.df
        return self.mean + (z @ self._chol().T) / np.sqrt(g)[:, None]

    def logpdf(self, x: np.ndarray) -> np.ndarray:
        """Log density at each row of ``x`` (shape (n, ndim) or (ndim,))."""
        x = np.atleast_2d(np.asarray(x, float))
        chol = self._chol()
        dev = np.linalg.solve(chol, (x - self.mean).T)
        maha = np.sum(dev**2, axis=0)
        d, nu = self.ndim, self.df
        return (special.gammaln((nu + d) / 2) - special.gammaln(nu / 2) - 0.5 * d * math.log(nu * math.pi)
                - np.sum(np.log(np.diag(chol))) - 0.5 * (nu + d) * np.log1p(maha / nu))


@dataclass(frozen=True)
class EvidenceEstimate:
    """An importance-sampling estimate of ln Z.

    Attributes
    ----------
    log_evidence : float
        ln Z (natural log; includes every normalising constant of prior and likelihood).
    stderr : float
        Monte-Carlo standard error of ln Z.
    ess : float
        Effective sample size of the importance weights, (Σw)²/Σw².
    n_draws : int
        Draws from the proposal (each one likelihood evaluation, bar draws outside the prior).
    method : str
    """

    log_evidence: float
    stderr: float
    ess: float
    n_draws: int
    method: str = "importance sampling from a multivariate Student-t fitted to the posterior samples"

    @property
    def reliable(self) -> bool:
        """Enough effective draws and a finite estimate."""
        return bool(math.isfinite(self.log_evidence) and self.ess >= MIN_WEIGHT_ESS)

    def as_dict(self) -> dict:
        return {"log_evidence": self.log_evidence, "stderr": self.stderr, "weights_ess": self.ess,
                "n_draws": self.n_draws, "method": self.method, "reliable": self.reliable}


def importance_evidence(log_prior: Callable[[np.ndarray], float],
                        log_likelihood_many: Callable[[np.ndarray], np.ndarray],
                        proposal: StudentT, n_draws: int, rng: np.random.Generator) -> EvidenceEstimate:
    """Estimate ln Z = ln ∫ π(θ) L(θ) dθ by importance sampling from ``proposal``.

    Parameters
    ----------
    log_prior : callable
        θ (ndim,) -> ln π(θ), normalised; ``-inf`` outside the support.
    log_likelihood_many : callable
        θ array (k, ndim) -> ln L at each row (normalised Gaussian likelihood); may run in parallel.
    proposal : StudentT
        Typically :meth:`StudentT.fit` on posterior samples.
    n_draws : int
    rng : numpy.random.Generator

    Returns
    -------
    EvidenceEstimate
    """
    theta = proposal.draw(int(n_draws), rng)
    lp = np.array([log_prior(t) for t in theta])
    ll = np.full(len(theta), -np.inf)
    inside = np.isfinite(lp)
    if inside.any():
        ll[inside] = log_likelihood_many(theta[inside])
    logw = np.where(np.isfinite(lp) & np.isfinite(ll), lp + ll, -np.inf) - proposal.logpdf(theta)
    if not np.isfinite(logw).any():
        return EvidenceEstimate(-math.inf, math.inf, 0.0, len(theta))
    m = float(np.max(logw))
    w = np.exp(logw - m)
    mean = float(np.mean(w))
    log_z = m + math.log(mean)
    se = float(np.std(w, ddof=1) / math.sqrt(w.size) / mean)
    ess = float(w.sum() ** 2 / np.sum(w**2))
    return EvidenceEstimate(log_z, se, ess, len(theta))


def model_probabilities(evidences: dict[str, EvidenceEstimate], *,
                        threshold: float = DECISIVE_PROBABILITY) -> dict:
    """Posterior model probabilities (equal prior probabilities) and a decision.

    Parameters
    ----------
    evidences : dict name -> EvidenceEstimate
    threshold : float
        A model is selected when its probability, with its log Bayes factor against the runner-up
        lowered by two combined Monte-Carlo standard errors, is at least this.

    Returns
    -------
    dict
        ``probabilities`` (name -> float), ``selected`` (name or None), ``favoured``,
        ``log_bayes_factor`` (favoured over runner-up) and its ``log_bayes_factor_stderr``,
        ``probability_lower`` (the conservative probability), ``threshold``, ``reliable``,
        ``explanation``.
    """
    names = list(evidences)
    lz = np.array([evidences[k].log_evidence for k in names])
    finite = np.isfinite(lz)
    probs = np.zeros(lz.size)
    if finite.any():
        probs[finite] = np.exp(lz[finite] - special.logsumexp(lz[finite]))
    order = np.argsort(-probs)
    best = names[order[0]]
    reliable = all(evidences[k].reliable for k in names)
    out = {"probabilities": dict(zip(names, probs.tolist())), "favoured": best, "threshold": threshold,
           "reliable": reliable, "method": evidences[best].method,
           "prior_model_probabilities": "equal"}
    if len(names) == 1:
        return out | {"selected": best, "log_bayes_factor": None, "log_bayes_factor_stderr": None,
                      "probability_lower": 1.0, "explanation": f"{best} imposed; not compared."}
    other = names[order[1]]
    lbf = float(lz[order[0]] - lz[order[1]])
    se = math.hypot(evidences[best].stderr, evidences[other].stderr)
    lower = float(stats.logistic.cdf(lbf - 2.0 * se)) if math.isfinite(lbf) and math.isfinite(se) else float("nan")
    decisive = reliable and lower >= threshold
    selected = best if decisive else None
    if decisive:
        why = (f"P({best}) = {probs[order[0]]:.4g} (≥ {threshold:g} even with ln B lowered by 2 Monte-Carlo "
               f"standard errors: {lower:.4g}): {best} is selected.")
    elif not reliable:
        why = ("the evidence estimate is unreliable (few effective importance weights): no slip condition is "
               "selected from it.")
    else:
        why = (f"P({best}) = {probs[order[0]]:.4g}, conservatively {lower:.4g} < {threshold:g}: the data do not "
               f"decide; no slip condition is selected.")
    return out | {"selected": selected, "log_bayes_factor": lbf, "log_bayes_factor_stderr": se,
                  "probability_lower": lower, "explanation": why}
