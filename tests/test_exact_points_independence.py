"""Issue 24: the exact membrane's summary values do not depend on the row count.

Each scene is one of the stress run's points-check failures (``python benchmarks/stress_domain.py
--membrane exact --n 1000 --seed 24 --points-check 300 --workers 2``, commit c70113d): its summary at
10, 11 and 50 rows differed from the 1001-row one by up to 0.108, or one row count gave an error and
another a history. Now every count must give the same summary to 1e-8 (or the same named error).

The expected extrema come from a computation independent of the history's row grid and of its
extremum search (``locate`` below): the stage's states solved to 1e-13 at 25 Chebyshev points of a
window around the reported locator, the Chebyshev fit of the observable, and the root of its
derivative (numpy), then that state solved to 1e-13.
"""
from __future__ import annotations


import numpy as np
import pytest

import adhfit
from adhfit.errors import AdhfitError
from adhfit.exact import history as H
from adhfit.exact.control import prepare
from adhfit.exact.stages import delamination
from adhfit.exact.state import Config

GRIDS = (10, 11, 50)
KEYS = ("onset", "f_min", "turning_point")

#: pressure control: on 10 rows the turning point and f_min were a delamination row (the refinement
#: between rows did not converge and fell back to the least row): turning point a off by 0.108
COARSE_TURN = dict(control="pressure", slip="no-slip", d=0.027227786348524408, w=0.004163991265739962,
                   rs=10.457730879586677, p_max=1.5900481568620402, lambda0=2.6955141698249943)
#: the control turns just before the no-slip branch end (alpha = 0): coarse grids put the turning
#: point at the branch end, 1001 rows between their last two rows (a off by 3.7e-4 at 10-200 rows)
TURN_BEFORE_END = dict(control="displacement", slip="no-slip", p=0.7683200796126186, w=0.023719450397892354,
                       rs=5.939551694173983, a_max=0.33955338070828706, lambda0=1.3686283443830103)
#: the first delamination row of 10 rows lies past the no-slip branch end: "no quasi-static branch from
#: the onset" (a ConvergenceError) at 10 and 11 rows, a history at 50 and 1001
FIRST_ROW_PAST_END = dict(control="displacement", slip="no-slip", p=0.6992688975873742, w=0.001904389195541837,
                          rs=0.16304495887071477, a_max=0.13181703016158652, lambda0=2.634997585248391)
#: pressure control, frictionless: the first delamination step from the onset failed on 10 rows
#: and the march did not split it (the split needs a solved state to continue from)
FIRST_STEP_SPLIT = dict(control="pressure", slip="frictionless", d=0.06486114441243407, w=2.753293276910255,
                        rs=0.08185823275931524, a_max=0.029344486423591835, lambda0=1.0549167175133536)
#: the first making-contact row of 1001 rows (a = 1e-6) had f = -2.2e-10, rounding of a compressive
#: force of ~1e-12, and was raised as a tensile adhesionless contact (a DomainError) at 1001 rows only
TINY_FIRST_ROW = dict(control="displacement", slip="frictionless", p=0.4042411567161617, w=2.521140146908237,
                      rs=0.15257441395856844, delta_max=0.041777977922031376, lambda0=1.1161811384161209)
#: frictionless displacement control: f_min and the turning point lie between delamination rows
#: (0.02 off on 10 rows)
FRICTIONLESS_FLAT = dict(control="displacement", slip="frictionless", p=0.6150567159181977,
                         w=0.00041213209912865787, rs=30.421139871554356, delta_max=0.42380487719640314,
                         lambda0=1.2675883416512475)
#: no slip, displacement control: the turning point off by 0.063 on 10 rows
NO_SLIP_TURN = dict(control="displacement", slip="no-slip", p=0.539319772226521, w=9.761960739042847,
                    rs=0.8030605014275229, a_max=0.25872163569510015, lambda0=2.256852277099529)

SCENES = [COARSE_TURN, TURN_BEFORE_END, FIRST_ROW_PAST_END, FIRST_STEP_SPLIT, TINY_FIRST_ROW,
          FRICTIONLESS_FLAT, NO_SLIP_TURN]
IDS = ["coarse-turn", "turn-before-end", "first-row-past-end", "first-step-split", "tiny-first-row",
       "frictionless-flat", "no-slip-turn"]


def _outcome(sc, n):
    try:
        return adhfit.simulate(**sc, points=n, membrane="exact")
    except AdhfitError as e:
        return type(e).__name__


def _values(summary):
    out = {"f_max": summary["f_max"]}
    for k in KEYS:
        for q in ("f", "p", "a"):
            out[f"{k}.{q}"] = summary[k][q]
    return out


@pytest.mark.parametrize("scene", SCENES, ids=IDS)
def test_summary_is_the_same_at_every_row_count(scene):
    ref = _outcome(scene, 1001)
    for n in GRIDS:
        got = _outcome(scene, n)
        if isinstance(ref, str) or isinstance(got, str):
            assert got == ref, (n, got, ref)
            continue
        a, b = _values(got.summary), _values(ref.summary)
        for k in a:
            assert a[k] == pytest.approx(b[k], abs=1e-8, rel=0), (n, k)


def locate(scene, which, ref_state):
    """The extremum ``which`` (``"f_min"`` or ``"turning_point"``) on the delamination stage near the
    reported state ``ref_state``, independently: 25 states solved to 1e-13 at Chebyshev points of a
    window of 2e-3 onset rho_a about it, a Chebyshev fit of the observable, the root of its derivative;
    the state there. None when the minimum lies at the window's edge (an end of the branch)."""
    c = prepare(scene["control"], scene["slip"], scene.get("p"), scene.get("d"), scene["w"], scene["rs"],
                scene["lambda0"], scene.get("a_max"), scene.get("delta_max"), scene.get("p_max"), 200, 8)
    cfg = Config(c.lambda0, c.crv, c.n)
    _, m = H._loading(cfg, c)
    _, on = H._pinning(cfg, c, m)
    stage = delamination(cfg, c.control, c.slip, m, c.w, c.p, c.d)
    if which == "f_min":
        obs = lambda s: s.f  # noqa: E731
    elif c.control == "displacement":
        obs = lambda s: -s.d  # noqa: E731
    else:
        obs = lambda s: s.p  # noqa: E731
    half = 1e-3 * on.rho_a
    x0 = ref_state.rho_a
    nodes = x0 + half * np.cos(np.pi * (np.arange(25) + 0.5) / 25)
    order = np.argsort(np.abs(nodes - x0))
    sts, x = {}, stage.x(ref_state)
    for i in order:  # outward from the reported state, each from the nearest solved one
        near = min(sts, key=lambda q: abs(q - nodes[i])) if sts else None
        guess = stage.x(sts[near]) if near is not None else x
        sts[nodes[i]] = stage.solve(nodes[i], guess, tol=1e-13)
    t = (nodes - x0) / half
    y = np.array([obs(sts[v]) for v in nodes])
    cheb = np.polynomial.chebyshev.Chebyshev.fit(t, y, 20)
    roots = cheb.deriv().roots()
    roots = roots[np.isreal(roots)].real
    roots = roots[np.abs(roots) < 0.9]
    if not roots.size:
        return None
    r = roots[np.argmin(cheb(roots))]
    v = x0 + half * r
    near = min(sts, key=lambda q: abs(q - v))
    return stage.solve(v, stage.x(sts[near]), tol=1e-13)


@pytest.mark.parametrize("scene", [COARSE_TURN, TURN_BEFORE_END, FRICTIONLESS_FLAT, NO_SLIP_TURN],
                         ids=["coarse-turn", "turn-before-end", "frictionless-flat", "no-slip-turn"])
def test_summary_extrema_agree_with_an_independent_location(scene):
    res = {n: H.exact_history(**scene, points=n) for n in (10, 1001)}
    hist = res[1001]
    for which in ("f_min", "turning_point"):
        s = hist.summary[which]
        ref_state = min(hist.states, key=lambda st: abs(st.a - s["a"]) + abs(st.f - s["f"]))
        if ref_state.rho_a <= 0.0 or ref_state.G < scene["w"] * (1 - 1e-9):
            continue  # on pinning or loading: not this check's stage
        st = locate(scene, which, ref_state)
        if st is None:
            continue
        for n, r in res.items():
            got = r.summary[which]
            assert got["f"] == pytest.approx(st.f, abs=1e-8, rel=0), (n, which)
            assert got["p"] == pytest.approx(st.p, abs=1e-8, rel=0), (n, which)
            assert got["a"] == pytest.approx(st.a, abs=1e-8, rel=0), (n, which)


#: no-slip pinning continued in the control from the end of loading: alpha rises from 0.4 to 2.8 while d
#: moves by 0.05 (near a fold in d); the rows' march, evenly spaced in d, ran Newton off to alpha + 2 pi k
#: (2.4e6) and failed: one of the two ConvergenceErrors of the stress run. The rows then started from the
#: continuation that found the onset, and the history passed through pinning states with alpha down to
#: -0.015 first: the membrane beside the pinned edge turned into the substrate (inadmissible, as the
#: no-slip delamination branch's end at alpha = 0). Retracting d from the end of loading gives alpha < 0 at
#: once: the branch that presses on is the history (docs/contracts.md A2), and it turns past vertical at the
#: clamp at alpha = 0.107, G = 0.108 < w: a DomainError now (tests/test_exact_stress_seeds.py: seed 7's
#: like scene, whose pressing branch reaches w).
STEEP_CONTROL_PINNING = dict(control="displacement", slip="no-slip", p=-0.9212140191887281, w=6.845748455078082,
                             rs=0.07604898370037898, a_max=0.06722282506017598, lambda0=1.5567744192733814)


def test_pinning_rows_in_the_control_follow_a_steep_branch():
    from adhfit.errors import DomainError
    from tests.test_exact_stress_seeds import retracting_alpha_signs
    for n in (10, 50, 200):
        with pytest.raises(DomainError, match="turns past vertical at the clamp"):
            H.exact_history(**STEEP_CONTROL_PINNING, points=n)
    # independent: pinning states solved in d either side of the end of loading: alpha < 0 retracting
    alphas = retracting_alpha_signs(STEEP_CONTROL_PINNING)
    assert alphas[1e-4] < 0.0 and alphas[1e-3] < alphas[1e-4] and alphas[-1e-4] > 0.0


#: no-slip pinning continued in d stalls at alpha = 1.370 with G = 0.318 < w = 3.80: the other
#: ConvergenceError of the stress run. It is the branch's largest d (a fold in the control, alpha and G
#: peaking next to it, both falling past it): no pinned state at a larger gap and no onset of delamination.
CONTROL_FOLD = dict(control="displacement", slip="no-slip", p=-0.28816314004564436, w=3.7953424657445645,
                    rs=0.028558810004232025, a_max=0.02685813924696101, lambda0=1.1015354901724248)


def test_pinning_that_folds_in_the_control_before_the_onset_is_a_domain_error():
    from adhfit.errors import DomainError
    from tests.test_domain_exact_ends import arclength_pinning
    msgs = []
    for n in (10, 50, 200):
        with pytest.raises(DomainError) as err:
            H.exact_history(**CONTROL_FOLD, points=n)
        msgs.append(str(err.value))
    assert all("retracts the control at most to d = " in m for m in msgs)
    d_maxes = [float(m.split(" at most to d = ")[1].split()[0]) for m in msgs]
    assert max(d_maxes) - min(d_maxes) < 1e-10
    d_max = d_maxes[-1]
    # the independent branch (pseudo-arclength in (l1p, alpha), no parameter of its own to fold in):
    # d rises to the engine's d_max and falls again, G stays below w throughout
    c, path = arclength_pinning(CONTROL_FOLD, ds=0.01, steps=500)
    d = np.array([s.d for s in path])
    k = int(np.argmax(d))
    assert 0 < k < len(path) - 1 and d[-1] < d[k] - 1e-4
    assert d[k] == pytest.approx(d_max, abs=1e-5)
    assert max(s.G for s in path) < c.w
