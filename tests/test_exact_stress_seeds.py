"""Stress-seed scenes of the exact membrane (issue 24: seeds 2, 3, 7, 11, 24), each one's fix checked
independently of the code under test where possible (another row grid, the branch's own states, the
analytic identity of the contact force)."""
import math

import numpy as np
import pytest

import adhfit
from adhfit.errors import ConvergenceError, DomainError
from adhfit.exact import kernels as K
from adhfit.exact.history import exact_history

def _prepared(sc: dict, points: int = 50):
    """The exact engine's validated scene and its solver configuration (n = 8), as a history starts."""
    from adhfit.exact.control import prepare
    from adhfit.exact.state import Config
    c = prepare(sc["control"], sc["slip"], sc.get("p"), sc.get("d"), sc["w"], sc["rs"], sc["lambda0"],
                sc.get("a_max"), sc.get("delta_max"), sc.get("p_max"), points, 8)
    return c, Config(c.lambda0, c.crv, c.n)


GRIDS = (10, 11, 50, 200, 1001)


def _summary_values(s):
    return [s["f_max"]] + [s[k][q] for k in ("onset", "f_min", "turning_point") for q in ("f", "p", "a")]


def _same_on_every_grid(sc, grids=GRIDS):
    """Every grid gives a history whose summary agrees with the 1001-row one to 1e-8."""
    ref = _summary_values(adhfit.simulate(**sc, points=1001, membrane="exact").summary)
    for n in grids:
        got = _summary_values(adhfit.simulate(**sc, points=n, membrane="exact").summary)
        assert np.max(np.abs(np.subtract(got, ref))) < 1e-8, n


# 4a: a false "tensile while making contact" DomainError at 1001 rows only: the first rows (a ~ 1e-6) had
# f ~ -1e-10 (the absolute error of the last, Jacobian-updated Newton step), where the force is positive
COMPRESSIVE = {
    "sphere_p_pos": {"control": "displacement", "slip": "frictionless", "p": 0.6646232032268258,
                     "w": 7.485110334339072, "rs": 1.030477256042499, "delta_max": 0.01501837070897856,
                     "lambda0": 1.2000317907318199},
    "big_sphere": {"control": "displacement", "slip": "no-slip", "p": 0.6526070675532547, "w": 5.693148666126391,
                   "rs": 86.45105591657092, "delta_max": 0.00024086249299457173, "lambda0": 1.0731404068642771},
    "p_neg": {"control": "displacement", "slip": "frictionless", "p": -0.3477996296038832,
              "w": 0.0006285446688657191, "rs": 0.17595056676506596, "delta_max": 0.0037782452349012664,
              "lambda0": 1.0583911299190005},
}


@pytest.mark.parametrize("name", sorted(COMPRESSIVE))
def test_compressive_at_every_grid(name):
    """Independent: while making contact the force is f = pi a^2 (p + T1+/rs) (alpha = 0, the edge
    tangent to the sphere); T1+ = t1(l1+, l2) > 0 and p + T1+/rs > 0 on every row of the 1001-row
    history, well above the error of its terms, so no state is tensile; the summary is the same on every
    grid (10 rows to 1001)."""
    sc = COMPRESSIVE[name]
    res = exact_history(**sc, points=1001)
    mc = [s for s, st in zip(res.states, res.columns["stage"]) if st == "making_contact"][1:]
    q = np.array([s.p + K.tensions(s.l1p, s.l2a)[0] / sc["rs"] for s in mc])
    assert q.min() > 1e-3 * abs(sc["p"])
    assert res.summary["f_max"] > 0.0
    _same_on_every_grid(sc)


# 3: seed 11, pressure control, frictionless, flat punch: pinning continued in p stalled at alpha = pi/2 -
# 1.1e-5 (a ConvergenceError at 200 rows, and on every grid for the second scene): the contact region's
# tension T1- = T1+ cos(alpha) falls to 0 there (slack), with G ~ 7.7 < w ~ 8.7
SLACK = {
    "a": {"control": "pressure", "slip": "frictionless", "d": 0.6391910314157798, "w": 8.667611079474714,
          "rs": math.inf, "a_max": 0.3628276458970798, "lambda0": 1.2220547858031294},
    "b": {"control": "pressure", "slip": "frictionless", "d": 0.49753020186477803, "w": 8.845695061650245,
          "rs": math.inf, "a_max": 0.25537208750441964, "lambda0": 1.1863795606145033},
}


@pytest.mark.parametrize("name", sorted(SLACK))
def test_frictionless_pinning_ends_slack_below_w(name):
    """A DomainError (the slack end) on every grid. Independent of the history's code: pinning states
    solved here on the branch parameterized by the contact stretch (alpha and p unknown, the clamp and the
    gap d as residuals, the contact edge where the loading left it), at lambda_c - 1 = 1e-4, 1e-5, 1e-6:
    alpha within 2e-6 of pi/2 at the last, the contact tension T1- ~ 6e-6 (slack in the limit), Case I at
    the clamp, and G below w by more than 0.9 with a rise of < 1e-2 over the last two decades."""
    from adhfit.exact.history import _loading
    from adhfit.exact.stages import Stage
    sc = SLACK[name]
    for n in GRIDS:
        with pytest.raises(DomainError, match="slack"):
            exact_history(**sc, points=n)
    c, cfg = _prepared(sc)
    _, m = _loading(cfg, c)
    st = Stage(cfg, "frictionless", {"rho_a": m.rho_a}, ("alpha", "p"), ("clamp", "d"), {"d": sc["d"]}, "lc")
    guess, gs = [0.5 * math.pi - 1.6e-4, -1.0], []
    for x in (1e-4, 1e-5, 1e-6):
        s = st.solve(1.0 + x, guess)
        assert abs(s.theta_end) < 0.5 * math.pi and 0.0 < 0.5 * math.pi - s.alpha < 2.0 * x
        assert 0.0 < K.tensions(s.l1m, s.l2a)[0] < 7.0 * x  # 1 - lambda_c^-6 ~ 6 (lambda_c - 1)
        gs.append(s.G)
        guess = [0.5 * math.pi - 0.1 * (0.5 * math.pi - s.alpha), s.p]
    assert max(gs) < sc["w"] - 0.9 and abs(gs[-1] - gs[0]) < 1e-2


# 4b: pressure control, frictionless: at 1001 rows only the pinning rows' small first steps in alpha took the
# branch that presses on (p rising to 1.21 above the loading end's 0.99, lc to 4.06) and stalled near vertical
# at the clamp (alpha = 0.366): "Newton line search did not converge"; the onset (alpha = 0.900) lies on the
# branch that retracts, which 10-200 rows follow
PRESSES_ON = {"control": "pressure", "slip": "frictionless", "d": 0.13931713060061957, "w": 0.5109398294217656,
              "rs": 0.21226385610254273, "a_max": 0.18360772105325168, "lambda0": 1.3397743889314204}


def test_pinning_rows_follow_the_retracting_branch_on_1001_rows():
    """Independent: the 1001-row pinning rows retract (p at or below the loading end's, G rising to w)
    and lie on the 200-row history's pinning path (p against alpha, interpolated); the summary agrees on
    every grid."""
    sc = PRESSES_ON
    r1, r2 = exact_history(**sc, points=200), exact_history(**sc, points=1001)
    c1, c2 = r1.columns, r2.columns
    pin2 = c2["stage"] == "pinning"
    p_end = c2["p"][np.flatnonzero(c2["stage"] == "making_contact")[-1]]
    assert np.all(c2["p"][pin2] <= p_end + 1e-12) and np.all(c2["G"][pin2] <= sc["w"] * (1 + 1e-9))
    assert np.all(np.diff(c2["G"][pin2]) > 0)
    pin1 = c1["stage"] == "pinning"
    a1, p1 = c1["alpha"][pin1], c1["p"][pin1]
    from scipy.interpolate import CubicSpline
    inside = (c2["alpha"][pin2] >= 0.1) & (c2["alpha"][pin2] <= a1.max())  # (p is steep in alpha near 0)
    spline = CubicSpline(a1, p1)
    # (the branch that presses on lies ~1 away in p)
    assert np.max(np.abs(spline(c2["alpha"][pin2][inside]) - c2["p"][pin2][inside])) < 1e-4
    _same_on_every_grid(sc)


# 4c: displacement control, no slip, weak adhesion: the onset at alpha = 0.049 lies near the no-slip branch's
# end (alpha = 0); on 10 and 11 rows Newton on the end equations from the onset lost its line search
NEAR_END = {"control": "displacement", "slip": "no-slip", "p": 0.4975077728354589, "w": 0.0010840928104376567,
            "rs": 2.860838911140139, "a_max": 0.704434603294333, "lambda0": 1.5045346537864834}


def test_no_slip_branch_end_on_few_rows():
    """Independent: the branch end on 10 and 11 rows is the 1001-row one (its own march, other steps) to
    1e-8; it has alpha = 0 and G = w (the end's two conditions), below the onset's contact radius."""
    sc = NEAR_END
    ref = exact_history(**sc, points=1001)
    for n in (10, 11):
        h = exact_history(**sc, points=n)
        end = h.inputs["delamination_ends_at_a"]
        assert end == pytest.approx(ref.inputs["delamination_ends_at_a"], abs=1e-8)
        dl = [s for s, st in zip(h.states, h.columns["stage"]) if st == "delamination"]
        last = min(dl, key=lambda s: s.a)
        assert abs(last.alpha) < 1e-10 and last.G == pytest.approx(sc["w"], rel=1e-9)
        assert last.a == pytest.approx(end, abs=1e-12) and end < h.summary["onset"]["a"]
    _same_on_every_grid(sc)


# 2: seed 7, displacement control, no slip: pinning continued in d stalled at a fold of d (alpha = 0.202, G =
# 0.227 < w = 1.097); past the fold G rises (the fold check wanted it falling) and its first probe, 1.9e-3 in
# lambda1+ past it, failed to solve: a ConvergenceError on every grid
FOLD_NO_SLIP = {"control": "displacement", "slip": "no-slip", "p": -0.11728594120516367, "w": 1.0971977836637328,
                "rs": 0.19255787881367523, "a_max": 0.1700321586950153, "lambda0": 1.0849927077844557}


def test_pinning_fold_in_d_then_alpha_zero_is_a_domain_error():
    """A DomainError on every grid, its locator the same. Independent of the history's code: the whole
    pinning branch marched here in lambda1+ from the end of loading (alpha = 0 there; steps of 1e-3, then
    2e-5 near the fold): d rises to a maximum equal to the locator (to 1e-7), then falls, and alpha comes
    back to 0 (the membrane tangent to the sphere at the pinned edge) with G < w everywhere on the way."""
    from adhfit.exact.history import _loading, march
    from adhfit.exact.stages import Stage
    sc = FOLD_NO_SLIP
    locs = []
    for n in GRIDS:
        with pytest.raises(DomainError, match="retracts the control at most to d") as err:
            exact_history(**sc, points=n)
        locs.append(err.value.context["locator"] if hasattr(err.value, "context") else
                    float(str(err.value).split("at most to d = ")[1].split()[0]))
    assert max(locs) - min(locs) < 1e-9
    c, cfg = _prepared(sc)
    _, m = _loading(cfg, c)
    st = Stage(cfg, "given", {"rho_a": m.rho_a, "lc": m.lc, "p": sc["p"]}, ("alpha",), ("clamp",), {}, "l1p")
    coarse = list(m.l1p - 1e-3 * np.arange(1, int((m.l1p - 0.861) / 1e-3)))
    fine = list(np.arange(coarse[-1] - 2e-5, 0.857, -2e-5))
    sts = march(st, coarse + fine, [1e-3], stop_ok=True)
    k = next(i for i, s in enumerate(sts) if s.alpha < 0.0)
    on = sts[:k]
    d = np.array([s.d for s in on])
    i = int(np.argmax(d))
    assert 0 < i < k - 1 and abs(d[i] - locs[-1]) < 1e-7
    assert all(s.G < sc["w"] for s in sts[:k + 1]) and all(s.alpha > 0.0 for s in on)
    assert d[-1] < d[i] - 1e-3  # d falls past the fold before alpha reaches 0


# 1: seed 7, displacement control, no slip, p = -0.78: the pinning branch that retracts d from the end of
# loading has alpha < 0 at once (the free membrane beside the pinned edge turned into the sphere); it was
# continued in d through such states to an "onset" at alpha = -0.042, from which no delamination branch
# exists: a ConvergenceError on every grid. No admissible pinned state retracts d: the branch that presses on
# is the history (docs/contracts.md A2: the end of loading is the turning point). (Two seed-24 scenes whose
# pinning rows dipped to alpha = -0.015 and -0.007 before rising now take that branch too, which turns past
# vertical at the clamp before G reaches w: DomainErrors.)
ENTERS = {"control": "displacement", "slip": "no-slip", "p": -0.782996481377277, "w": 0.047905513575745774,
          "rs": 0.2829169838283269, "a_max": 0.2368757732048399, "lambda0": 1.5758284915566447}


def retracting_alpha_signs(sc):
    """Independent of the history's code: no-slip pinning states solved in d (unknowns lambda1+ and alpha,
    the contact field frozen at the end of loading) at d_m + h, h = +-1e-4, +-1e-3: {h: alpha}."""
    from adhfit.exact.history import _loading
    from adhfit.exact.stages import Stage
    c, cfg = _prepared(sc)
    _, m = _loading(cfg, c)
    st = Stage(cfg, "given", {"rho_a": m.rho_a, "lc": m.lc, "p": sc["p"]}, ("l1p", "alpha"), ("clamp", "d"),
               {"d": m.d}, "d")
    alphas = {}
    for h in (-1e-3, -1e-4, 1e-4, 1e-3):
        s = st.solve(m.d + h, [m.l1p, 0.0])
        assert abs(s.d - (m.d + h)) < 1e-9 and abs(s.theta_end) < 0.5 * math.pi
        alphas[h] = s.alpha
    return alphas


def test_no_slip_pinning_that_would_enter_the_substrate_presses_on():
    """Independent: pinning states solved in d either side of the end of loading
    (``retracting_alpha_signs``): retracting (d above d_m) alpha < 0, pressing on (d below) alpha > 0,
    alpha changing sign at d_m like (d - d_m): no admissible pinned state retracts the control. The
    history is the branch that presses on: every pinning row has alpha >= 0 and d <= d_m, G rises to w,
    the turning point is the end of loading; the summary is the same on every grid."""
    sc = ENTERS
    alphas = retracting_alpha_signs(sc)
    assert alphas[1e-4] < 0.0 and alphas[1e-3] < alphas[1e-4]
    assert alphas[-1e-4] > 0.0 and alphas[-1e-3] > alphas[-1e-4]
    assert alphas[1e-3] / alphas[1e-4] == pytest.approx(10.0, rel=0.1)
    h = exact_history(**sc, points=200)
    col = h.columns
    pin = col["stage"] == "pinning"
    mk = np.flatnonzero(col["stage"] == "making_contact")[-1]
    assert np.all(col["alpha"][pin] >= 0.0) and np.all(col["d"][pin] <= col["d"][mk] + 1e-12)
    assert np.all(np.diff(col["G"][pin]) > 0) and col["G"][pin][-1] == pytest.approx(sc["w"], rel=1e-9)
    assert h.summary["turning_point"]["f"] == h.summary["f_max"]
    _same_on_every_grid(sc)


# seed 2, displacement control, frictionless, flat punch: the delamination branch meets the clamp's vertical
# steeply in rho_a (theta_end rising ~12 per unit of rho_a there) at a = 0.23241; the march stalled just
# before it, and Newton from the last state straight at the next rho_a failed: a ConvergenceError on 50-300
# rows; on 10 and 11 rows the finer retry from the stall landed past it on another branch (a = 1.08, beyond
# the clamp) and gave a history; 1001 rows found the DomainError
VERTICAL_DEL = {"control": "displacement", "slip": "frictionless", "p": 0.9881968374222942,
                "w": 0.040155760401110734, "rs": math.inf, "a_max": 0.7295076319166437,
                "lambda0": 1.9429146564880362}


def test_delamination_meeting_vertical_steeply_is_a_domain_error_on_every_grid():
    """The same DomainError (its locator to 1e-9) on every grid. Independent of the history's code: the
    delamination branch (G = w) continued here in the centre stretch lc (unknowns rho_a and alpha, no
    check of the clamp's tangent) from a state solved at rho_a = 0.0612 through lc steps of 1e-4: rho_a
    falls monotonically and theta_end rises through pi/2, at the locator's contact radius (to 1e-6)."""
    from adhfit.exact.history import _loading, _pinning
    from adhfit.exact.solve import solve_state
    from adhfit.exact.stages import delamination
    sc = VERTICAL_DEL
    locs = []
    for n in GRIDS:
        with pytest.raises(DomainError, match="delamination branch .* turns past vertical") as err:
            exact_history(**sc, points=n)
        locs.append(float(str(err.value).split(" at a = ")[1].split()[0]))
    assert max(locs) - min(locs) < 1e-9
    c, cfg = _prepared(sc)
    _, m = _loading(cfg, c)
    _, on = _pinning(cfg, c, m)
    st = delamination(cfg, c.control, c.slip, m, c.w, c.p, c.d)
    s = st.solve(0.0612, [3.8, on.alpha])
    assert s.theta_end < 0.5 * math.pi
    x, rows = [s.rho_a, s.alpha], [s]
    for k in range(1, 200):
        s = solve_state(cfg, "frictionless", {"p": sc["p"], "lc": rows[0].lc + 1e-4 * k}, ("rho_a", "alpha"), x,
                        ("clamp", "G"), {"w": sc["w"]}, tol=1e-11)
        assert abs(s.G - sc["w"]) < 1e-9 and s.rho_a < rows[-1].rho_a
        x = [s.rho_a, s.alpha]
        rows.append(s)
        if s.theta_end > 0.5 * math.pi + 1e-4:
            break
    th = np.array([r.theta_end for r in rows])
    j = int(np.flatnonzero(th > 0.5 * math.pi)[0])
    assert j > 1
    a0, a1, t0, t1 = rows[j - 1].a, rows[j].a, th[j - 1], th[j]
    a_cross = a0 + (a1 - a0) * (0.5 * math.pi - t0) / (t1 - t0)
    assert abs(a_cross - locs[-1]) < 1e-6


# seed 2, displacement control, no slip, p = -0.578: pinning is marched in alpha up to a fold of alpha (2.6175,
# the handover to the control). On 50 and 200 rows a row solved on another branch (lambda1+ = 0.70 where the
# branch has 0.98; the clamp tangent -0.15 against -1.18) and the march stalled on it: a ConvergenceError (or a
# false slack DomainError); on 10 and 11 rows the only row in alpha lay on the fold itself (2 u = 1 to
# rounding), where Newton in alpha does not converge
PIN_JUMP = {"control": "displacement", "slip": "no-slip", "p": -0.5776374910167641, "w": 2.2694848735519155,
            "rs": 1.186919775940009, "a_max": 0.9048270047761684, "lambda0": 1.0593571856987913}


def test_no_slip_pinning_rows_stay_on_their_branch():
    """Independent: the pinning branch marched here in alpha from the end of loading on steps of 1e-3
    (lambda1+ within 0.01 from step to step); every 200-row pinning row with alpha below the fold lies on it
    (lambda1+ and d interpolated in alpha, to 1e-6); the summary is the same on every grid."""
    from adhfit.exact.history import _loading, march
    from adhfit.exact.stages import pinning
    sc = PIN_JUMP
    c, cfg = _prepared(sc)
    _, m = _loading(cfg, c)
    st = pinning(cfg, c.control, c.slip, m, c.p, c.d)
    al = np.arange(1e-3, 2.6, 1e-3)
    sts = march(st, list(al), st.x(m))
    l1 = np.array([s.l1p for s in sts])
    assert len(sts) == len(al) and np.max(np.abs(np.diff(l1))) < 0.01
    d = np.array([s.d for s in sts])
    h = exact_history(**sc, points=200)
    col = h.columns
    rows = (col["stage"] == "pinning") & (col["alpha"] < 2.59) & (col["alpha"] > 1e-3)
    seg = np.flatnonzero(rows)
    seg = seg[seg < np.flatnonzero(col["alpha"] == col["alpha"][col["stage"] == "pinning"].max())[0]]
    assert len(seg) >= 5
    for i in seg:
        assert abs(np.interp(col["alpha"][i], al, d) - col["d"][i]) < 1e-6
        assert abs(np.interp(col["alpha"][i], al, l1) - h.states[i].l1p) < 1e-5
    _same_on_every_grid(sc)


# seed 2, displacement control, no slip, sphere (rs = 0.024): on 10 and 11 rows the delamination march on its
# fine steps passed the branch end (alpha = 0, a = 0.0087) between two of its states, but the history's last
# row before it had alpha = 0.55; the retry from that row stalled at alpha = 0.204 (above the 0.2 that marks a
# branch end as reached): a ConvergenceError where 50 rows and more end the branch
NO_SLIP_END_SKIPPED = {"control": "displacement", "slip": "no-slip", "p": 0.5111712743357746,
                       "w": 0.19038904867822415, "rs": 0.024080653133154082, "a_max": 0.019320483508876007,
                       "lambda0": 2.5546809207809607}


def test_no_slip_end_passed_between_fine_steps_on_few_rows():
    """Independent: the delamination branch marched here in rho_a from the onset on 4000 steps: alpha
    changes sign once, between rows whose linear interpolation in alpha puts the end's contact radius
    within 1e-6 of the history's ``delamination_ends_at_a`` on every grid (which agree to 1e-9); the
    summary is the same on every grid."""
    from adhfit.exact.history import _loading, _pinning, march
    from adhfit.exact.stages import delamination
    sc = NO_SLIP_END_SKIPPED
    ends = [exact_history(**sc, points=n).inputs["delamination_ends_at_a"] for n in GRIDS]
    assert max(ends) - min(ends) < 1e-9
    c, cfg = _prepared(sc)
    _, m = _loading(cfg, c)
    _, on = _pinning(cfg, c, m)
    st = delamination(cfg, c.control, c.slip, m, c.w, c.p, c.d)
    rho = on.rho_a * (1.0 - np.arange(1, 3000) / 4000.0)
    sts = march(st, list(rho), st.x(on), stop_ok=True, start=(on.rho_a, on))
    al = np.array([s.alpha for s in sts])
    k = int(np.flatnonzero(al < 0.0)[0])
    assert np.all(al[:k] > 0.0) and k > 10
    s0, s1 = sts[k - 1], sts[k]
    a_end = s0.a + (s1.a - s0.a) * s0.alpha / (s0.alpha - s1.alpha)
    assert abs(a_end - ends[-1]) < 1e-6
    _same_on_every_grid(sc)


# seed 2, pressure control, frictionless: the turning point (the least p along delamination, a = 0.0135 near
# detachment) is flat (p'' ~ 8 in rho_a); on 10 and 11 rows the quartic's vertex was accepted 0.042 h off
# its stencil's centre (within 0.05 h), its a 3.3e-8 off the 1001-row one (centred there)
FLAT_TURN = {"control": "pressure", "slip": "frictionless", "d": -0.463733091600647, "w": 0.0003937175126646584,
             "rs": 0.617900151293699, "a_max": 0.3174400150584697, "lambda0": 1.1383095391471063}


def test_flat_turning_point_same_on_every_grid():
    """Independent: the turning point located here as the root of the slope of p in rho_a along delamination
    (central differences at h = 2e-4 and 1e-4 Richardson-extrapolated, states solved to 1e-13, secant
    iterations): every grid's turning point has its contact radius within 2e-8 of it (the stencil's
    truncation) and its p within 1e-13; the summary is the same on every grid (to 1e-8)."""
    from adhfit.exact.history import _loading, _pinning
    from adhfit.exact.stages import delamination
    sc = FLAT_TURN
    c, cfg = _prepared(sc)
    _, m = _loading(cfg, c)
    _, on = _pinning(cfg, c, m)
    st = delamination(cfg, c.control, c.slip, m, c.w, c.p, c.d)
    ref = st.solve(0.010176, st.x(on), tol=1e-12)
    ref = st.solve(0.010176, st.x(ref), tol=1e-13)

    def slope(x):
        def dd(h):
            return (st.solve(x + h, st.x(ref), tol=1e-13).p - st.solve(x - h, st.x(ref), tol=1e-13).p) / (2 * h)
        d1, d2 = dd(2e-4), dd(1e-4)
        return d2 + (d2 - d1) / 3.0
    x0, x1 = 0.010176, 0.0101765
    f0, f1 = slope(x0), slope(x1)
    for _ in range(6):
        if f1 == f0:
            break
        x0, f0, x1 = x1, f1, x1 - f1 * (x1 - x0) / (f1 - f0)
        f1 = slope(x1)
    star = st.solve(x1, st.x(ref), tol=1e-13)
    for n in GRIDS:
        tp = exact_history(**sc, points=n).summary["turning_point"]
        assert abs(tp["a"] - star.a) < 2e-8 and abs(tp["p"] - star.p) < 1e-13, n
    _same_on_every_grid(sc)


# six frictionless scenes (displacement control) whose delamination branch carries the contact edge to the
# sphere's equator within one step of the history's rows: on 10 and 11 rows (50 too for two of them) the
# march stepped past it onto another branch (a falling again) and returned a history; 1001 rows prove a = rs
EQUATOR = {
    "s1": {"control": "displacement", "slip": "frictionless", "p": 0.36735439358701316, "w": 0.00031259301230824986,
           "rs": 0.5124442357201477, "delta_max": 0.8728324245272762, "lambda0": 2.7655775058208825},
    "s2": {"control": "displacement", "slip": "frictionless", "p": -0.7260345712065515, "w": 0.00014779182143689402,
           "rs": 0.021953514749671277, "a_max": 0.019488176097841522, "lambda0": 2.0707687416907334},
    "s4": {"control": "displacement", "slip": "frictionless", "p": 0.12151333599780623, "w": 0.0005457697824094171,
           "rs": 0.2127047124189917, "a_max": 0.20147958717277656, "lambda0": 2.0558870159032776},
    "s7": {"control": "displacement", "slip": "frictionless", "p": -0.6846364761243735, "w": 0.0007181046225948551,
           "rs": 0.021001063093705464, "a_max": 0.01961404512410852, "lambda0": 1.8351783278989775},
    "s8": {"control": "displacement", "slip": "frictionless", "p": -0.4598590942448595, "w": 0.010544557074958764,
           "rs": 0.5266807479173881, "delta_max": 0.9111962578618391, "lambda0": 1.9154934014350846},
    "s9": {"control": "displacement", "slip": "frictionless", "p": -0.08394176894038985, "w": 0.0014771093784706714,
           "rs": 0.3074227678740187, "a_max": 0.2841624136451513, "lambda0": 2.472601735037768},
}


@pytest.mark.parametrize("name", sorted(EQUATOR))
def test_delamination_equator_same_on_every_grid(name):
    """Independent: the delamination branch marched here from the onset state by state (Newton from the
    previous one, steps of 1e-3 of the onset's rho_a, no history logic) reaches a state whose contact edge
    is at the sphere's equator (a >= rs (1 - 1e-6)) with a rising all the way; every grid raises that
    DomainError (10 and 11 rows gave a history before)."""
    from adhfit.exact.history import _loading, _pinning
    from adhfit.exact.stages import delamination
    sc = EQUATOR[name]
    c, cfg = _prepared(sc, points=1001)
    _, m = _loading(cfg, c)
    _, on = _pinning(cfg, c, m)
    stage = delamination(cfg, c.control, c.slip, m, c.w, c.p, c.d)
    prev, h, reached = on, 1e-3 * on.rho_a, False
    for _ in range(2000):
        try:
            st = stage.solve(prev.rho_a - h, stage.x(prev))
        except ConvergenceError:
            h *= 0.5  # Newton's basin shrinks toward the equator: shorter steps
            assert h > 1e-12
            continue
        assert st.a >= prev.a - 1e-12 and abs(st.theta_end) < 0.5 * math.pi
        if st.a >= c.rs * (1.0 - 1e-6):
            reached = True
            break
        prev = st
    assert reached
    for n in GRIDS:
        with pytest.raises(DomainError, match="sphere's equator"):
            adhfit.simulate(**sc, points=n, membrane="exact")


# the same proven end on every grid where 10 and 11 rows (50 for the slack end) failed or went on: a making-contact
# row at a_max that was the state at a split of its step (a = 0.0979: history), first rows Newton could not reach
# from the free state (PastVertical, a lost line search), a slack-end stall at pi/2 - 1.2e-8 (ConvergenceError)
SAME_END = {
    "mc_split_row": ({"control": "displacement", "slip": "no-slip", "p": -0.9533915972652607, "w": 4.858318180151501,
                      "rs": 0.2856328402860007, "a_max": 0.10438553367116966, "lambda0": 1.267665063376192},
                     "while making contact", 0.0981337),
    "mc_first_row": ({"control": "displacement", "slip": "frictionless", "p": -0.9976723763053266,
                      "w": 7.057175047026398, "rs": 0.13347910427346832, "a_max": 0.1161723284674687,
                      "lambda0": 2.103087568840771}, "while making contact", 0.0145782),
    "pin_vertical": ({"control": "displacement", "slip": "no-slip", "p": 0.9973944928658296, "w": 8.523060422933066,
                      "rs": 10.84805243393741, "a_max": 0.6648785191341225, "lambda0": 1.8842230662667385},
                     "turns past vertical at the clamp at alpha", 1.0195671),
    "slack_near_half_pi": ({"control": "pressure", "slip": "frictionless", "d": 0.37644877673672195,
                            "w": 7.0106484336706245, "rs": math.inf, "a_max": 0.5980762159198754,
                            "lambda0": 1.2368332211288449}, "line tension at the contact edge fall to 0", None),
}


@pytest.mark.parametrize("name", sorted(SAME_END))
def test_same_proven_end_on_every_grid(name):
    """Every grid raises the same DomainError (its bound the same to the printed digits); for the making-contact
    ends, independently: the making-contact states solved directly (Newton from the previous one, steps of 1e-3
    of a_max, no history logic) stay in Case I below the bound and cannot be continued to a_max in Case I."""
    sc, words, bound = SAME_END[name]
    for n in GRIDS:
        with pytest.raises(DomainError, match=words) as err:
            adhfit.simulate(**sc, points=n, membrane="exact")
        if bound is not None:
            assert f"{bound:.8g}"[:8] in str(err.value), n
    if words != "while making contact":
        return
    from adhfit.exact.stages import PastVertical, making_contact
    c, cfg = _prepared(sc)
    stage = making_contact(cfg, c.control, c.p, c.d)
    h = 1e-3 * c.a_max
    prev = stage.solve(h, [c.free.lc, h / c.free.lc])
    stop = bound * (1.0 - 5e-3)
    while prev.a < stop:
        prev = stage.solve(min(prev.a + h, stop), stage.x(prev))
        assert abs(prev.theta_end) < 0.5 * math.pi
    # past the bound: no Case I state (Newton either fails or lands past vertical)
    for a in (bound * 1.002, 0.5 * (bound + c.a_max), c.a_max):
        try:
            st = stage.solve(a, stage.x(prev))
        except (PastVertical, ConvergenceError):
            continue
        assert not abs(st.theta_end) < 0.5 * math.pi or abs(st.a - a) > 1e-9
