"""Fits a lab can trust (issue 9): tests stopped early, an un-tared load cell, real noise levels,
correlated noise, a drifting zero, and the report's keys.

Curves come from :func:`adhfit.synthetic.synthetic_curve` (linear interpolation of a
2000-row forward history, independent of the fit's 150-row PCHIP interpolants), each with its own
seed.  Expected values are the curves' truths, never values the fit produced.
"""
from __future__ import annotations

import functools

import numpy as np
import pytest
from scipy import stats

from adhfit.data import Curve
from adhfit.fitting.api import fit as fit_curve
from adhfit.synthetic import synthetic_curve
from adhfit.scene import Scene

#: the synthetic curves are made with the large-stretch model: fit with it (not the default auto)
LsScene = functools.partial(Scene, membrane_model="large-stretch")

TRUE = {"work_of_adhesion": 0.4, "mu_h": 2.0}
SPHERE = (LsScene(membrane_radius="2 mm", substrate_radius="1 mm", control="displacement", pressure="1.2 kPa"),
          0.6e-3, 20e-6)
FLAT_P = (LsScene(membrane_radius="2 mm", substrate_radius="inf", control="pressure", gap="0.2 mm"), 1.6e3, 0.0)
JARGON = ("kink", "dF/dx", "χ²", "covariance", "profile", "optimiser", "start", "Jacobian")


def _curve(case=SPHERE, slip="no-slip", noise=0.01, seed=5, **kw):
    scene, x_max, off = case
    curve, truth = synthetic_curve(scene, slip, **TRUE, x_max=x_max, x_offset=off, noise=noise,
                                   rng=np.random.default_rng(seed), **kw)
    return scene, curve, truth


def _cut(curve: Curve, end: int) -> Curve:
    return Curve(path="<cut>", control=curve.control, x=curve.x[:end], force=curve.force[:end],
                 line=curve.line[:end], i_turn=curve.i_turn)


def _inside(e, truth: float) -> bool:
    lo, hi = e.ci95
    return (lo is None or lo <= truth) and (hi is None or truth <= hi)


@pytest.mark.parametrize("kind", ["right after the turn", "8 rows after the turn", "inside pinning",
                                  "inside delamination"])
def test_truncated_tests_give_honest_results(kind):
    """Every truncation gives a result (no internal error); W_ad is never a two-sided interval that
    excludes the truth; a test that stops before delamination bounds W_ad from below only."""
    scene, curve, truth = _curve()
    end = {"right after the turn": curve.i_turn + 2, "8 rows after the turn": curve.i_turn + 9,
           "inside pinning": curve.i_turn + 41, "inside delamination": truth["i_jump"] - 5}[kind]
    # 60-row histories (interpolation error ~1e-3 of the force, far below the 1 % noise) keep CI fast
    result = fit_curve(_cut(curve, end), scene, slip="no-slip", points=60)
    w = result.parameters["work_of_adhesion"]
    report = result.as_dict()["parameters"]["work_of_adhesion"]
    assert w.status in ("determined", "lower_bound", "undetermined")
    if w.status == "determined":
        assert _inside(w, TRUE["work_of_adhesion"]), w
    if kind != "inside delamination":
        assert w.status == "lower_bound", w
        assert report["value"] is None and report["ci95"][1] is None
        assert report["ci95"][0] <= TRUE["work_of_adhesion"]
        assert any("only bound W_ad from below" in s for s in result.warnings), result.warnings
    mu = result.parameters["mu_h"]
    assert mu.status == "determined" and _inside(mu, TRUE["mu_h"]), mu


def test_test_ending_in_pinning_with_an_outlier_last_row_is_a_lower_bound(tmp_path):
    """Regression (recovery study, displacement-flat, frictionless, stopped inside pinning, 2 % noise,
    replicate 0 of seed 20261201): the last row lies ~2.9σ above the pinning curve, and a W_ad that
    starts delamination in the last two rows fitted it, Δχ² = 8 below every pinning-only W_ad, which
    read as W_ad = 0.171 [0.163, 0.179] 'determined' for a true 0.4.  A test that ends is not a
    delamination: W_ad must come out as a lower bound at or below the truth (never a two-sided interval
    excluding it).  The curve is built by the study's own code with the study's seed key."""
    import sys
    from pathlib import Path
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))
    import recovery  # noqa: PLC0415
    import recovery_cases as rc  # noqa: PLC0415
    ss = recovery.seed_sequence(20261201, "displacement-flat", "frictionless", "trunc-pinning", 0.02, 0)
    path = tmp_path / "curve.csv"
    truth = rc.make_curve("displacement-flat", "frictionless", 0.02, "trunc-pinning",
                          np.random.default_rng(ss), path)
    assert not truth["pull_off_in_data"] and truth["G_max_reached"] < truth["work_of_adhesion"]
    result = fit_curve(str(path), rc.CASES["displacement-flat"].scene, slip="frictionless")
    w = result.parameters["work_of_adhesion"]
    assert w.status == "lower_bound", w
    assert w.ci95[1] is None and w.ci95[0] <= truth["work_of_adhesion"], w


def test_untared_load_cell_is_fitted_by_default():
    """A load-cell zero of +1.5 % of the peak force: with default options W_ad, μh and the zero are
    recovered inside their 95 % intervals (before, W_ad moved by -4 to -5 % and the interval
    excluded the truth)."""
    scene, x_max, off = SPHERE
    probe, _ = _curve(noise=0.005, seed=11)[1:]
    f0 = 0.015 * float(np.max(probe.force))
    scene, curve, truth = _curve(noise=0.005, seed=11, force_offset=f0)
    result = fit_curve(curve, scene, slip="no-slip")  # default offsets: the load-cell zero is fitted
    for name in TRUE:
        assert result.parameters[name].status == "determined"
        assert _inside(result.parameters[name], TRUE[name]), result.parameters[name]
    zero = result.as_dict()["offsets"]["force"]
    assert zero["fitted"] and zero["ci95"][0] <= f0 <= zero["ci95"][1], zero
    # a clean fit: no warnings of any kind, no solver jargon
    assert not any(j in w for w in result.warnings for j in JARGON), result.warnings
    assert not any("correlated" in w or "drift" in w for w in result.warnings), result.warnings


def test_force_offset_can_be_fixed():
    scene, curve, truth = _curve(noise=0.005, seed=12)
    result = fit_curve(curve, scene, slip="no-slip", fit_force_offset=False, profile=False, points=60)
    zero = result.as_dict()["offsets"]["force"]
    assert zero["value"] == 0.0 and not zero["fitted"] and zero["note"]
    assert "force_offset" not in result.parameters


def _coverage(combos, compare_slips: bool) -> int:
    misses = 0
    for k, (case, slip) in enumerate(combos):
        scene, curve, truth = _curve(case, slip, noise=0.04, seed=900 + k)
        result = fit_curve(curve, scene, slip="auto" if compare_slips else slip)
        assert result.slip["selected"] in (slip, None), result.slip      # never the wrong condition
        misses += sum(not _inside(result.parameters[n], TRUE[n]) for n in TRUE)
    return misses


def test_coverage_at_four_percent_noise():
    """Reduced coverage check at 4 % force noise: 2 curves (a sphere under displacement control, a flat
    under pressure control), 4 intervals.  With a true coverage of 95 % the misses X ~ Binomial(4, 0.05),
    P(X >= 2) = 1.4 %: the test allows 1.  (Before issue 9 the pull-off jump was missed at this noise and
    W_ad's interval held the truth in 0-7 % of curves: 2 misses or more were the rule.)  The slip is
    imposed here to keep CI short; the slow variant compares both."""
    assert _coverage([(SPHERE, "no-slip"), (FLAT_P, "frictionless")], compare_slips=False) <= 1
    assert stats.binom.sf(1, 4, 0.05) < 0.02


@pytest.mark.slow
def test_coverage_at_four_percent_noise_full():
    """4 curves (both controls, both slips), 8 intervals: X ~ Binomial(8, 0.05), P(X >= 3) = 0.6 %;
    the slip compared (never the wrong one selected)."""
    assert _coverage([(SPHERE, "no-slip"), (SPHERE, "frictionless"), (FLAT_P, "no-slip"),
                      (FLAT_P, "frictionless")], compare_slips=True) <= 2
    assert stats.binom.sf(2, 8, 0.05) < 0.01


def test_correlated_noise_is_detected_and_widens_the_intervals():
    """Oversampled rows (AR(1) noise, ρ = 0.8): a plain warning and intervals widened by about
    sqrt((1 + ρ)/(1 - ρ)) = 3 against the same curve with white noise of the same σ."""
    scene, clean, truth = _curve(noise=0.0)
    rng = np.random.default_rng(21)
    sigma = 0.01 * float(np.max(clean.force))
    e = rng.normal(0.0, sigma, clean.force.size)
    ar = np.empty_like(e)
    ar[0] = e[0]
    for i in range(1, e.size):  # unit-variance AR(1): x_i = ρ x_{i-1} + sqrt(1 - ρ²) e_i
        ar[i] = 0.8 * ar[i - 1] + np.sqrt(1 - 0.8 ** 2) * e[i]
    widths = {}
    for label, noise in (("white", e), ("ar", ar)):
        curve = Curve(path="<syn>", control=clean.control, x=clean.x, force=clean.force + noise,
                      line=clean.line, i_turn=clean.i_turn)
        result = fit_curve(curve, scene, slip="no-slip", profile=False, points=60)
        mu = result.parameters["mu_h"]
        widths[label] = np.log(mu.ci95[1] / mu.ci95[0])
        correlated = any("correlated from row to row" in w for w in result.warnings)
        assert correlated == (label == "ar"), (label, result.warnings)
        if label == "ar":
            assert _inside(mu, TRUE["mu_h"]) and _inside(result.parameters["work_of_adhesion"], 0.4)
    assert widths["ar"] > 1.8 * widths["white"], widths


def test_zero_drift_is_warned_about():
    """A linear drift of the load-cell zero (3 % of the peak force over the test) is named in a
    plain sentence."""
    scene, curve, truth = _curve(noise=0.005, seed=31)
    drift = 0.03 * float(np.max(curve.force)) * np.linspace(0.0, 1.0, curve.force.size)
    drifted = Curve(path="<syn>", control=curve.control, x=curve.x, force=curve.force + drift,
                    line=curve.line, i_turn=curve.i_turn)
    result = fit_curve(drifted, scene, slip="no-slip", profile=False, points=60)
    assert any("drifted" in w for w in result.warnings), result.warnings
