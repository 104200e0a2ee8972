"""Exact membrane: free inflation and adhesionless making contact.

Checked against an independent high-precision solution (tests/exact_reference.py: a different
formulation, adaptive DOP853 at rtol 1e-13), against the large-stretch closed forms as lambda0 grows,
and by the energy balance d(U - PV) = -F dd.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from adhfit.exact.inflation import free_inflation
from adhfit.exact.solve import solve_state
from adhfit.exact.state import DEFAULT_N, Config
from tests import exact_reference as ref


def _closed_d0(p):
    return p / (1 + math.sqrt(1 - p * p))


@pytest.mark.parametrize("p, lambda0", [(0.6, 1.1), (0.6, 1.5), (-0.4, 1.3)])
def test_free_inflation_matches_reference(p, lambda0):
    d0_ref, lc_ref = ref.free_inflation(abs(p), lambda0)
    st = free_inflation(p, lambda0, n=64)
    assert st.d == pytest.approx(math.copysign(d0_ref, p), abs=1e-9)
    assert st.lc == pytest.approx(lc_ref, rel=1e-9)
    assert free_inflation(p, lambda0).d == pytest.approx(math.copysign(d0_ref, p), abs=1e-7)  # default n


@pytest.mark.parametrize("n", [14, 128])
def test_free_inflation_when_the_shot_at_lambda0_curls(n):
    """A high pressure at a low pre-stretch (p = 0.676, lambda0 = 1.1: a fit's trial point): the shot
    at lc = lambda0, the bracket's lower end, curls through the axis (r(beta) - 1 = +35 at n = 14, NaN
    at 128), which used to read as 'no Case I state'; the state exists (theta at the clamp ~1.08)."""
    d0_ref, lc_ref = ref.free_inflation(0.675792865403995, 1.1)
    st = free_inflation(0.675792865403995, 1.1, n=n)
    assert st.lc == pytest.approx(lc_ref, rel=1e-8)
    assert st.d == pytest.approx(d0_ref, abs=1e-8)


@pytest.mark.parametrize("guess", [1.68, 1.05, 10.0])  # near; far (secant fails: bracketing)
def test_free_inflation_from_a_guess_against_reference(guess):
    """Continuation (compiled secant iterations from a guess, bracketing when they fail or land
    outside Case I) finds the reference's Case I state from near and far guesses."""
    d0_ref, lc_ref = ref.free_inflation(0.6, 1.5)
    memo: dict = {}
    for _ in range(2):  # the second call starts from the slope the first one left in memo
        st = free_inflation(0.6, 1.5, n=64, lc_guess=guess, memo=memo)
        assert st.lc == pytest.approx(lc_ref, rel=1e-9)
        assert st.d == pytest.approx(d0_ref, abs=1e-9)
        assert st.theta_end < 0.5 * math.pi


def test_free_inflation_design_numbers():
    # docs/numerics.md B5: (approximation - exact)/exact of the apex deflection at p = 0.6
    expected = {1.1: -0.33, 1.3: -0.15, 1.5: -0.067, 2.0: -0.012, 3.0: -0.001}
    for lam0, err in expected.items():
        exact = free_inflation(0.6, lam0).d
        assert (_closed_d0(0.6) - exact) / exact == pytest.approx(err, abs=0.006 if lam0 < 1.4 else 0.0006)


def test_free_inflation_converges_to_closed_form():
    errs = [abs(free_inflation(0.6, lam0).d - _closed_d0(0.6)) for lam0 in (3.0, 6.0, 12.0)]
    # the neglected terms are O(lambda^-6) relative to O(1): each doubling divides by >= 32
    assert errs[1] < errs[0] / 32 and errs[2] < errs[1] / 32
    assert errs[2] < 1e-7


def test_step_halving():
    vals = [free_inflation(0.6, 1.2, n=n).d for n in (16, 32, 64, 128)]
    assert abs(vals[2] - vals[3]) < 1e-10
    assert abs(vals[1] - vals[3]) > abs(vals[2] - vals[3])


@pytest.mark.parametrize("rs", [0.5, math.inf])
def test_making_contact_matches_reference(rs):
    p, lam0, rho_a = 0.6, 1.2, 0.1
    a, d, f = ref.making_contact(p, lam0, rs, rho_a)
    cfg = Config(lam0, 0.0 if math.isinf(rs) else 1 / rs, 64)
    fi = free_inflation(p, lam0)
    st = solve_state(cfg, "continuous", {"p": p, "rho_a": rho_a}, ("lc",), (fi.lc,), ("clamp",), {})
    assert st.a == pytest.approx(a, abs=1e-9)
    assert st.d == pytest.approx(d, abs=1e-9)
    assert st.f == pytest.approx(f, abs=1e-9)


def test_making_contact_converges_to_large_stretch():
    # large-stretch making contact at p = 0.6, rs = 0.5, a = 0.25 (paper eqs. 25-26; closed form
    # values from the large-stretch engine of adhfit.core: f = 0.5105088062, d = -0.0081858...)
    p, rs, a = 0.6, 0.5, 0.25
    f_ls = math.pi * a * a * p * (1 + 1 / (p * rs))  # eq. (26)
    errs = []
    for lam0 in (5.0, 10.0):
        fi = free_inflation(p, lam0)
        st = solve_state(Config(lam0, 1 / rs), "continuous", {"p": p}, ("lc", "rho_a"), (fi.lc, a / fi.lc),
                         ("clamp", "a"), {"a": a})
        errs.append(abs(st.f - f_ls))
    assert errs[0] < 1e-4 and errs[1] < errs[0] / 20


@pytest.mark.parametrize("rs", [0.5, math.inf])
def test_making_contact_energy_balance(rs):
    # a central difference over 2e-4 in rho_a amplifies the quadratures' discretization error ~1e4-fold:
    # the balance (a check of the equations, not of the default mesh) is taken at n = 16
    p, lam0, n = 0.6, 1.2, 16
    cfg = Config(lam0, 0.0 if math.isinf(rs) else 1 / rs, n)
    fi = free_inflation(p, lam0, n)

    def at(rho_a):
        return solve_state(cfg, "continuous", {"p": p, "rho_a": rho_a}, ("lc",), (fi.lc,), ("clamp",), {})

    h = 1e-4
    sp, sm, s0 = at(0.12 + h), at(0.12 - h), at(0.12)
    # U/(mu h b^2) - (P b/mu h) V/b^3 against F dd/(mu h b^2) = 2 f dd
    dE = (sp.u - 2 * p * sp.v) - (sm.u - 2 * p * sm.v)
    assert dE / (sp.d - sm.d) == pytest.approx(-2 * s0.f, rel=1e-6)


@pytest.mark.parametrize("lambda0, lo, hi", [(1.5, 0.2, 0.94), (1.1, -0.21, 0.27), (3.0, 0.23, 0.987)])
def test_free_curve_matches_direct_solves(lambda0, lo, hi):
    """d0(p) interpolated from free inflation at 20 apex stretches (pressure-control delta) against one
    Newton solve per pressure: ranges up to the free-inflation pressure maximum's neighbourhood
    (lambda0 = 3, p -> 0.987, where a polynomial in p itself is off by ~2e-5) and through p = 0."""
    from adhfit.exact.inflation import free_curve
    p = np.linspace(lo, hi, 41)
    ends = [free_inflation(hi, lambda0), free_inflation(lo, lambda0)]
    d0 = free_curve(p, ends, lambda0)
    sols = [free_inflation(q, lambda0) for q in p]
    direct = np.array([s.d for s in sols])
    # 1e-10: the accepted difference (adhfit.exact.control.D0_CHECK); ~5e-12 through p = 0, 3e-14 otherwise
    assert np.max(np.abs(d0 - direct)) < 1e-10
    # the apex stretch at the same roots (the start of control's check solves): same d0, and lc close
    # to the direct solves' (d0 is smooth in lc: 1e-8 leaves the check solve one secant step)
    d0s, lc = free_curve(p, ends, lambda0, with_stretch=True)
    assert np.array_equal(d0s, d0)
    assert np.max(np.abs(lc - np.array([s.lc for s in sols]))) < 1e-8


@pytest.mark.parametrize("d, lambda0", [(0.2, 1.1), (0.2, 1.5), (-0.05, 1.1), (0.4, 3.0), (0.01, 1.2)])
def test_free_state_at_a_gap(d, lambda0):
    """Pressure control starts at the free state with apex deflection d: Newton on (lc, p) from the
    large-stretch cap agrees with the root search in p (free inflation at each p), and at n = 64 its
    pressure inflates the independent reference to the same apex deflection."""
    from adhfit.exact.control import _free_at_gap, _gap_bracketed, _gap_newton
    st = _gap_newton(d, lambda0, 14)
    assert st is not None
    old = _gap_bracketed(d, lambda0, 14)
    assert (st.p, st.lc, st.d) == pytest.approx((old.p, old.lc, d), abs=1e-11)
    st = _free_at_gap(d, lambda0, 64)
    d0_ref, lc_ref = ref.free_inflation(abs(st.p), lambda0)
    assert math.copysign(d0_ref, d) == pytest.approx(d, abs=1e-9)
    assert st.lc == pytest.approx(lc_ref, rel=1e-9)


@pytest.mark.parametrize("lambda0, lo, hi", [(1.1, -0.64, 0.27), (1.2, -0.25, 0.82), (1.5, 0.2, 0.94),
                                             (2.0, -0.25, 0.72), (3.0, -0.12, 0.987)])
def test_scaled_d0_curve_matches_direct_solves(lambda0, lo, hi):
    """The pressure-control d0(p) (nodes by the scaling symmetry, p interpolated in d0, ``checked_curve``)
    against free inflation solved at each pressure by the bracketing root search (no start from the
    curve): within control.D0_CHECK = 1e-10 on every row. Ranges through p = 0 (at lambda0 = 1.1 wide
    enough that 20 nodes are off by 2e-9 and the curve is refined) and up to the pressure maximum."""
    from adhfit.exact import scaled
    from adhfit.exact.control import CHECK_MARGIN, D0_CHECK
    from adhfit.exact.inflation import checked_curve
    p = np.linspace(lo, hi, 61)
    ends = [free_inflation(hi, lambda0), free_inflation(lo, lambda0)]
    direct = np.array([free_inflation(q, lambda0).d for q in p])
    d0 = checked_curve(p, ends, lambda0, np.array([3, 15, 30, 45, 57]), CHECK_MARGIN * D0_CHECK, D0_CHECK)
    assert d0 is not None  # each of these passes its checks (else this test would check nothing)
    assert np.max(np.abs(d0 - direct)) <= D0_CHECK
    # one node by the scaling symmetry: the state at its own pressure is the directly solved one
    lc = free_inflation(0.5 * (lo + hi), lambda0).lc
    q, d, theta = scaled.free_at_stretch(lc, lambda0, DEFAULT_N, 1.1 * abs(0.5 * (lo + hi)))
    st = free_inflation(q, lambda0)
    assert (d, theta, lc) == pytest.approx((st.d, st.theta_end, st.lc), abs=1e-11)


@pytest.mark.parametrize("lambda0, d, lo, hi", [(1.1, -0.05, -0.64, 0.27), (1.5, 0.2, 0.2, 0.94),
                                                (3.0, 0.2, -0.12, 0.987)])
def test_pressure_control_d0_from_the_touching_state(lambda0, d, lo, hi):
    """``Control._d0_curve`` as a history calls it: the curve's ends found as nodes beyond the rows'
    pressures from the free state at the gap d (``scaled.end_node``), d0 within 1e-10 of free inflation
    solved at each pressure by the bracketing root search."""
    from adhfit.exact.control import D0_CHECK, prepare
    c = prepare("pressure", "frictionless", None, d, 0.2, 0.5, lambda0, 0.25, None, None, 200, DEFAULT_N)
    assert lo < c.free.p < hi
    p = np.concatenate([np.linspace(lo, hi, 60), [c.free.p]])
    ends = c._node_ends(lo, hi)  # found from the free state (not the fallback of solves at lo, hi)
    assert ends is not None and ends[0].p >= hi and ends[1].p <= lo
    d0 = c._d0_curve(p)
    assert d0 is not None
    direct = np.array([free_inflation(q, lambda0).d for q in p])
    assert np.max(np.abs(d0 - direct)) <= D0_CHECK
    assert d0[-1] == pytest.approx(c.free.d, abs=D0_CHECK)


@pytest.mark.parametrize("lambda0, d", [(1.775, 0.2178), (1.1, 0.1), (2.5, 0.1), (1.3, -0.05)])
def test_case_one_limit_between_direct_solves(lambda0, d):
    """The largest |p| with a Case I free state (``control.case_one_limit``, from scaled shots along the
    branch) against the bracketing solver of ``free_inflation``: a Case I state 1 % below it, none 1 %
    above (closer in, the bracketing solver can step over the two roots near the limit)."""
    from adhfit.errors import ConvergenceError
    from adhfit.exact.control import case_one_limit, prepare
    c = prepare("pressure", "frictionless", None, d, 0.2, 0.5, lambda0, 0.25, None, None, 200, DEFAULT_N)
    limit = case_one_limit(c.lambda0, c.n, c.free)
    assert limit is not None and 0.5 < limit < 1.01
    st = free_inflation(0.99 * limit, lambda0)
    assert 0.0 < st.theta_end < 0.5 * math.pi
    with pytest.raises(ConvergenceError):
        free_inflation(1.01 * limit, lambda0)
