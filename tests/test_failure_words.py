"""Every failure in words (issue 20, item 5): each test fails on the code before it.

- noise-free curves are ``determined`` (they came out ``undetermined``: the optimiser stopped short at the
  turning point's kink, and the profile's sub-fits then found a lower χ² on both sides), with intervals
  that hold the truth, and without a drifting-zero warning;
- a zero-width or non-finite interval is never ``determined``;
- a test stopped inside delamination says so (it was explained as "never reached delamination");
- a relative shift past a first-order estimate is not printed as a number (+4e+02 %);
- a fit that did not converge says so first in its warnings, and on the command line.
Truths come from the generator's parameters and from the forward model's own stage column.
"""
from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import adhfit
from adhfit.fitting.intervals import honest
from adhfit.fitting.membrane import shift_text
from adhfit.fitting.result import Estimate
from adhfit.synthetic import synthetic_curve
from adhfit.scene import Scene

TRUE = {"work_of_adhesion": 0.4, "mu_h": 2.0}


def _scene(control: str, lambda0: float = 2.0) -> Scene:
    if control == "pressure":
        return Scene(membrane_radius="2 mm", substrate_radius="1 mm", control="pressure", gap="0 mm",
                     prestretch=lambda0, slip="auto", membrane_model="large-stretch")
    return Scene(membrane_radius="2 mm", substrate_radius="1 mm", control="displacement", pressure="1.2 kPa",
                 prestretch=lambda0, slip="auto", membrane_model="large-stretch")


@pytest.mark.parametrize("control,slip,lambda0", [("pressure", "no-slip", 5.0), ("displacement", "no-slip", 2.0)])
def test_noise_free_curves_are_determined(control, slip, lambda0):
    sc = _scene(control, lambda0)
    x_max = 1500.0 if control == "pressure" else 6e-4
    curve, _ = synthetic_curve(sc, slip, **TRUE, x_max=x_max, rows=200, noise=0.0, rng=np.random.default_rng(1))
    r = adhfit.fit(curve, sc)
    for name, value in TRUE.items():
        e = r.parameters[name]
        assert e.status == "determined", (name, e)
        assert e.ci95[0] <= value <= e.ci95[1] and e.ci95[1] / e.ci95[0] - 1 < 1e-3, (name, e)
    assert r.slip["selected"] == slip
    assert not any("drifted" in w for w in r.warnings), r.warnings


def test_zero_width_or_non_finite_interval_is_never_determined():
    flat = Estimate("work_of_adhesion", 0.1632, 0.0035, (0.1632, 0.1632), "profile", (0.156, 0.170), "determined")
    fixed = honest(flat)
    assert fixed.status == "determined" and fixed.ci95 == (0.156, 0.170) and "no width" in fixed.ci_method
    nothing = honest(dataclasses.replace(flat, ci95_covariance=None))
    assert nothing.status == "undetermined" and nothing.ci95 is None and nothing.as_dict()["value"] is None
    nan = honest(dataclasses.replace(flat, ci95=(0.15, float("nan")), ci95_covariance=None))
    assert nan.status == "undetermined"
    bound = honest(Estimate("work_of_adhesion", 0.3, None, (float("inf"), None), "profile", None, "lower_bound"))
    assert bound.status == "undetermined"


def test_a_test_stopped_inside_delamination_says_so():
    sc = _scene("displacement")
    curve, truth = synthetic_curve(sc, "no-slip", **TRUE, x_max=6e-4, rows=200, noise=0.005,
                                   rng=np.random.default_rng(8))
    # the stages from the forward model itself, at the true parameters
    hist = adhfit.simulate_scene(sc, mu_h="2 N/m", work_of_adhesion="0.4 J/m^2", slip="no-slip",
                                 delta_max=0.3, points=400).si
    stage = hist["stage"].to_numpy()
    delta = hist["displacement [m]"].to_numpy(float)
    stable = hist["stable"].to_numpy(bool)
    onset = float(delta[np.flatnonzero(stage == "delamination")[0]])
    x_tp = float(np.min(delta[stable & (stage == "delamination")]))
    down = np.arange(curve.i_turn + 1, len(curve.x))
    inside = down[(curve.x[down] < onset - 0.3 * (onset - x_tp)) & (curve.x[down] > x_tp + 0.2 * (onset - x_tp))]
    assert inside.size >= 3
    cut = int(inside[2]) + 1
    stopped = dataclasses.replace(curve, **{k: getattr(curve, k)[:cut] for k in ("x", "force", "line")},
                                  time=None, contact_radius=None)
    r = adhfit.fit(stopped, sc, slip="no-slip")
    w = r.parameters["work_of_adhesion"]
    assert w.status == "lower_bound" and w.ci95[0] <= TRUE["work_of_adhesion"]
    said = [x for x in r.warnings if x.startswith("The data only bound W_ad from below")]
    assert said and "into delamination" in said[0] and "starts to peel off" not in said[0], r.warnings


def test_nonsense_percentages_are_not_printed():
    assert shift_text(0.0123) == "+1.2 %"
    assert "%" in shift_text(4.0) and "4e+02" not in shift_text(4.0) and "more than 50 %" in shift_text(4.0)
    assert "more than" in shift_text(float("nan"))


def test_a_fit_that_did_not_converge_says_so(monkeypatch, tmp_path, capsys):
    import adhfit.fitting.lsq as lsq
    real = lsq.minimise

    def starved(residual, params, **kw):
        kw["max_nfev"] = 3
        return real(residual, params, **kw)
    monkeypatch.setattr(lsq, "minimise", starved)
    sc = _scene("displacement")
    curve, _ = synthetic_curve(sc, "no-slip", **TRUE, x_max=6e-4, rows=120, noise=0.01,
                               rng=np.random.default_rng(2))
    r = adhfit.fit(curve, sc, slip="no-slip", profile=False)
    assert not r.fits["no-slip"].success
    assert r.warnings[0].startswith("The fit did not converge")
    from adhfit.cli.writing import summary_text
    assert "WARNING: The fit did not converge" in summary_text(r, tmp_path)


def test_pull_off_term_is_censored():
    """The pull-off term is -2 ln P(turning point in the row gap), P from the normal CDF (scipy.stats,
    independently of the implementation's tail-safe log form): flat inside the gap, a wall outside."""
    from scipy import stats
    from adhfit.fitting.lsq import pull_off_term
    gap = (2.0, 1.0, 1.0 / 8)  # last attached row at x = 2, first detached at 1 (x falls on the way out)
    assert pull_off_term(gap, 1.5) ** 2 < 1e-3  # the middle of the gap
    for x in (1.3, 1.7):  # inside, 0.3 of the gap from an edge: no pull toward the middle (χ² < 0.02)
        assert pull_off_term(gap, x) ** 2 < 0.02
    for x in (0.9, 1.0, 1.05, 1.95, 2.1, 2.4):
        p = stats.norm.cdf((2.0 - x) * 8) - stats.norm.cdf((1.0 - x) * 8)
        assert pull_off_term(gap, x) == pytest.approx(np.sqrt(-2 * np.log(p)), rel=1e-9)
    assert pull_off_term(gap, 4.0) > 10 and np.isfinite(pull_off_term(gap, 40.0))


@pytest.mark.parametrize("control,slip", [("displacement", "no-slip"), ("pressure", "frictionless")])
def test_where_the_rows_fall_does_not_move_w_ad_or_the_verdict(control, slip):
    """One noise-free history sampled on 8 grids (rows 200..207, so the turning point falls at a different
    place between two rows each time), fitted with σ = 1 % of the peak force given: W_ad stays within
    0.5 standard errors of the truth on every grid and the slip ΔBIC moves by less than 2, or by less than
    5 % when the evidence is overwhelming (with the Gaussian pull-off term and the correlation widening of
    noise-free residuals, ΔBIC moved from 0.4 to 7.1 on the first case, crossing two evidence words)."""
    sc = _scene(control)
    x_max = 1500.0 if control == "pressure" else 6e-4
    ws, dbic = [], []
    for k in range(8):
        c, _ = synthetic_curve(sc, slip, **TRUE, x_max=x_max, rows=200 + k, noise=0.0,
                               rng=np.random.default_rng(0))
        r = adhfit.fit(c, sc, sigma=0.01 * float(np.max(c.force)), profile=False)
        e = r.fits[slip].parameters["work_of_adhesion"]
        ws.append((e.value - TRUE["work_of_adhesion"]) / e.stderr)
        dbic.append(r.slip["delta_bic"])
        assert r.slip["favoured"] == slip
    assert max(abs(z) for z in ws) < 0.5, ws
    assert max(dbic) - min(dbic) < max(2.0, 0.05 * min(dbic)), dbic


@pytest.mark.parametrize("control,slip,seed", [("pressure", "no-slip", 100), ("displacement", "frictionless", 101)])
def test_a_drifting_zero_is_fitted(control, slip, seed, runslow):
    """A 0 -> 1 % linear drift of the load-cell zero (1 % noise): the drift is fitted (offsets.force_drift
    within 3 standard errors of the truth), W_ad and μh intervals hold the truth, the verdict is not
    wrong.  Before, the drift was left in the data: W_ad coverage 0/5 under pressure control.  The full
    study (12 curves: both controls and slips, 3 seeds each: 12/12 W_ad and μh covered, no wrong verdict
    word above 'cannot tell') runs with --runslow."""
    sc = _scene(control)
    x_max = 1500.0 if control == "pressure" else 6e-4
    seeds = range(seed, seed + (3 if runslow else 1))
    for s in seeds:
        clean, _ = synthetic_curve(sc, slip, **TRUE, x_max=x_max, rows=200, noise=0.01, rng=np.random.default_rng(s))
        drift = 0.01 * float(np.max(clean.force))
        curve, _ = synthetic_curve(sc, slip, **TRUE, x_max=x_max, rows=200, noise=0.01, rng=np.random.default_rng(s),
                                   force_drift=drift)
        r = adhfit.fit(curve, sc)
        for name, value in TRUE.items():
            e = r.parameters[name]
            assert e.ci95[0] <= value <= e.ci95[1], (name, e)
        fitted = r.as_dict()["offsets"]["force_drift"]
        assert abs(fitted["value"] - drift) < 3 * fitted["stderr"], fitted
        assert r.slip["favoured"] == slip or r.slip["evidence"] == "cannot tell", r.slip
