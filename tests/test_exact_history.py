"""Exact membrane histories: contact-edge states against the independent reference, the A2 contract,
convergence to the large-stretch engine as lambda0 grows, and energy balances."""
from __future__ import annotations

import math

import numpy as np
import pytest

from adhfit import simulate
from adhfit.exact.history import exact_history
from adhfit.exact.stages import delamination, making_contact, pinning
from adhfit.exact.state import DEFAULT_N, Config
from tests import exact_reference as ref

BASE = dict(p=0.6, w=0.2, rs=0.5, a_max=0.25)
# The default n is checked against the independent reference at issue 11's 1e-6 with the 10x margin it
# was chosen for (benchmarks/results/exact_n.md); TIGHT_N steps at 1e-8 (convergence to the reference).
ISSUE_TOL, TIGHT_N, TIGHT_TOL = 1e-7, 14, 1e-8
STEPS = sorted({DEFAULT_N, TIGHT_N})


def _tol(n):
    return TIGHT_TOL if n >= TIGHT_N else ISSUE_TOL


@pytest.fixture(scope="module", params=[(s, n) for s in ("frictionless", "no-slip") for n in STEPS],
                ids=lambda q: f"{q[0]}-n{q[1]}")
def hist(request):
    slip, n = request.param
    return slip, n, exact_history("displacement", slip, lambda0=1.2, points=40, n=n, **BASE)


def test_columns_and_flags(hist):
    slip, _, h = hist
    c = h.columns
    assert list(c["stage"][:1]) == ["making_contact"] and c["stage"][-1] == "delamination"
    for k in ("a", "alpha", "d", "delta", "f", "G"):
        assert np.all(np.isfinite(c[k])), k
    turn = h.summary["turning_point"]
    i = int(np.argmin(c["delta"]))
    assert c["delta"][i] == pytest.approx(turn["delta"], abs=1e-12)
    assert c["stable"][: i + 1].all() and not c["stable"][i + 1:].any()
    assert c["a"][-1] <= 1e-3 * BASE["a_max"]
    dl = c["stage"] == "delamination"
    assert np.allclose(c["G"][dl], BASE["w"], atol=1e-10)


def test_states_against_reference(hist):
    """Every stage's states, re-shot by the independent solver from the same edge data."""
    slip, n, h = hist
    m = [s for s, st in zip(h.states, h.columns["stage"]) if st == "making_contact"][-1]
    picks = [i for i in (len(h.states) // 3, len(h.states) // 2, -3)]
    for i in picks:
        s = h.states[i]
        edge = "frictionless" if slip == "frictionless" else "given"
        lc = s.lc if slip == "frictionless" else m.lc
        r_end, d, f, G = ref.edge_state(0.6, 1.2, 0.5, lc, s.rho_a, s.alpha, edge, s.l1p)
        assert r_end == pytest.approx(1.0, abs=_tol(n))
        assert (d, f, G) == pytest.approx((s.d, s.f, s.G), abs=_tol(n))


@pytest.mark.parametrize("slip", ["frictionless", "no-slip"])
def test_converges_to_large_stretch(slip):
    ls = simulate("displacement", slip, **BASE).summary
    errs = []
    for lam0 in (5.0, 10.0):
        ex = exact_history("displacement", slip, lambda0=lam0, points=30, **BASE).summary
        errs.append(max(abs(ex["f_max"] - ls["f_max"]), abs(ex["f_min"]["f"] - ls["f_min"]["f"]),
                        abs(ex["onset"]["delta"] - ls["onset"]["delta"]),
                        abs(ex["turning_point"]["delta"] - ls["turning_point"]["delta"])))
    assert errs[1] < 1e-6 and errs[1] < errs[0] / 20


@pytest.mark.parametrize("control, slip, kw", [
    ("displacement", "no-slip", dict(p=0.2, rs=math.inf)),  # turning point and f_min at the onset
    ("displacement", "frictionless", dict(p=0.2, rs=math.inf)),
    ("pressure", "frictionless", dict(d=-0.05, rs=0.5)),
    ("pressure", "no-slip", dict(d=0.2, rs=0.5)),
])
def test_large_lambda0_matches_large_stretch(control, slip, kw):
    ls = simulate(control, slip, w=0.2, a_max=0.25, **kw).summary
    ex = exact_history(control, slip, w=0.2, a_max=0.25, lambda0=10.0, points=40, **kw).summary
    for key in ("onset", "f_min", "turning_point"):
        for q in ("f", "delta", "p", "a"):
            # the neglected terms are O(lambda^-6): 1e-6 at lambda0 = 10
            assert ex[key][q] == pytest.approx(ls[key][q], abs=2e-6), (key, q)


def test_simulate_exact_pressure_control():
    r = simulate("pressure", "frictionless", d=0.2, w=0.2, rs=0.5, a_max=0.25, lambda0=1.5,
                 points=30, membrane="exact")
    assert list(r.frame.columns) == ["stage", "a", "alpha", "p", "d", "delta", "f", "G", "stable"]
    assert np.allclose(r.frame["d"], 0.2, atol=1e-10)
    assert r.summary["turning_point"]["p"] == pytest.approx(r.frame["p"].min(), abs=1e-12)


def _cap_area(a, crv):
    return 2 * math.pi * a * a / (1 + math.sqrt(1 - (a * crv) ** 2))


@pytest.mark.parametrize("slip", ["frictionless", "no-slip"])
def test_energy_balance_pinning(slip):
    """d(U - PV) = -F dd along pinning (the edge force does no work)."""
    p, lam0 = 0.6, 1.2
    h = exact_history("displacement", slip, lambda0=lam0, points=20, **BASE)
    m = [s for s, st in zip(h.states, h.columns["stage"]) if st == "making_contact"][-1]
    stage = pinning(Config(lam0, 2.0), "displacement", slip, m, p)
    a0, da = 0.3, 1e-4
    # difference quotients of solved states: solve them to 1e-14 (rows use 1e-10)
    s_p, s_m, s_0 = (stage.solve(a0 + k * da, stage.x(m), tol=1e-14) for k in (1, -1, 0))
    dE = (s_p.u - 2 * p * s_p.v) - (s_m.u - 2 * p * s_m.v)
    assert dE / (s_p.d - s_m.d) == pytest.approx(-2 * s_0.f, rel=1e-6)


@pytest.mark.parametrize("slip", ["frictionless", "no-slip"])
def test_release_rate_from_stored_energy(slip):
    """G = w on delamination, from d(U - PV) + F dd = W_ad dA (not from eq. 23).

    dA is the substrate area swept by the peeled material, 2 pi a lambda1- |d rho_a| (the model binds
    the adhesion energy to the material, as the paper does: frictionless pinning slides the edge with
    no adhesive spreading force). For no slip it equals the change of the contact cap area.
    """
    p, lam0, w = 0.6, 1.2, 0.2
    h = exact_history("displacement", slip, lambda0=lam0, points=20, **BASE)
    stg = h.columns["stage"]
    m = [s for s, st in zip(h.states, stg) if st == "making_contact"][-1]
    on = [s for s, st in zip(h.states, stg) if st == "pinning"][-1]
    stage = delamination(Config(lam0, 2.0), "displacement", slip, m, w, p)
    r0, dr = 0.7 * on.rho_a, 1e-5
    s_p, s_m = (stage.solve(r0 + k * dr, stage.x(on), tol=1e-14) for k in (1, -1))
    s_0 = stage.solve(r0, stage.x(on), tol=1e-14)
    dE = (s_p.u - 2 * p * s_p.v) - (s_m.u - 2 * p * s_m.v)
    dA = 2 * math.pi * s_0.a * s_0.l1m * (s_p.rho_a - s_m.rho_a)
    if slip == "no-slip":
        assert _cap_area(s_p.a, 2.0) - _cap_area(s_m.a, 2.0) == pytest.approx(dA, rel=1e-7)
    assert (dE + 2 * s_0.f * (s_p.d - s_m.d)) / dA == pytest.approx(w, rel=1e-5)


def test_loading_end_from_delta_max_and_p_max():
    h = exact_history("displacement", "frictionless", p=0.6, w=0.2, rs=0.5, delta_max=0.2, lambda0=1.3,
                      points=20)
    i = int(np.argmax(h.columns["f"]))
    assert h.columns["delta"][i] == pytest.approx(0.2, abs=1e-9)
    h = exact_history("pressure", "no-slip", d=0.2, w=0.2, rs=0.5, p_max=0.6, lambda0=1.3, points=20)
    assert h.columns["p"][h.columns["stage"] == "making_contact"].max() == pytest.approx(0.6, abs=1e-9)


@pytest.mark.parametrize("kw, name", [
    (dict(p=0.95, lambda0=1.05, a_max=0.25), "p"),  # no Case I free inflation
    (dict(p=0.6, lambda0=1.0, a_max=0.25), "lambda0"),
    (dict(p=0.6, lambda0=1.2, delta_max=1.5), "delta_max"),  # beyond what loading reaches
    (dict(p=0.6, lambda0=1.2, a_max=0.6), "a_max"),  # past the substrate's equator (rs = 0.5)
])
def test_input_errors_name_the_parameter(kw, name):
    from adhfit.errors import InputError
    with pytest.raises(InputError) as exc:
        exact_history("displacement", "frictionless", w=0.2, rs=0.5, points=20, **kw)
    assert exc.value.name == name


def test_weak_adhesion_no_slip_branch_ends_where_large_stretch_does():
    """No slip, w = 0.002: quasi-static delamination ends at a finite radius where alpha = 0."""
    kw = dict(p=0.6, w=0.002, rs=0.5, a_max=0.25)
    ls = simulate("displacement", "no-slip", **kw)
    ex = exact_history("displacement", "no-slip", lambda0=10.0, points=40, **kw)
    assert ex.columns["alpha"][-1] == pytest.approx(0.0, abs=1e-12)
    assert ex.inputs["delamination_ends_at_a"] == pytest.approx(ls.inputs["delamination_ends_at_a"], abs=1e-5)


def test_no_slip_delamination_never_enters_the_substrate():
    """No slip, pressure control, lambda0 = 1.78, w = 0.237, a large contact: alpha reaches 0 between two
    delamination rows and the continuation would carry on smoothly to alpha < 0 (the membrane inside the
    sphere).
    The history must end there instead, at alpha = 0, as the large-stretch one does; its f_min (near
    alpha = 0, where a coarse edge mesh was 9e-7 off) agrees with n = 32 to 1e-7."""
    control, args = "pressure", dict(d=0.2178, w=0.237, rs=0.5, a_max=0.3728, lambda0=1.775, points=200)
    h = exact_history(control, "no-slip", **args)
    alpha = h.columns["alpha"]
    assert np.all(alpha >= 0.0) and alpha[-1] == pytest.approx(0.0, abs=1e-12)
    assert h.inputs["delamination_ends_at_a"] == h.columns["a"][-1] > 0.1
    fine = exact_history(control, "no-slip", n=32, **args)
    assert h.summary["f_min"]["f"] == pytest.approx(fine.summary["f_min"]["f"], abs=1e-7)


def test_delta_is_nan_where_free_inflation_has_no_case_one_state():
    """Pressure control, lambda0 = 1.78, a large contact: the loading pushes p to 1.48, beyond the
    pressures at which the free membrane has a Case I state (up to ~0.97 here). There d0(p) does not
    exist and delta must be NaN (the large-stretch engine's convention for |p| > 1), not the apex of a
    shot that curls through the axis and happens to meet r(beta) = 1 (before: delta 3e25, 162, -9.7).
    Below it, delta = d0(p) - d with d0 from one free-inflation solve per row."""
    from adhfit.errors import ConvergenceError
    from adhfit.exact.inflation import free_inflation
    lam0 = 1.775
    h = exact_history("pressure", "no-slip", d=0.2178, w=0.237, rs=0.5, a_max=0.3728, lambda0=lam0, points=80)
    for q in (1.0, 1.2, 1.47):
        with pytest.raises(ConvergenceError):
            free_inflation(q, lam0)
    p, delta, d = h.columns["p"], h.columns["delta"], h.columns["d"]
    assert np.any(p > 1.0) and np.all(np.isnan(delta[p > 1.0]))
    low = np.flatnonzero(p < 0.95)
    assert len(low) > 30 and np.all(np.isfinite(delta[low]))
    for i in low[::4]:
        assert delta[i] == pytest.approx(free_inflation(p[i], lam0).d - d[i], abs=1e-10)


@pytest.mark.parametrize("n", STEPS)
@pytest.mark.parametrize("slip", ["frictionless", "no-slip"])
def test_pressure_control_states_against_reference(slip, n):
    """Pressure control, lambda0 = 1.5: states re-shot by the independent solver at their own p."""
    h = exact_history("pressure", slip, d=0.2, w=0.2, rs=0.5, a_max=0.25, lambda0=1.5, points=30, n=n)
    m = [s for s, st in zip(h.states, h.columns["stage"]) if st == "making_contact"][-1]
    for i in (len(h.states) // 2, -5):
        s = h.states[i]
        edge = "frictionless" if slip == "frictionless" else "given"
        lc = s.lc if slip == "frictionless" else m.lc
        r_end, d, f, G = ref.edge_state(s.p, 1.5, 0.5, lc, s.rho_a, s.alpha, edge, s.l1p)
        assert r_end == pytest.approx(1.0, abs=_tol(n))
        assert d == pytest.approx(0.2, abs=_tol(n))
        assert (f, G) == pytest.approx((s.f, 0.2), abs=_tol(n))


def test_strong_adhesion_and_domain_limits():
    # strong adhesion, no slip: G rises steeply near the end of pinning, the onset is still found
    h = exact_history("displacement", "no-slip", p=0.6, w=10.0, rs=0.5, a_max=0.25, lambda0=10.0, points=20)
    assert h.summary["f_min"]["f"] == pytest.approx(
        simulate("displacement", "no-slip", p=0.6, w=10.0, rs=0.5, a_max=0.25).summary["f_min"]["f"], abs=1e-6)
    # at lambda0 = 1.2 the contact region goes slack (stretch -> 1) before G reaches w = 5: an error
    from adhfit.errors import ConvergenceError
    with pytest.raises(ConvergenceError, match="slack"):
        exact_history("pressure", "frictionless", d=0.2, w=5.0, rs=0.5, a_max=0.25, lambda0=1.2, points=20)


@pytest.mark.parametrize("control, slip, kw", [("displacement", "frictionless", dict(p=0.6)),
                                               ("displacement", "no-slip", dict(p=0.6)),
                                               ("pressure", "frictionless", dict(d=0.2)),
                                               ("pressure", "no-slip", dict(d=0.2))])
def test_rows_and_extrema_are_solved_states(control, slip, kw):
    """Rows of the compiled continuation (whose last Newton step is often taken without a shot,
    ``newton._finish``) re-solved one by one (Newton from a perturbed start, residuals to 1e-13) agree
    with the rows to 1e-9 in every stage; the refined f_min is a minimum of f along delamination (states
    solved 1e-4 either side have a larger f); pressure control's delta column (interpolated d0(p))
    agrees with one free-inflation solve per row."""
    from adhfit.exact.inflation import free_inflation
    lam0 = 1.5
    h = exact_history(control, slip, lambda0=lam0, points=60, w=0.2, rs=0.5, a_max=0.25, **kw)
    stg = h.columns["stage"]
    m = [s for s, st in zip(h.states, stg) if st == "making_contact"][-1]
    cfg, p, d = Config(lam0, 2.0), kw.get("p"), kw.get("d")
    stage = delamination(cfg, control, slip, m, 0.2, p, d)
    stages = {"making_contact": (making_contact(cfg, control, p, d), "a"),
              "pinning": (pinning(cfg, control, slip, m, p, d), "alpha"),
              "delamination": (stage, "rho_a")}
    checked = 0
    for i in range(1, len(h.states) - 1, 3):
        s = h.states[i]
        if stg[i] == "pinning" and i + 1 < len(stg) and stg[i + 1] != "pinning":
            continue  # the onset (G = w): solved by its own stage
        st, param = stages[stg[i]]
        t = st.solve(getattr(s, param), [1.0001 * x for x in st.x(s)], tol=1e-13)
        assert (t.f, t.d, t.a, t.p, t.G, t.lc) == pytest.approx((s.f, s.d, s.a, s.p, s.G, s.lc), abs=1e-9)
        checked += 1
    assert checked >= 18
    fmin = h.summary["f_min"]
    j = int(np.argmin(np.abs(h.columns["f"] - fmin["f"])))
    rho = h.states[j].rho_a
    for dr in (1e-4, -1e-4):
        t = stage.solve(rho + dr, stage.x(h.states[j]), tol=1e-13)
        assert t.f > fmin["f"]
    if control == "pressure":
        for i in range(0, len(h.states), 9):
            s = h.states[i]
            assert h.columns["delta"][i] == pytest.approx(free_inflation(s.p, lam0).d - s.d, abs=1e-10)


@pytest.mark.parametrize("n", STEPS)
def test_onset_when_g_rises_slowly_along_pinning(n):
    """No slip, pressure control, lambda0 = 1.1, w = 1: G climbs to w only near alpha ~ 1.5 and the
    pinning branch continues past it onto states with G ~ 0.06 (a long alpha step can land there).
    The onset must be the first G = w: G rises along the pinning rows, and the onset state re-shot by
    the independent solver closes at the clamp with G = w and the row's gap."""
    h = exact_history("pressure", "no-slip", d=-0.05, w=1.0, rs=0.5, a_max=0.25, lambda0=1.1, points=30, n=n)
    stg = h.columns["stage"]
    g = h.columns["G"][stg == "pinning"]
    assert np.all(np.diff(g) > 0) and g[-1] == pytest.approx(1.0, abs=1e-10)
    m = [s for s, st in zip(h.states, stg) if st == "making_contact"][-1]
    on = [s for s, st in zip(h.states, stg) if st == "pinning"][-1]
    r_end, d, f, G = ref.edge_state(on.p, 1.1, 0.5, m.lc, on.rho_a, on.alpha, "given", on.l1p)
    assert (r_end, d, f, G) == pytest.approx((1.0, -0.05, on.f, 1.0), abs=_tol(n))
