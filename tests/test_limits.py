"""Analytical limits and hand-derived identities of the forward model (issue 2).

Every expected value here comes from the paper's equations worked by hand, never from an earlier run
of the engine. Notation as docs/contracts.md A1: lengths over b, kappa = p = b/R, c = 1/rs.

Small-contact expansion used below (derived from eqs. 15, 20, 25 with C2 = 0): with
sin(theta) = kappa r + D/r, D = -(kappa + c) a^2, linearising tan(theta) in D (the neglected terms are
O(a^4 log a)) gives

    delta = d0 - d = (kappa + c) a^2 [ ln(2 / (a (1 + s))) + 1/s - 1/2 ] + O(a^4 log^2 a),
    s = sqrt(1 - kappa^2),

where 1/s - 1 + ln(2/(1 + s)) = int_0^1 [(1 - kappa^2 r^2)^(-3/2) - 1] dr / r in closed form, the
-kappa a^2 / 2 of the missing free cap over [0, a] and the -a^2/(2 rs) of the substrate term supply
the remaining 1/2. Under pressure control d = d_fix is held, so p - p_cr = delta / d0'(p_cr) with
d0'(p) = 1 / (s (1 + s)).
"""
from __future__ import annotations

import math

import mpmath as mp
import numpy as np
import pandas as pd
import pytest

import adhfit
from adhfit.core.inflation import apex_deflection, critical_pressure
from adhfit.loading import state_at

INF = math.inf
BASE_DC = dict(p=0.6, w=0.2, rs=0.5, a_max=0.25)        # paper's base case, displacement control
SLIPS = ("no-slip", "frictionless")


def _curv(rs: float) -> float:
    return 0.0 if math.isinf(rs) else 1.0 / rs


def _small_contact_delta(kappa: float, c: float, a: float) -> float:
    """Leading two terms of delta(a) for a -> 0 (module docstring)."""
    s = math.sqrt(1.0 - kappa * kappa)
    return (kappa + c) * a * a * (math.log(2.0 / (a * (1.0 + s))) + 1.0 / s - 0.5)


# ---------------------------------------------------------------------------------------------
# free inflation, eqs. (15) and (64)
# ---------------------------------------------------------------------------------------------
@pytest.mark.parametrize("p", [1e-8, 0.01, 0.3, 0.6, 0.9, 0.999, 1.0])
def test_apex_deflection_is_eq15_for_positive_pressure(p):
    # eq. (15) as printed, d0 = R - sqrt(R^2 - 1) with R = 1/p, evaluated at 40 digits (it cancels)
    with mp.workdps(40):
        R = 1 / mp.mpf(p)
        want = float(R - mp.sqrt(R * R - 1))
    assert float(apex_deflection(p)) == pytest.approx(want, rel=4e-16, abs=0)


@pytest.mark.parametrize("p", [0.0, 0.2, 0.6, 0.95, 1.0])
def test_apex_deflection_odd_and_finite_at_zero(p):
    # P < 0 inflates the membrane downward: the Case I cap is the mirror image (docs/numerics.md C)
    assert float(apex_deflection(-p)) == -float(apex_deflection(p))
    assert float(apex_deflection(0.0)) == 0.0
    assert abs(float(apex_deflection(p))) <= 1.0


def test_apex_deflection_undefined_beyond_unit_pressure():
    assert np.isnan(apex_deflection(1.0 + 1e-9)) and np.isnan(apex_deflection(-1.5))


def test_eq64_inverts_eq15_over_the_whole_gap_range():
    d = np.concatenate([np.linspace(-1 + 1e-9, 1 - 1e-9, 4001), [-0.5, 0.0, 1e-12, -1e-12]])
    back = apex_deflection(critical_pressure(d))
    # d0 has slope 1/(s (1 + s)) in p, s = sqrt(1 - p^2) = (1 - d^2)/(1 + d^2): the round trip is as
    # good as double precision allows, a few ulps amplified by 1/s near |d| = 1
    s = (1 - d * d) / (1 + d * d)
    assert np.all(np.abs(back - d) <= 4e-16 * (1 + 1 / s))
    inner = np.abs(d) <= 0.9
    assert np.max(np.abs(back - d)[inner]) <= 2e-15
    p = np.linspace(-1, 1, 2001)
    assert np.max(np.abs(critical_pressure(apex_deflection(p)) - p)) <= 4e-15
    # eq. (64) itself: the pressure whose free cap reaches gap d, p = 2d/(1+d^2), at 30 digits
    for x in (-0.9, -0.2, 0.1, 0.3, 0.77):
        with mp.workdps(30):
            want = float(2 * mp.mpf(x) / (1 + mp.mpf(x) ** 2))
        assert float(critical_pressure(x)) == pytest.approx(want, rel=2e-16)


# ---------------------------------------------------------------------------------------------
# a -> 0: making contact recovers free inflation, at the rate a^2 log a
# ---------------------------------------------------------------------------------------------
SMALL_DC = [(0.6, 0.5), (0.6, INF), (-0.3, 0.5), (0.0, 2.0), (0.95, INF), (-0.9, 0.5)]


@pytest.mark.parametrize("slip", SLIPS)
@pytest.mark.parametrize("p,rs", SMALL_DC)
def test_making_contact_tends_to_free_inflation_displacement(p, rs, slip):
    c, d0 = _curv(rs), float(apex_deflection(p))
    errs = {}
    for a in (1e-2, 1e-3, 1e-4):
        s = state_at("displacement", slip, "making_contact", p=p, w=0.2, rs=rs, a_max=0.25, a=a)
        assert s["p"] == p and s["alpha"] == 0.0 and s["G"] == 0.0
        assert s["d"] == pytest.approx(d0 - s["delta"], abs=1e-15)
        # eq. (26) in groups: f = pi (p + 1/rs) a^2
        assert s["f"] == pytest.approx(math.pi * (p + c) * a * a, rel=1e-13)
        # leading rate: delta / (a^2 ln(1/a)) -> p + 1/rs; the full two-term expansion to O(a^2)
        errs[a] = abs(s["delta"] - _small_contact_delta(p, c, a)) / (a * a)
    # the remainder is O(a^2 log^2 a) relative to a^2: a wrong log coefficient would leave O(1) here
    assert errs[1e-3] < 2e-3 and errs[1e-4] < 5e-5, errs
    assert errs[1e-4] < errs[1e-2]


@pytest.mark.parametrize("d,rs", [(0.2, INF), (0.0, 0.5), (-0.2, 0.5), (0.6, 2.0)])
def test_making_contact_tends_to_critical_pressure_pressure_control(d, rs):
    c, p_cr = _curv(rs), float(critical_pressure(d))
    s_cr = math.sqrt(1 - p_cr * p_cr)
    errs = {}
    for a in (1e-2, 1e-3, 1e-4):
        s = state_at("pressure", "no-slip", "making_contact", d=d, w=0.2, rs=rs, a_max=0.25, a=a)
        assert s["d"] == d and s["G"] == 0.0
        assert s["f"] == pytest.approx(math.pi * (s["p"] + c) * a * a, rel=1e-13)
        want = _small_contact_delta(p_cr, c, a) * s_cr * (1 + s_cr)
        errs[a] = abs(s["p"] - p_cr - want) / (a * a)
        assert s["p"] > p_cr
    assert errs[1e-3] < 2e-3 and errs[1e-4] < 5e-5, errs


# ---------------------------------------------------------------------------------------------
# start of pinning = end of making contact (paper after eq. 50)
# ---------------------------------------------------------------------------------------------
PIN_START = [("displacement", dict(p=0.6, rs=0.5)), ("displacement", dict(p=0.6, rs=INF)),
             ("pressure", dict(d=0.0, rs=0.5)), ("pressure", dict(d=0.2, rs=INF)),
             ("displacement", dict(p=-0.3, rs=0.5))]


@pytest.mark.parametrize("slip", SLIPS)
@pytest.mark.parametrize("control,kw", PIN_START)
def test_pinning_at_zero_angle_is_end_of_making_contact(control, kw, slip):
    kw = dict(w=0.2, a_max=0.25, **kw)
    mc = state_at(control, slip, "making_contact", a=0.25, **kw)
    pin = state_at(control, slip, "pinning", alpha=0.0, **kw)
    assert pin["G"] == pytest.approx(0.0, abs=1e-13)
    assert pin["alpha"] == 0.0
    for k in ("a", "d", "f", "p"):
        assert pin[k] == pytest.approx(mc[k], abs=1e-11), k
    # and the loading end itself is eq. (26) at a_max
    assert mc["f"] == pytest.approx(math.pi * (mc["p"] + _curv(kw["rs"])) * 0.0625, rel=1e-13)


# ---------------------------------------------------------------------------------------------
# energy release rate and force identities along pinning and delamination
# ---------------------------------------------------------------------------------------------
IDENTITY_CASES = [("displacement", dict(p=0.6, rs=0.5)), ("displacement", dict(p=0.6, rs=INF)),
                  ("pressure", dict(d=0.0, rs=0.5)), ("pressure", dict(d=0.2, rs=INF)),
                  ("displacement", dict(p=-0.3, rs=0.5)),
                  ("pressure", dict(d=0.3, rs=INF, w=3.0, a_max=0.3))]   # reaches theta_a > pi/2


def _run(control, slip, kw):
    return adhfit.simulate(control, slip, **{"w": 0.2, "a_max": 0.25, **kw})


@pytest.mark.parametrize("control,kw", IDENTITY_CASES)
def test_frictionless_release_rate_and_force(control, kw):
    r = _run(control, "frictionless", kw)
    c, w = _curv(kw["rs"]), r.inputs["w"]
    pin = r.frame[r.frame.stage == "pinning"]
    a, al, p, f, G = (pin[k].to_numpy() for k in ("a", "alpha", "p", "f", "G"))
    assert np.all(al < math.pi / 2)                       # eq. (54)
    np.testing.assert_allclose(G, np.tan(al) ** 2 / 2, rtol=1e-12, atol=1e-14)      # eq. (60)
    t = 1.0 / np.cos(al)                                  # T1+/mu h = lambda1+/lambda2, eq. (54)
    np.testing.assert_allclose(G, t * (1 - np.cos(al)) + 0.5 * (t - 1) ** 2, rtol=1e-12, atol=1e-14)
    # eq. (59): f = pi [ (p + 1/rs) a^2 - a sqrt(1 - a^2/rs^2) tan(alpha) ]
    f59 = math.pi * ((p + c) * a * a - a * np.sqrt(1 - (a * c) ** 2) * np.tan(al))
    np.testing.assert_allclose(f, f59, rtol=1e-11, atol=1e-13)
    dl = r.frame[r.frame.stage == "delamination"]
    # eq. (63): constant contact angle, G = w
    np.testing.assert_allclose(dl.alpha, math.atan(math.sqrt(2 * w)), rtol=1e-13)
    np.testing.assert_allclose(dl.G, w, rtol=1e-13)
    f59 = math.pi * ((dl.p + c) * dl.a ** 2 - dl.a * np.sqrt(1 - (dl.a * c) ** 2) * np.tan(dl.alpha))
    np.testing.assert_allclose(dl.f, f59, rtol=1e-11, atol=1e-13)


@pytest.mark.parametrize("control,kw", IDENTITY_CASES)
def test_no_slip_release_rate_eq52(control, kw):
    """G from eq. (52) with sqrt(1 + C2/a^2) recovered from the solved force through eq. (49):
    f = pi a^2 p - pi a t sin(theta_a), theta_a = alpha - asin(a/rs) (eq. 22)."""
    r = _run(control, "no-slip", kw)
    c, w = _curv(kw["rs"]), r.inputs["w"]
    for stage in ("pinning", "delamination"):
        g = r.frame[r.frame.stage == stage]
        a, al, p, f, G = (g[k].to_numpy() for k in ("a", "alpha", "p", "f", "G"))
        th = al - np.arcsin(a * c)
        ok = np.abs(np.sin(th)) > 1e-3                    # eq. (49) cannot give t where sin = 0
        assert ok.sum() >= 0.8 * ok.size
        t = (math.pi * a * a * p - f)[ok] / (math.pi * a * np.sin(th))[ok]
        assert np.all(t > 0)                              # T1+ > 0 (eq. 10)
        G52 = t * (1 - np.cos(al[ok])) + 0.5 * (t - 1) ** 2
        np.testing.assert_allclose(G[ok], G52, rtol=1e-9, atol=1e-12)
        if stage == "pinning":
            np.testing.assert_allclose(a, r.inputs["a_max"], rtol=0, atol=0)   # a = a_m, no slip
            assert np.all(np.diff(G) > 0) and G[-1] == pytest.approx(w, rel=1e-12)
        else:
            np.testing.assert_allclose(G, w, rtol=1e-12)                        # eq. (62)


# ---------------------------------------------------------------------------------------------
# flat substrate as the limit rs -> inf, and lambda0 cancelling
# ---------------------------------------------------------------------------------------------
def _summary_vector(s: dict) -> np.ndarray:
    return np.array([s["f_max"]] + [s[k][q] for k in ("onset", "f_min", "turning_point")
                                    for q in ("f", "delta", "p", "a")], float)


@pytest.mark.parametrize("slip", SLIPS)
@pytest.mark.parametrize("control,kw", [("displacement", dict(p=0.6)), ("pressure", dict(d=0.2))])
def test_large_substrate_radius_converges_to_flat_at_rate_one_over_rs(control, kw, slip):
    flat = _summary_vector(_run(control, slip, {**kw, "rs": INF}).summary)
    err = {rs: np.max(np.abs(_summary_vector(_run(control, slip, {**kw, "rs": rs}).summary) - flat))
           for rs in (1e3, 1e4, 1e5)}
    # O(1/rs): each decade of rs takes a decade off the error
    assert 8.0 < err[1e3] / err[1e4] < 12.0 and 8.0 < err[1e4] / err[1e5] < 12.0, err
    assert err[1e5] * 1e5 == pytest.approx(err[1e3] * 1e3, rel=0.05)
    # and states at fixed locators (end of loading, a delamination radius) converge the same way
    base = {**kw, "w": 0.2, "a_max": 0.25}
    s_inf = state_at(control, slip, "delamination", rs=INF, a=0.1, **base)
    e = [abs(state_at(control, slip, "delamination", rs=rs, a=0.1, **base)["f"] - s_inf["f"])
         for rs in (1e3, 1e4)]
    assert 8.0 < e[0] / e[1] < 12.0


@pytest.mark.parametrize("slip", SLIPS)
@pytest.mark.parametrize("control,kw", [("displacement", dict(p=0.6, rs=0.5)), ("pressure", dict(d=0.2, rs=INF))])
def test_prestretch_leaves_every_observable_unchanged(control, kw, slip):
    frames = {l0: adhfit.simulate(control, slip, w=0.2, a_max=0.25, lambda0=l0, **kw) for l0 in (1.2, 2.0, 5.0)}
    ref = frames[2.0]
    for l0 in (1.2, 5.0):
        pd.testing.assert_frame_equal(frames[l0].frame, ref.frame, rtol=1e-13, atol=1e-15)
        np.testing.assert_allclose(_summary_vector(frames[l0].summary), _summary_vector(ref.summary),
                                   rtol=1e-13, atol=1e-15)


# ---------------------------------------------------------------------------------------------
# making contact force (eq. 26) from the frame's own columns, and the loading end round trips
# ---------------------------------------------------------------------------------------------
@pytest.mark.parametrize("slip", SLIPS)
@pytest.mark.parametrize("control,kw", PIN_START)
def test_making_contact_force_eq26(control, kw, slip):
    r = adhfit.simulate(control, slip, w=0.2, a_max=0.25, **kw)
    mc = r.frame[r.frame.stage == "making_contact"]
    c = _curv(kw["rs"])
    np.testing.assert_allclose(mc.f, math.pi * (mc.p + c) * mc.a ** 2, rtol=1e-13, atol=1e-16)
    assert (mc.G == 0).all() and (mc.alpha == 0).all()
    assert mc.a.iloc[0] == 0.0 and mc.a.iloc[-1] == 0.25
    assert r.summary["f_max"] == pytest.approx(math.pi * (mc.p.iloc[-1] + c) * 0.0625, rel=1e-13)
    if control == "pressure":
        # the first row is free inflation at the critical pressure, eq. (64)
        assert mc.p.iloc[0] == pytest.approx(float(critical_pressure(kw["d"])), abs=1e-15)
        assert (mc.d == kw["d"]).all()
    else:
        assert mc.d.iloc[0] == pytest.approx(float(apex_deflection(kw["p"])), abs=1e-15)
        assert (mc.p == kw["p"]).all()


def test_pull_off_frictionless_slightly_smaller_than_no_slip_at_paper_base_case():
    # the paper's remark (section 5.1), true at its base case only; not a law (docs/numerics.md C)
    ns = adhfit.simulate("displacement", "no-slip", **BASE_DC).summary["f_min"]["f"]
    fr = adhfit.simulate("displacement", "frictionless", **BASE_DC).summary["f_min"]["f"]
    assert ns < fr < 0
    assert abs(fr - ns) < 0.1 * abs(ns)


@pytest.mark.parametrize("slip", SLIPS)
@pytest.mark.parametrize("rs", [0.5, INF])
@pytest.mark.parametrize("delta_max", [0.02, 0.1, 0.2])
def test_delta_max_round_trips(delta_max, rs, slip):
    r = adhfit.simulate("displacement", slip, p=0.6, w=0.2, rs=rs, delta_max=delta_max)
    mc = r.frame[r.frame.stage == "making_contact"]
    assert mc.delta.iloc[-1] == pytest.approx(delta_max, abs=1e-10)
    assert mc.delta.max() == pytest.approx(delta_max, abs=1e-10)
    assert mc.a.iloc[-1] == pytest.approx(r.inputs["a_max"], abs=0)


@pytest.mark.parametrize("slip", SLIPS)
@pytest.mark.parametrize("d,rs,p_max", [(0.2, 0.5, 0.7), (0.2, INF, 0.9), (0.0, 0.5, 0.5), (-0.2, 0.5, 0.3),
                                        (0.2, 0.5, 1.0), (0.2, 0.5, 1.05)])
def test_p_max_round_trips(d, rs, p_max, slip):
    r = adhfit.simulate("pressure", slip, d=d, w=0.2, rs=rs, p_max=p_max)
    mc = r.frame[r.frame.stage == "making_contact"]
    assert mc.p.iloc[-1] == pytest.approx(p_max, abs=1e-10)
    assert mc.p.max() == pytest.approx(p_max, abs=1e-10)


def test_p_max_above_one_round_trips():
    r = adhfit.simulate("pressure", "no-slip", d=0.2, w=0.2, rs=0.5, p_max=1.3)
    mc = r.frame[r.frame.stage == "making_contact"]
    assert mc.p.iloc[-1] == pytest.approx(1.3, abs=1e-10)
