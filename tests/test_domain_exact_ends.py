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
from adhfit.errors import ConvergenceError, DomainError
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


def arclength_pinning(sc, ds=0.02, steps=800, y0=None):
    """The pinning branch from the end of loading (or from the unknowns ``y0``, alpha last) by
    pseudo-arclength continuation in (unknowns, alpha): the states in order until G >= w, the clamp
    passes vertical (|theta_end| >= pi/2) or the steps shrink below 1e-7 (the branch ends)."""
    c, cfg, m = _setup(sc)
    y = np.array([m.lc if c.slip == "frictionless" else m.l1p] + ([m.p] if c.control == "pressure" else [])
                 + [0.0]) if y0 is None else np.asarray(y0, dtype=float)
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


# frictionless pinning on a small sphere (rs = 0.496): two branches leave the end of loading with alpha > 0
# (alpha ~ (d - d_m)^2 there), one retracting (d rising) and one pressing on to the sphere's equator
# (a = rs, G = 0.044 < w); the alpha march took the second and reported "no solution". The history is
# the retracting one.
EQUATOR = dict(control="displacement", slip="frictionless", p=-0.14495288731550682, w=0.4513969744342152,
               rs=0.4957602082298765, a_max=0.4311997675345813, lambda0=1.8833558792258702)


def test_pinning_follows_the_branch_that_retracts():
    r = adhfit.simulate(**EQUATOR, points=200, membrane="exact")
    f = r.frame
    pin = f[f.stage == "pinning"]
    d_m = f[f.stage == "making_contact"].d.iloc[-1]
    assert pin.d.iloc[0] > d_m and np.all(np.diff(pin.d.to_numpy()) > 0)  # retracting all the way
    assert pin.G.iloc[-1] == pytest.approx(EQUATOR["w"], abs=1e-9)
    # independent: a retracted state (d = d_m + 0.01) by Newton from the end of loading, then the arclength
    # continuation from it, oriented by its first step, reaches G = w at the same alpha
    c, cfg, m = _setup(EQUATOR)
    y = np.array([m.lc, 1e-3])
    for _ in range(40):
        def res(z):
            st = evaluate(cfg, c.p, z[0], m.rho_a, z[1], "frictionless")
            return np.array([st.r_end - 1.0, st.d - (m.d + 0.01)])
        r0 = res(y)
        J = np.column_stack([(res(y + e) - r0) / e.sum() for e in np.diag([1e-7 * y[0], 1e-9])])
        y = y - np.linalg.solve(J, r0)
        if np.max(np.abs(r0)) < 1e-12:
            break
    assert 0.0 < y[1] < 1e-3  # alpha ~ (d - d_m)^2 near the end of loading
    _, path = arclength_pinning(EQUATOR, ds=0.01, y0=y)
    assert path[0].d > m.d + 0.01 and path[-1].G >= c.w  # it went on retracting and reached the onset
    i = len(path) - 1
    t = (c.w - path[i - 1].G) / (path[i].G - path[i - 1].G)
    assert path[i - 1].alpha + t * (path[i].alpha - path[i - 1].alpha) == pytest.approx(
        float(pin.alpha.iloc[-1]), abs=1e-5)


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


# no-slip pinning at p = 0.98: the clamp tangent reaches pi/2 at alpha = 1.1678 (G = 1.47 < w = 5.58); the
# alpha bracket's long steps passed over that stretch of the branch onto another one and its onset solve
# failed ("exact pinning: onset G = w did not converge")
JUMP = dict(control="displacement", slip="no-slip", p=0.9842074671895105, w=5.576721599580395,
            rs=0.1363600075001485, a_max=0.11170492038040732, lambda0=2.359117113435467)


def test_pinning_bracket_does_not_step_over_the_case_one_limit():
    with pytest.raises(DomainError) as err:
        adhfit.simulate(**JUMP, points=200, membrane="exact")
    msg = str(err.value)
    assert "turns past vertical at the clamp" in msg
    alpha_end = float(msg.split("at alpha = ")[1].split(",")[0])
    c, path = arclength_pinning(JUMP, ds=0.005)
    assert path[-1].theta_end >= 0.5 * math.pi and max(s.G for s in path) < c.w
    assert path[-1].d > path[0].d  # the branch retracts (d rises): it is the history's
    assert alpha_end == pytest.approx(path[-1].alpha, abs=2e-3)
    assert path[-2].alpha <= alpha_end + 1e-9


def arclength_making_contact(sc, ds=0.01, steps=3000):
    """Making contact by pseudo-arclength continuation of r(clamp) = 1 in (lc, rho_a) (displacement
    control): the states in order until the clamp passes vertical or the steps shrink below 1e-8."""
    c, cfg, _ = _setup(dict(sc, a_max=0.02 * sc["a_max"]))
    start = H._loading(cfg, c)[1]
    y = np.array([start.lc, start.rho_a])

    def res(z):
        st = evaluate(cfg, c.p, z[0], z[1], 0.0, "continuous")
        return np.array([st.r_end - 1.0]), st

    def jac(z):
        r0 = res(z)[0]
        return np.array([[(res(z + e)[0][0] - r0[0]) / e[j] for j, e in
                          enumerate(np.diag([1e-7 * max(1.0, abs(q)) for q in z]))]])
    t = np.array([0.0, 1.0])
    out = []
    for _ in range(steps):
        tn = np.linalg.solve(np.vstack([jac(y), t]), np.eye(2)[-1])
        tn /= np.linalg.norm(tn)
        t = tn if tn @ t >= 0 else -tn
        z, ok = y + ds * t, False
        for _ in range(30):
            r, st = res(z)
            F = np.append(r, (z - y) @ t - ds)
            if not np.all(np.isfinite(F)):
                break
            if np.max(np.abs(F)) < 1e-12:
                ok = True
                break
            z = z - np.linalg.solve(np.vstack([jac(z), t]), F)
        if not ok:
            ds *= 0.5
            if ds < 1e-8:
                break
            continue
        y = z
        out.append(st)
        if not abs(st.theta_end) < 0.5 * math.pi:
            break
    return c, out


# making contact at p = -0.92: the contact radius stalls at 0.404084 as the clamp tangent meets -pi/2
# tangentially; the march in a reported "Newton line search did not converge"
STALL = dict(control="displacement", slip="no-slip", p=-0.9209532193877663, w=6.718050633006767,
             rs=0.712172686849101, a_max=0.559048196633177, lambda0=2.7340736285041256)


def test_making_contact_stalling_at_the_case_one_limit_is_a_domain_error():
    with pytest.raises(DomainError) as err:
        adhfit.simulate(**STALL, points=200, membrane="exact")
    msg = str(err.value)
    assert "while making contact" in msg
    bound = float(msg.split("a_max must stay below ")[1].split()[0])
    c, path = arclength_making_contact(STALL)
    # the independent branch passes vertical at the clamp; the largest contact radius before it is the bound
    assert path[-1].theta_end <= -0.5 * math.pi
    a_top = max(s.a for s in path[:-1])  # its last Case I state lies up to one arclength step before the end
    assert a_top <= bound + 1e-6 and bound - a_top < 1e-5


# frictionless pinning on a small sphere (rs = 0.2798): no pinning state retracts the control from the end of
# loading; the branch presses on (d falls: the end of loading is the turning point, docs/contracts.md A2)
# and meets G = w = 0.027 only with the contact edge at the sphere's equator; delamination then found "no
# quasi-static branch from the onset"
EQUATOR_ONSET = dict(control="displacement", slip="frictionless", p=0.3185165589164103, w=0.027253888747996682,
                     rs=0.2797871848551301, delta_max=0.6507329121955819, lambda0=1.5066331781755788)


def test_onset_at_the_sphere_equator_is_a_domain_error():
    with pytest.raises(DomainError) as err:
        adhfit.simulate(**EQUATOR_ONSET, points=200, membrane="exact")
    assert "equator" in str(err.value)
    c, path = arclength_pinning(EQUATOR_ONSET, ds=0.005)
    _, _, m = _setup(EQUATOR_ONSET)
    first = next(i for i, s in enumerate(path) if s.a * c.crv >= 1.0 - 1e-6)
    assert max(s.G for s in path[:first]) < c.w and path[first].d < m.d  # below w short of the equator
