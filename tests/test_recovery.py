"""Synthetic recovery: curves from the forward model plus Gaussian force noise, fitted by ``fit_curve``.

Truth must lie inside the reported 95 % intervals at a rate consistent with 95 %, estimates must be
within 5 %, the slip condition must be identified at low noise (never the wrong one) and reported
undecidable at high noise.  Every replicate has its own explicit seed (numpy ``default_rng``).
"""
from __future__ import annotations

import functools

import numpy as np
import pytest
from scipy import stats

from adhfit.fitting.fit import fit_curve
from adhfit.fitting.synthetic import synthetic_curve
from adhfit.scene import Scene

#: the synthetic curves are made with the large-stretch model: fit with it (not the default auto)
LsScene = functools.partial(Scene, membrane_model="large-stretch")

TRUE = {"work_of_adhesion": 0.4, "mu_h": 2.0}
#: the paper's FEA set (b = 2 mm, R_s = 1 mm, 1.2 kPa / gap 0) and a flat substrate
CASES = {
    "displacement": (LsScene(membrane_radius="2 mm", substrate_radius="1 mm", control="displacement",
                           pressure="1.2 kPa"), 0.6e-3, 20e-6),
    "pressure": (LsScene(membrane_radius="2 mm", substrate_radius="1 mm", control="pressure", gap="0 mm"),
                 1.6e3, 0.0),
    "displacement-flat": (LsScene(membrane_radius="2 mm", substrate_radius="inf", control="displacement",
                                pressure="1.2 kPa"), 0.4e-3, -30e-6),
    "pressure-flat": (LsScene(membrane_radius="2 mm", substrate_radius="inf", control="pressure",
                            gap="0.2 mm"), 1.6e3, 0.0),
}
COMBOS = [(c, s) for c in ("displacement", "pressure") for s in ("no-slip", "frictionless")]


def _replicate(case, slip, seed, noise=0.005, fit_slip="auto", profile=True):
    scene, x_max, off = CASES[case]
    curve, truth = synthetic_curve(scene, slip, **TRUE, x_max=x_max, x_offset=off, noise=noise,
                                   rng=np.random.default_rng(seed))
    return fit_curve(curve, scene, slip=fit_slip, profile=profile), truth


def _misses(result) -> list[str]:
    ci = {name: result.parameters[name].ci95 for name in TRUE}
    return [name for name in TRUE if ci[name] is None or not ci[name][0] <= TRUE[name] <= ci[name][1]]


def _check_point(result, slip):
    assert result.slip["selected"] in (slip, None), result.slip      # never the wrong condition
    for name in TRUE:
        assert abs(result.parameters[name].value / TRUE[name] - 1) < 0.05, (name, result.parameters[name])


def test_recovery_ci():
    """Reduced variant: one replicate per control x slip (8 intervals in all).

    Tolerance: with a true coverage of 95 %, 3 or more misses among 8 intervals have probability
    1 - P(X <= 2 | n=8, p=0.05) = 0.6 %; the seeds are fixed, so the test is deterministic.
    """
    misses = []
    for i, (control, slip) in enumerate(COMBOS):
        result, _ = _replicate(control, slip, seed=1000 + i)
        _check_point(result, slip)
        assert result.slip["selected"] == slip, result.slip   # 0.5 % noise: decisive
        misses += _misses(result)
    assert len(misses) <= 2, misses
    assert stats.binom.sf(2, 8, 0.05) < 0.01


def test_slip_undecidable_at_high_noise():
    """At 10x the noise (5 %) the two conditions' fits differ by far less than the decisive ΔBIC."""
    result, _ = _replicate("displacement", "no-slip", seed=7, noise=0.05, profile=False)
    assert result.slip["selected"] is None
    assert result.slip["verdict"] == "the data cannot tell them apart"
    assert any("undecided" in w for w in result.warnings)


@pytest.mark.slow
@pytest.mark.parametrize("case", list(CASES))
@pytest.mark.parametrize("slip", ["no-slip", "frictionless"])
def test_coverage_full(case, slip):
    """Full variant: 50 seeded replicates per case (curved and flat) and slip condition.

    Per parameter, with a true coverage of 95 % the number of misses X ~ Binomial(50, 0.05): the test
    allows X <= 7 (P(X >= 8) = 0.3 %). Every replicate must recover W_ad and μh within 5 % and never
    select the wrong slip condition; at 0.5 % noise at least 45 of 50 must select the right one.
    """
    n, misses, selected = 50, {name: 0 for name in TRUE}, 0
    for seed in range(n):
        result, _ = _replicate(case, slip, seed=10_000 + seed)
        _check_point(result, slip)
        selected += result.slip["selected"] == slip
        for name in _misses(result):
            misses[name] += 1
    assert all(m <= 7 for m in misses.values()), misses
    assert stats.binom.sf(7, n, 0.05) < 0.005
    assert selected >= 45, selected
