"""The load-cell zero and drift integrated out of the posterior (adhfit.fitting.bayes.linear).

Checked against independent computations: the marginal log posterior against a Gauss-Hermite quadrature
of the joint posterior over the zero and the drift; the completed chain against a run that samples every
coordinate.
"""
from __future__ import annotations

import functools
import math

import numpy as np
import pytest
from scipy import special

from adhfit.fitting.bayes.linear import Marginal
from adhfit.fitting.bayes.mcmc import sample_posterior
from adhfit.fitting.bayes.posterior import Target, default_priors
from adhfit.fitting.lsq import fit_slip
from adhfit.fitting.model import CurveModel
from adhfit.fitting.objective import ObjectiveFit
from adhfit.scene import Scene
from adhfit.synthetic import synthetic_curve


def _target(sigma=None):
    scene = functools.partial(Scene, membrane_model="large-stretch")(
        membrane_radius="2 mm", substrate_radius="1 mm", control="displacement", pressure="1.2 kPa", slip="auto")
    curve, _ = synthetic_curve(scene, "no-slip", work_of_adhesion=0.4, mu_h=2.0, x_max=6e-4, rows=90,
                               noise=0.01, x_offset=2e-5, force_offset=3e-6, force_drift=-4e-6,
                               approach=0.25, tail=0.3, rng=np.random.default_rng(8))
    raw = fit_slip(CurveModel(curve, scene, "no-slip"), sigma=sigma)
    pri = default_priors(raw.par, [raw.par.si(raw.best.params)], {})
    tg = Target(ObjectiveFit.from_single(raw), list(raw.par.names), [pri[n] for n in raw.par.names])
    return tg, tg.theta0(), raw.best.covar


@pytest.fixture(scope="module", params=[False, True], ids=["sigma-unknown", "sigma-given"])
def target(request):
    tg, theta0, cov = _target()
    if request.param:  # the same curve with σ given (the estimate of the first fit)
        tg, theta0, cov = _target(sigma=float(tg.fit.sigma))
    assert {"force_offset", "force_drift"} <= set(tg.names)  # both linear coordinates are there to integrate
    return tg, theta0, cov


def _quadrature(tg, theta, lin, centre, sd, nodes=60):
    """ln ∫ exp(ln π(θ with β)) dβ over the linear coordinates, tensor Gauss-Hermite around ``centre``."""
    x, w = special.roots_hermite(nodes)
    total = []
    for i in range(nodes):
        for j in range(nodes):
            th = theta.copy()
            th[lin[0]] = centre[0] + math.sqrt(2.0) * sd[0] * x[i]
            th[lin[1]] = centre[1] + math.sqrt(2.0) * sd[1] * x[j]
            total.append(tg(th) + x[i] ** 2 + x[j] ** 2 + math.log(w[i] * w[j]))
    return special.logsumexp(total) + math.log(2.0 * sd[0] * sd[1])


def test_marginal_equals_the_integral_of_the_joint(target):
    tg, theta0, cov = target
    m = Marginal.of(tg, theta0, cov)
    assert m is not None and m.ndim == tg.ndim - 2
    lin = m.linear
    sd = np.sqrt(np.diag(cov))[lin]
    for shift in (0.0, 1.5):  # at the optimum and away from it (W_ad and μh moved by 1.5 standard errors)
        theta = theta0.copy()
        theta[m.free] += shift * np.sqrt(np.diag(cov))[m.free]
        # centre the quadrature on the least-squares zero and drift at θ0 (not the marginal's β̂)
        q = _quadrature(tg, theta, lin, theta0[lin], sd)
        assert m.log_posterior(theta[m.free]) == pytest.approx(q, abs=2e-6)


def test_completed_chain_samples_the_joint_posterior(target):
    """Integrating out and drawing back the zero and drift gives the posterior that sampling every
    coordinate gives: means within 0.15 sd and sds within 10 % (both runs have ESS > 1000; the
    Monte-Carlo error of a mean is < 0.05 sd)."""
    tg, theta0, cov = target
    kw = {"n_walkers": 8, "n_ensembles": 4, "tune_steps": 15, "check_every": 5, "max_steps": 300,
          "progress": False}
    fast = sample_posterior(tg, theta0, cov, seed=3, **kw)
    full = sample_posterior(tg, theta0, cov, seed=4, integrate_linear=False, **kw)
    assert fast.converged and full.converged
    assert fast.chain.shape[-1] == full.chain.shape[-1] == tg.ndim
    assert fast.n_evaluations < 0.85 * full.n_evaluations
    a, b = fast.flat, full.flat
    sd = b.std(axis=0)
    np.testing.assert_array_less(np.abs(a.mean(axis=0) - b.mean(axis=0)) / sd, 0.15)
    np.testing.assert_allclose(a.std(axis=0) / sd, 1.0, atol=0.1)
    # the joint log posterior stored with the completed chain is the target's own
    k = fast.burn
    for e, s, w in ((0, k, 0), (1, k + 7, 3), (3, -1, 5)):
        assert fast.log_prob[e, s, w] == pytest.approx(tg(fast.chain[e, s, w]), abs=1e-7)


def test_no_integral_where_a_prior_edge_is_near(target):
    """A zero or drift whose flat prior ends within a few standard errors of its estimate keeps being sampled."""
    import dataclasses
    tg, theta0, cov = target
    k = tg.names.index("force_offset")
    p = tg.priors[k]
    v = theta0[k] * p.factor
    near = dataclasses.replace(p, a=v - 2.0 * math.sqrt(cov[k, k]) * p.factor, b=v + 1.0)
    tight = Target(tg.fit, tg.names, [near if i == k else q for i, q in enumerate(tg.priors)])
    assert Marginal.of(tight, theta0, cov) is None
    assert Marginal.of(tg, theta0, cov) is not None
