"""Stress-seed scenes of the exact membrane (issue 24: seeds 3, 7, 11, 24), each one's fix checked
independently of the code under test where possible (another row grid, the branch's own states, the
analytic identity of the contact force)."""
import math

import numpy as np
import pytest

import adhfit
from adhfit.errors import ConvergenceError, DomainError
from adhfit.exact import kernels as K
from adhfit.exact.history import exact_history

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
    from adhfit.exact.control import prepare
    from adhfit.exact.history import _loading
    from adhfit.exact.stages import Stage
    from adhfit.exact.state import Config
    sc = SLACK[name]
    for n in GRIDS:
        with pytest.raises(DomainError, match="slack"):
            exact_history(**sc, points=n)
    c = prepare(sc["control"], sc["slip"], None, sc["d"], sc["w"], sc["rs"], sc["lambda0"], sc["a_max"],
                None, None, 50, 8)
    cfg = Config(c.lambda0, c.crv, c.n)
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
