"""Physical units (SceneResult) and the membrane profile z(r), against independent facts."""
from __future__ import annotations

import math

import numpy as np
import pytest

import adhfit
from adhfit.core.profile import profile
from adhfit.physical import simulate_scene
from adhfit.scene import Scene

# the paper's FEA set (section 4, docs/numerics.md C): b = 2 mm, mu h = 2 N/m -> force scale 8 mN,
# pressure scale 2 kPa; P = 1.2 kPa -> p = 0.6; R_s = 1 mm -> rs = 0.5; W = 0.4 J/m^2 -> w = 0.2
FEA = dict(membrane_radius="2 mm", substrate_radius="1 mm", control="displacement",
           pressure="1.2 kPa", mu_h="2 N/m", work_of_adhesion="0.4 J/m^2", slip="no-slip",
           contact_radius_max="0.5 mm")


def test_si_frame_is_the_dimensionless_one_scaled_by_hand():
    res = simulate_scene(Scene(**FEA))
    dim = adhfit.simulate("displacement", "no-slip", p=0.6, w=0.2, rs=0.5, a_max=0.25).frame
    si = res.si
    np.testing.assert_allclose(si["force [N]"], dim.f * 8e-3, rtol=1e-12, atol=0)
    np.testing.assert_allclose(si["pressure [Pa]"], 1200.0, rtol=1e-12)
    np.testing.assert_allclose(si["contact_radius [m]"], dim.a * 2e-3, rtol=1e-12, atol=0)
    np.testing.assert_allclose(si["displacement [m]"], dim.delta * 2e-3, rtol=1e-12, atol=1e-18)
    np.testing.assert_allclose(si["energy_release_rate [J/m^2]"], dim.G * 2.0, rtol=1e-12, atol=0)
    assert res.summary_si["force_max [N]"] == pytest.approx(res.result.summary["f_max"] * 8e-3)


def test_b_not_one_changes_nothing_dimensionless():
    """docs/numerics.md C: test in SI with b != 1 so a stray factor b would show."""
    base = simulate_scene(Scene(**FEA))
    big = simulate_scene(Scene(**{**FEA, "membrane_radius": "4 mm", "substrate_radius": "2 mm",
                                  "pressure": "0.6 kPa", "contact_radius_max": "1 mm"}))
    np.testing.assert_allclose(big.frame.f, base.frame.f, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(big.si["force [N]"], 2 * base.si["force [N]"], rtol=1e-12, atol=1e-18)


def test_free_inflation_profile_is_the_spherical_cap():
    p = 0.6
    r, z = profile("making_contact", "no-slip", a=0.0, alpha=0.0, p=p, d=0.0, f=0.0, G=0.0, rs=0.5)
    R = 1 / p  # sphere of radius R through the clamp, centre at z = sqrt(R^2 - 1) above... below
    np.testing.assert_allclose(z, -(np.sqrt(R * R - r * r) - np.sqrt(R * R - 1)), rtol=1e-12, atol=1e-15)
    assert z[0] == pytest.approx(-p / (1 + math.sqrt(1 - p * p)), rel=1e-14)  # eq. 15


@pytest.mark.parametrize("control,slip,kw", [
    ("displacement", "no-slip", dict(p=0.6, rs=0.5)), ("displacement", "frictionless", dict(p=0.6, rs=0.5)),
    ("displacement", "no-slip", dict(p=-0.3, rs=1.0)), ("pressure", "frictionless", dict(d=0.1, rs=math.inf)),
    ("pressure", "no-slip", dict(d=0.3, rs=math.inf, w=3.0, a_max=0.3)),  # reaches theta_a > pi/2
])
def test_profile_meets_the_substrate_at_the_edge_and_the_clamp(control, slip, kw):
    kw = {"w": 0.2, "a_max": 0.25, **kw}
    r_ = adhfit.simulate(control, slip, **kw, points=60)
    fr = r_.frame
    for i in range(1, len(fr), 7):
        x = fr.iloc[i]
        r, z = profile(x.stage, slip, a=x.a, alpha=x.alpha, p=x.p, d=x.d, f=x.f, G=x.G, rs=kw["rs"])
        assert np.all(np.isfinite(z)) and z[-1] == 0.0 and r[-1] == 1.0
        k = int(np.flatnonzero(r == x.a)[0])  # the edge: the free membrane's first point
        c = 0.0 if math.isinf(kw["rs"]) else 1 / kw["rs"]
        sag = x.a**2 * c / (1 + math.sqrt(1 - (x.a * c) ** 2))
        # the free membrane's rise from the edge to the clamp (J1 from the row's reconstructed
        # constants D, C2) must land on the substrate, whose height is the row's own gap d
        assert z[k] == pytest.approx(-x.d - sag, abs=1e-9)
        assert abs(z[k] - z[k - 1]) < 0.05  # and joins the contact region continuously
