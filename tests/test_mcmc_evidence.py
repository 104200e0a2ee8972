"""The evidence estimator (adhfit.fitting.evidence) against analytic evidences, and the slip decision rule.

Gaussian-linear model: y = X β + ε, ε ~ N(0, σ² I), prior β ~ N(0, s² I) has the analytic evidence
y ~ N(0, σ² I + s² X Xᵀ).  With a flat box prior much wider than the posterior the evidence is the
Gaussian integral of the likelihood over the box volume.  Tolerances: four Monte-Carlo standard errors
(the estimator reports its own) plus 1e-9; the reported error itself is checked to be honest across
seeds (its z-scores have a spread near one).
"""
from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import stats

from adhfit.fitting.selection import StudentT, importance_evidence, model_probabilities


def _linear_problem(seed: int, n: int = 30, k: int = 3, sigma: float = 0.5, s: float = 2.0):
    rng = np.random.default_rng(seed)
    x = np.column_stack([np.ones(n), rng.uniform(-1, 1, (n, k - 1))])
    beta = rng.normal(0, s, k)
    y = x @ beta + rng.normal(0, sigma, n)
    return x, y, sigma, s


def _loglik(x, y, sigma):
    def many(thetas):
        r = y[None, :] - np.asarray(thetas) @ x.T
        return -0.5 * np.sum(r**2, axis=1) / sigma**2 - 0.5 * len(y) * math.log(2 * math.pi * sigma**2)
    return many


def _posterior_draws(x, y, sigma, s, rng, n=4000):
    prec = x.T @ x / sigma**2 + np.eye(x.shape[1]) / s**2
    cov = np.linalg.inv(prec)
    mean = cov @ x.T @ y / sigma**2
    return rng.multivariate_normal(mean, cov, n)


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_gaussian_linear_normal_prior(seed):
    x, y, sigma, s = _linear_problem(seed)
    exact = stats.multivariate_normal(np.zeros(len(y)), sigma**2 * np.eye(len(y)) + s**2 * x @ x.T).logpdf(y)
    rng = np.random.default_rng(seed + 100)
    prior = stats.multivariate_normal(np.zeros(x.shape[1]), s**2 * np.eye(x.shape[1]))
    est = importance_evidence(prior.logpdf, _loglik(x, y, sigma), StudentT.fit(_posterior_draws(x, y, sigma, s, rng)),
                              2000, rng)
    assert est.reliable and est.ess > 1000
    assert abs(est.log_evidence - exact) < 4 * est.stderr + 1e-9


def test_gaussian_linear_box_prior():
    x, y, sigma, _ = _linear_problem(7)
    k = x.shape[1]
    half = 50.0
    prec = x.T @ x / sigma**2
    bhat = np.linalg.solve(x.T @ x, x.T @ y)
    r = y - x @ bhat
    # ∫ L dβ over R^k (the box holds it all), times the box density (2 half)^-k
    exact = (-0.5 * r @ r / sigma**2 - 0.5 * len(y) * math.log(2 * math.pi * sigma**2)
             + 0.5 * k * math.log(2 * math.pi) - 0.5 * np.linalg.slogdet(prec)[1] - k * math.log(2 * half))
    log_prior = lambda t: -k * math.log(2 * half) if np.all(np.abs(t) <= half) else -math.inf  # noqa: E731
    rng = np.random.default_rng(8)
    draws = rng.multivariate_normal(bhat, np.linalg.inv(prec), 3000)
    est = importance_evidence(log_prior, _loglik(x, y, sigma), StudentT.fit(draws), 2000, rng)
    assert abs(est.log_evidence - exact) < 4 * est.stderr + 1e-9


def test_reported_stderr_is_honest():
    """Across 40 seeds the z-scores (estimate - exact)/stderr have sd ~ 1 (0.6-1.6 allows for 40 samples
    of heavy-ish tailed z's; a stderr too small by 2x would give ~2)."""
    x, y, sigma, s = _linear_problem(11, n=20)
    exact = stats.multivariate_normal(np.zeros(len(y)), sigma**2 * np.eye(len(y)) + s**2 * x @ x.T).logpdf(y)
    prior = stats.multivariate_normal(np.zeros(x.shape[1]), s**2 * np.eye(x.shape[1]))
    rng = np.random.default_rng(12)
    post = _posterior_draws(x, y, sigma, s, rng, 300)  # a rough proposal on purpose: visible MC error
    z = []
    for seed in range(40):
        est = importance_evidence(prior.logpdf, _loglik(x, y, sigma), StudentT.fit(post, inflate=1.6), 100,
                                  np.random.default_rng(seed))
        z.append((est.log_evidence - exact) / est.stderr)
    assert 0.6 < np.std(z) < 1.6
    assert abs(np.mean(z)) < 0.6


def test_student_t_matches_scipy():
    rng = np.random.default_rng(0)
    a = rng.normal(size=(3, 3))
    q = StudentT(np.array([1.0, -2.0, 0.5]), a @ a.T + np.eye(3), 5.0)
    pts = rng.normal(size=(10, 3))
    ref = stats.multivariate_t(q.mean, q.scale, df=q.df).logpdf(pts)
    np.testing.assert_allclose(q.logpdf(pts), ref, rtol=1e-12)
    draws = q.draw(20000, np.random.default_rng(1))
    np.testing.assert_allclose(np.cov(draws, rowvar=False), q.scale * 5 / 3, rtol=0.15, atol=0.1)


class _Ev:
    def __init__(self, lz, se=0.01, ess=500.0):
        from adhfit.fitting.selection import EvidenceEstimate
        self.e = EvidenceEstimate(lz, se, ess, 1000)


def _probs(a, b, **kw):
    return model_probabilities({"no-slip": _Ev(a, **kw).e, "frictionless": _Ev(b, **kw).e})


def test_decision_rule():
    d = _probs(10.0, 0.0)
    assert d["selected"] == "no-slip" and d["probabilities"]["no-slip"] > 0.9999
    assert _probs(0.0, 1.0)["selected"] is None            # P = 0.73: not decisive
    assert _probs(0.0, 1.0)["favoured"] == "frictionless"
    assert _probs(3.0, 0.0)["selected"] == "no-slip"        # P = 0.953, MC error tiny
    assert _probs(3.0, 0.0, se=0.2)["selected"] is None     # ... but not with ln B - 2 SE < logit(0.95)
    assert _probs(10.0, 0.0, ess=5.0)["selected"] is None   # unreliable estimate: never a silent pick
