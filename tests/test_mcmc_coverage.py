"""Coverage of the MCMC 95 % credible intervals on synthetic curves with known truth.

Each replicate draws a new noisy curve (0.5 % force noise, a displacement offset) from the forward model
with W_ad = 0.4 J/m², μh = 2 N/m (the paper's FEA set), fits it by MCMC with the true slip condition
imposed, and records whether each 95 % interval holds the truth (and that the median is within 5 %).

Tolerance: for n intervals of a parameter the number that cover is Binomial(n, 0.95) if the intervals
are calibrated; the test fails when that count is in the lower 0.1 % tail (two-sided test at ~0.1 %:
the upper tail cannot be reached with 50 replicates).  The full run (``--runslow``) has 50 replicates
with the default sampler settings; the CI variant has 2 replicates with tiny chains, where "at most one
of the four intervals misses" has probability 0.9995 for calibrated intervals.
"""
from __future__ import annotations

import functools

import numpy as np
import pytest
from scipy import stats

TRUTH = {"work_of_adhesion": 0.4, "mu_h": 2.0}


def _replicate(seed: int, **settings) -> dict:
    from functools import partial  # noqa: PLC0415
    from adhfit.fitting.api import fit  # noqa: PLC0415
    fit_curve_mcmc = partial(fit, method="mcmc")
    from adhfit.synthetic import synthetic_curve
    from adhfit.scene import Scene
    LsScene = functools.partial(Scene, membrane_model="large-stretch")
    scene = LsScene(membrane_radius="2 mm", substrate_radius="1 mm", control="displacement", pressure="1.2 kPa",
                  slip="no-slip")
    rng = np.random.default_rng(seed)
    curve, _ = synthetic_curve(scene, "no-slip", x_max=6e-4, rows=150, noise=0.005,
                               x_offset=float(rng.uniform(-3e-5, 3e-5)), rng=rng, **TRUTH)
    res = fit_curve_mcmc(curve, scene, seed=seed, progress=False, **settings)
    return {k: (res.parameters[k].ci95, res.parameters[k].value) for k in TRUTH}


def _check(results: list[dict], alpha: float) -> None:
    n = len(results)
    for name, truth in TRUTH.items():
        covered = sum(lo <= truth <= hi for (lo, hi), _ in (r[name] for r in results))
        assert stats.binom.cdf(covered, n, 0.95) > alpha, f"{name}: {covered}/{n} intervals cover the truth"
        for r in results:
            assert abs(r[name][1] / truth - 1) < 0.05


def test_coverage_reduced():
    results = [_replicate(s, workers=1, n_walkers=6, n_ensembles=2, tune_steps=10, max_steps=15,
                          predictive_draws=4) for s in (101, 102)]
    covered = sum(lo <= TRUTH[k] <= hi for r in results for k, ((lo, hi), _) in r.items())
    assert covered >= 3, results
    for r in results:
        for k, (_, med) in r.items():
            assert abs(med / TRUTH[k] - 1) < 0.05


@pytest.mark.slow
def test_coverage_full():
    _check([_replicate(1000 + s) for s in range(50)], alpha=1e-3)
