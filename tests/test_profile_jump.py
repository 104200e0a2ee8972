"""Profile intervals across the pull-off's jump in χ² (adhfit.fitting.intervals.gap_start), and in the hull of an
undecided slip.

Shallow displacement-control tests (flat punch, W_ad = 0.3 J/m², μh = 1.5 N/m, δ_max = 0.13 mm, 300 rows, 3 %
noise, no-slip): with W_ad fixed, χ² has a local minimum on each side of the configuration where the model's
pull-off crosses the last attached row, and profile sub-fits started from the optimum's side stayed in the
wrong one, several units of χ² above the profile.  Before the second start, 9 of 71 two-sided W_ad intervals
of seeds 22000-22079 missed the true W_ad (decided fits: 35/44 = 0.80); with it 3 of 71 (42/45), and 1 of 65 on
seeds 23000-23079.  These are three of the seeds that missed.
"""
from __future__ import annotations

import pytest

SCENE = "sample_data/flat_displacement_no-slip/scene.toml"


@pytest.mark.parametrize("seed", [22002, 22012, 22032])
def test_profile_interval_holds_the_truth_where_the_old_one_missed(seed, tmp_path):
    import adhfit
    from adhfit.scene import load_scene
    from adhfit.synthetic import measured_frame
    df, _ = measured_frame(load_scene(SCENE), "no-slip", mu_h=1.5, work_of_adhesion=0.3, x_max=1.3e-4, rows=300,
                           noise=0.03, seed=seed)
    path = tmp_path / "curve.csv"
    df.to_csv(path, index=False)
    w = adhfit.fit(path, SCENE).parameters["work_of_adhesion"]
    assert w.status == "determined" and w.ci_method.startswith("profile")
    assert w.ci95[0] <= 0.3 <= w.ci95[1], w
    assert w.ci95[1] - w.ci95[0] < 0.03  # still an interval that says something (±5 %)


def test_an_undecided_slip_hulls_both_profiles_not_a_covariance(tmp_path):
    """An undecided slip reports the hull of both conditions' intervals; the unfavoured condition's
    covariance interval is fragile at the pull-off's kink (here no-slip's was [0.08, 0.98] J/m² from a
    standard error of 64 % of W_ad), so both come from their profiles.  Frictionless pressure-control test,
    900 Pa, 5 % noise, seed 1000 (found by the plan's check against fits)."""
    import adhfit
    from adhfit.scene import load_scene
    from adhfit.synthetic import measured_frame
    scene = "sample_data/flat_pressure_frictionless/scene.toml"
    df, _ = measured_frame(load_scene(scene), "frictionless", mu_h=1.5, work_of_adhesion=0.3, x_max=900, rows=300,
                           noise=0.05, seed=1000)
    path = tmp_path / "curve.csv"
    df.to_csv(path, index=False)
    r = adhfit.fit(path, scene)
    assert r.slip["selected"] is None
    w = r.parameters["work_of_adhesion"]
    for fit in r.fits.values():
        assert fit.parameters["work_of_adhesion"].ci_method.startswith("profile")
    assert "hull over both slip conditions" in w.ci_method
    assert w.ci95[0] <= 0.3 <= w.ci95[1] and w.ci95[1] - w.ci95[0] < 0.1
