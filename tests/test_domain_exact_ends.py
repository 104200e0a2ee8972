"""The exact membrane's pinning and delamination ends (issue 24, item 1: the exact ConvergenceErrors).

Each scene is one of the exact-membrane ConvergenceErrors of the stress run
(``python benchmarks/stress_domain.py --membrane exact --n 1000 --seed 24``, commit 6e5e5d3). The
engine's answer is checked against an independent computation: a pseudo-arclength continuation of
the pinning branch written here (single shots through ``adhfit.exact.state.evaluate``, its own Newton
and finite differences, the branch parameterized by its arclength in (unknown, alpha), so neither a
fold in alpha nor one in the control stops it), or analytic facts (the flat contact field's tension
1 - lc^-6, the sphere's equator a = rs).
"""
from __future__ import annotations

import math

import numpy as np
import pytest

import adhfit
from adhfit.errors import DomainError
from adhfit.exact import history as H
from adhfit.exact.control import prepare
from adhfit.exact.stages import delamination
from adhfit.exact.state import Config, evaluate


def _setup(sc):
    sc = dict(sc)
    c = prepare(sc["control"], sc["slip"], sc.get("p"), sc.get("d"), sc["w"], sc["rs"], sc["lambda0"],
                sc.get("a_max"), sc.get("delta_max"), sc.get("p_max"), 200, 8)
    cfg = Config(c.lambda0, c.crv, c.n)
    _, m = H._loading(cfg, c)
    return c, cfg, m


def _shot(c, cfg, m, y):
    p = y[1] if c.control == "pressure" else c.p
    if c.slip == "frictionless":
        return evaluate(cfg, p, y[0], m.rho_a, y[-1], "frictionless")
    return evaluate(cfg, p, m.lc, m.rho_a, y[-1], "given", y[0])


def _res(c, cfg, m, y):
    st = _shot(c, cfg, m, y)
    r = [st.r_end - 1.0] + ([st.d - c.d] if c.control == "pressure" else [])
    return np.array(r), st


def arclength_pinning(sc, ds=0.02, steps=800):
    """The pinning branch from the end of loading by pseudo-arclength continuation in (unknowns, alpha):
    the states in order until G >= w, the clamp passes vertical (|theta_end| >= pi/2) or the steps
    shrink below 1e-7 (the branch ends)."""
    c, cfg, m = _setup(sc)
    y = np.array([m.lc if c.slip == "frictionless" else m.l1p] + ([m.p] if c.control == "pressure" else [])
                 + [0.0])
    k = len(y)

    def jac(z):
        r0 = _res(c, cfg, m, z)[0]
        J = np.empty((k - 1, k))
        for j in range(k):
            e = 1e-7 * max(1.0, abs(z[j]))
            zz = z.copy()
            zz[j] += e
            J[:, j] = (_res(c, cfg, m, zz)[0] - r0) / e
        return J

    t = np.zeros(k)
    t[-1] = 1.0
    out = []
    for _ in range(steps):
        tn = np.linalg.solve(np.vstack([jac(y), t]), np.eye(k)[-1])
        tn /= np.linalg.norm(tn)
        t = tn if tn @ t >= 0 else -tn
        z, ok = y + ds * t, False
        for _ in range(30):
            r, st = _res(c, cfg, m, z)
            F = np.append(r, (z - y) @ t - ds)
            if not np.all(np.isfinite(F)):
                break
            if np.max(np.abs(F)) < 1e-11:
                ok = True
                break
            z = z - np.linalg.solve(np.vstack([jac(z), t]), F)
        if not ok:
            ds *= 0.5
            if ds < 1e-7:
                break
            continue
        y = z
        out.append(st)
        if st.G >= c.w or not abs(st.theta_end) < 0.5 * math.pi:
            break
    return c, out


# exact pinning, frictionless, displacement control: alpha rises to a maximum (1.0786) and falls again
# while d rises and the clamp turns vertical; G peaks at 1.736 < w = 4.68 (the alpha march stalled at the fold)
FOLD_CASE_ONE = dict(control="displacement", slip="frictionless", p=0.9161753898026146, w=4.6848392043432465,
                     rs=6.910859597835364, delta_max=0.0041090682763668335, lambda0=1.347594062869533)


def test_pinning_past_a_fold_in_alpha_reaches_the_case_one_limit():
    with pytest.raises(DomainError) as err:
        adhfit.simulate(**FOLD_CASE_ONE, points=200, membrane="exact")
    msg = str(err.value)
    assert "turns past vertical at the clamp" in msg and "did not converge" not in msg
    d_end = float(msg.split(" at d = ")[1].split()[0])
    c, path = arclength_pinning(FOLD_CASE_ONE)
    alphas = np.array([s.alpha for s in path])
    # the independent branch: alpha folds, G stays below w, the clamp passes vertical where the engine says
    assert alphas.max() > alphas[-1] + 1e-4
    assert max(s.G for s in path) < c.w
    assert abs(path[-1].theta_end) >= 0.5 * math.pi
    assert abs(path[-1].d - d_end) < 0.02 and path[-2].d <= d_end + 1e-9


# exact pinning, no slip, displacement control: alpha folds at 0.8604 and G reaches w = 7.49 after the
# fold, at alpha = 0.8593 (the alpha march reported "G does not reach w")
FOLD_ONSET = dict(control="displacement", slip="no-slip", p=0.6808655522401987, w=7.487855680028116,
                  rs=math.inf, a_max=0.16642016711715485, lambda0=1.3412575959968316)


def test_pinning_onset_after_a_fold_in_alpha_is_found():
    h = H.exact_history(**FOLD_ONSET, points=200)
    stage, alpha, G = h.columns["stage"], h.columns["alpha"], h.columns["G"]
    i_on = int(np.flatnonzero(stage == "pinning")[-1])
    assert G[i_on] == pytest.approx(FOLD_ONSET["w"], abs=1e-9)
    assert alpha[stage == "pinning"].max() > alpha[i_on] + 1e-4  # the onset lies past the fold in alpha
    # the onset row is a state of the equations: shot again from its own unknowns (no Newton)
    c, cfg, m = _setup(FOLD_ONSET)
    st = h.states[i_on]
    again = evaluate(cfg, c.p, m.lc, m.rho_a, st.alpha, "given", st.l1p)
    assert again.r_end == pytest.approx(1.0, abs=1e-9) and again.G == pytest.approx(c.w, abs=1e-8)
    # the independent branch reaches G = w at the same contact angle
    c, path = arclength_pinning(FOLD_ONSET, ds=0.01)
    assert path[-1].G >= c.w
    i = len(path) - 1
    t = (c.w - path[i - 1].G) / (path[i].G - path[i - 1].G)
    assert path[i - 1].alpha + t * (path[i].alpha - path[i - 1].alpha) == pytest.approx(alpha[i_on], abs=1e-5)
    assert np.all(np.isfinite(h.columns["f"])) and np.all(np.isfinite(h.columns["delta"]))
    r = adhfit.simulate(**FOLD_ONSET, points=200, membrane="exact")  # and through the public call
    assert r.summary["onset"]["f"] == pytest.approx(h.summary["onset"]["f"], abs=1e-12)


# frictionless pinning on a flat substrate, pressure control: T1- = T1+ cos(alpha) -> 0 as alpha -> pi/2,
# the contact region going slack (lc -> 1: its tension is 1 - lc^-6); G(pi/2) = 6.645 < w = 9.05
SLACK_FLAT = dict(control="pressure", slip="frictionless", d=0.6859752434431015, w=9.048534937628242,
                  rs=math.inf, a_max=0.32952469215055524, lambda0=1.1150509606246646)


def test_frictionless_pinning_going_slack_is_a_domain_error():
    with pytest.raises(DomainError) as err:
        adhfit.simulate(**SLACK_FLAT, points=200, membrane="exact")
    msg = str(err.value)
    assert "going slack" in msg and "alpha -> pi/2" in msg
    c, path = arclength_pinning(SLACK_FLAT)
    last = path[-1]
    # the independent branch ends at alpha = pi/2 with the contact region's tension 1 - lc^-6 -> 0
    assert 0.5 * math.pi - last.alpha < 1e-3 and 1.0 - last.lc ** -6 < 1e-2
    assert max(s.G for s in path) < c.w
    g_end = float(msg.split("G = ")[-1].split()[0])
    assert g_end == pytest.approx(last.G, abs=2e-2)


# frictionless pinning on a small sphere (rs = 0.496): the contact field grows with lc until the contact edge
# reaches the sphere's equator, a = rs, where the branch ends (G = 0.044 < w = 0.45)
EQUATOR = dict(control="displacement", slip="frictionless", p=-0.14495288731550682, w=0.4513969744342152,
               rs=0.4957602082298765, a_max=0.4311997675345813, lambda0=1.8833558792258702)


def test_pinning_to_the_sphere_equator_is_a_domain_error():
    with pytest.raises(DomainError) as err:
        adhfit.simulate(**EQUATOR, points=200, membrane="exact")
    msg = str(err.value)
    assert "equator" in msg
    a_end = float(msg.split(", a = ")[1].split(")")[0])
    assert a_end == pytest.approx(EQUATOR["rs"], rel=1e-4)  # analytic: the equator is a = rs
    c, path = arclength_pinning(EQUATOR)
    # the independent branch runs into the equator (its last states, integrated past r = rs, are not
    # states of the model) with G below w all the way
    assert path[-1].a >= EQUATOR["rs"] * (1.0 - 1e-4) and max(s.G for s in path) < c.w


# frictionless delamination, displacement control: the clamp turns vertical at a = 0.714 before detachment
DELAM_CASE_ONE = dict(control="displacement", slip="frictionless", p=0.5590715649008304, w=9.455023661906516,
                      rs=5.528668402941251, a_max=0.7703213535905024, lambda0=2.097449099766094)


def test_delamination_case_one_limit_is_bisected():
    with pytest.raises(DomainError) as err:
        adhfit.simulate(**DELAM_CASE_ONE, points=200, membrane="exact")
    msg = str(err.value)
    assert "delamination branch (frictionless) turns past vertical" in msg
    a_end = float(msg.split(" at a = ")[1].split()[0])
    # independent: a march on a grid of 4000 rows from the onset, stopping where the clamp passes vertical
    c, cfg, m = _setup(DELAM_CASE_ONE)
    pin, on = H._pinning(cfg, c, m)
    stage = delamination(cfg, c.control, c.slip, m, c.w, c.p, c.d)
    sts = H.march(stage, on.rho_a * np.linspace(1.0, 0.0, 4001)[1:], stage.x(on), stop_ok=True)
    assert len(sts) < 4000
    assert sts[-1].a == pytest.approx(a_end, abs=2e-4) and 0.5 * math.pi - sts[-1].theta_end < 1e-3


# pressure control, no slip, d = 0.084: pinning reaches theta_end = -pi/2 at the clamp (the membrane drawn
# down past vertical); before, only theta_end > pi/2 was refused and this scene returned a Case II history
DOWN_PAST_VERTICAL = dict(control="pressure", slip="no-slip", d=0.08415974253425151, w=6.795920185054049,
                          rs=23.70969674873911, a_max=0.18355857206873044, lambda0=2.3567156349519522)


def test_clamp_past_vertical_downwards_is_outside_case_one():
    with pytest.raises(DomainError) as err:
        adhfit.simulate(**DOWN_PAST_VERTICAL, points=200, membrane="exact")
    assert "turns past vertical at the clamp" in str(err.value)
    c, path = arclength_pinning(DOWN_PAST_VERTICAL)
    # the independent branch passes theta_end = -pi/2 (downwards) before G reaches w
    assert path[-1].theta_end <= -0.5 * math.pi and path[-1].G < c.w
