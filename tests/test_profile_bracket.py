"""Profile limits found when sqrt(D) bends up steeply past the limit (the plan check's finding).

The first probe of a side is placed from the covariance; where that standard error is inflated, the
probe lands far beyond the limit (sqrt(D/crit) = 74) and regula falsi kept it as one end of the bracket,
creeping toward the limit from the other: eight sub-fits ended 10 % short, and the far probe (W_ad 0.23
against a limit near 0.42 J/m^2) was reported as the interval's end.
"""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from adhfit.fitting.profile import MAX_SUBFITS, TOL, _next_step

ROOT = Path(__file__).resolve().parents[1]


def _steps_to_limit(q, t_first: float, se: float) -> int:
    """Sub-fits the step rule needs to find q(t) = 1 to TOL, starting at t_first (as profile._side)."""
    tried, t = [], t_first
    for k in range(40):
        tried.append((t, q(t)))
        if abs(tried[-1][1] - 1.0) < TOL:
            return k + 1
        t = _next_step(tried, math.copysign(1.0, t_first), se)
    return 99


@pytest.mark.parametrize("power", [0.7, 1.0, 1.5])
def test_a_far_first_probe_on_a_kinked_profile_is_found_in_few_subfits(power):
    # sqrt(D/crit) rises like |t|^power to the limit at t = -0.028, then 3.4 times as steeply (the model's
    # pull-off crossing rows), and the first probe lands 22 limits out, at q = 72 (74 in the plan check)
    limit = -0.028

    def q(t):
        r = t / limit
        return r ** power if r <= 1.0 else 1.0 + 3.4 * (r - 1.0)

    assert q(-0.61) == pytest.approx(71.7, abs=0.1)
    assert _steps_to_limit(q, -0.61, 0.31) <= MAX_SUBFITS


def test_the_plan_checks_shallow_frictionless_curve_has_a_converged_no_slip_profile(tmp_path):
    """A replicate of the plan check (disp-shallow-fr, seed 73000): the no-slip W_ad profile's lower side
    ended at a probe at 0.233 J/m^2, far below its limit."""
    import adhfit
    from adhfit.scene import load_scene
    from adhfit.synthetic import measured_frame
    scene = load_scene(ROOT / "sample_data" / "flat_displacement_no-slip" / "scene.toml")
    frame, _ = measured_frame(scene, "frictionless", mu_h=1.5, work_of_adhesion=0.3, x_max=1.3e-4, rows=300,
                              noise=0.03, seed=73000)
    path = tmp_path / "curve.csv"
    frame.to_csv(path, index=False, float_format="%.9g")
    r = adhfit.fit(path, scene)
    ns = r.fits["no-slip"]
    assert ns.profile["work_of_adhesion"]["converged"] == [True, True]
    lo, hi = ns.parameters["work_of_adhesion"].ci95
    w = ns.parameters["work_of_adhesion"].value
    assert 0.9 * w < lo < w < hi
    assert not any("did not converge" in m for m in r.warnings)


def test_a_kink_narrowed_covariance_does_not_replace_the_profile(tmp_path):
    """A replicate of the recovery study (pressure-curved, no-slip, 3 % noise, seed 20261220, replicate 8):
    at the turning point's kink the covariance gives ln μh a standard error of 0.0007 (0.07 % at 3 % noise).
    Two sub-fits a few of those out were called an open (flat) side, and a sub-fit 4e-4 units of D below the
    optimum sent the report to the covariance: μh 1.9253-1.9276 N/m, missing the truth 2.0.  The profile
    itself, followed beyond FLAT_MIN, is 1.857-2.009."""
    import sys
    sys.path.insert(0, str(ROOT / "benchmarks"))
    import recovery
    import recovery_cases as rc
    from adhfit import fit
    ss = recovery.seed_sequence(20261220, "pressure-curved", "no-slip", "clean", 0.03, 8)
    path = tmp_path / "curve.csv"
    rc.make_curve("pressure-curved", "no-slip", 0.03, "clean", np.random.default_rng(ss), path)
    r = fit(str(path), rc.CASES["pressure-curved"].scene, slip="auto")
    e = r.parameters["mu_h"]
    assert e.status == "determined" and e.ci95[0] < 2.0 < e.ci95[1]
    assert math.log(e.ci95[1] / e.ci95[0]) > 0.05  # not the covariance's 0.1 %
    prof = r.fits["no-slip"].profile["mu_h"]
    assert prof["converged"] == [True, True] and prof["open"] == [False, False]
