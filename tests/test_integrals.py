"""The closed-form integrals (Carlson) against independent 30-digit quadrature of their definitions.

The compiled scalar kernels of :mod:`adhfit.core.membrane` are called directly (numba dispatchers
run from Python); also R_F and R_D themselves against scipy's (SciPy/Carlson reference values).
"""
from __future__ import annotations

import math

import mpmath as mp
import numpy as np
import pytest

from scipy.special import elliprd, elliprf

from adhfit.core.membrane import integrals, roots
from adhfit.core.special import carlson_rd, carlson_rf


def free_membrane_integrals(kappa, D, C2, a, q_edge, through):
    """J0, J1 row by row from the compiled kernel (arrays broadcast)."""
    rows = np.broadcast_arrays(*(np.asarray(v, float) for v in (kappa, D, C2, a, q_edge)))
    out = [integrals(*(float(v[i]) for v in rows), bool(through), True)[:2]
           for i in np.ndindex(rows[0].shape)]
    j0, j1 = (np.array([o[k] for o in out]).reshape(rows[0].shape) for k in (0, 1))
    return j0, j1


def quadratic_roots(kappa, D, C2):
    return roots(float(kappa), float(D), float(C2))


def _quad(kappa, D, C2, lo, hi):
    with mp.workdps(30):
        k, D, C2 = mp.mpf(kappa), mp.mpf(D), mp.mpf(C2)
        lo = mp.mpf(lo)
        Q = lambda r: (r * r + C2) - (k * r * r + D) ** 2  # noqa: E731
        j0 = mp.quad(lambda r: 1 / mp.sqrt(Q(r)), [lo, hi])
        j1 = mp.quad(lambda r: (k * r * r + D) / mp.sqrt(Q(r)), [lo, hi])
        return float(j0), float(j1)


def _edge(kappa, D, C2, a):
    return (a * a + C2) - (kappa * a * a + D) ** 2


CASES = [  # kappa, D, C2, a: making contact, frictionless, p < 0, p = 0, flat, near-vertical edge
    (0.6, -(0.6 + 2.0) * 0.25**2, 0.0, 0.25),
    (0.6, 0.25 * np.sqrt(1 - 0.25) * np.tan(0.5) - 2.6 * 0.0625, (0.25 * np.tan(0.5)) ** 2, 0.25),
    (-0.3, -(-0.3 + 1.0) * 0.16, 0.0, 0.4),
    (0.0, -2.0 * 0.0625, 0.0, 0.25),
    (0.9, -0.9 * 0.09, 0.0, 0.3),
    (0.2, 0.01, 0.02, 0.3),
]


@pytest.mark.parametrize("kappa,D,C2,a", CASES)
def test_ordinary_path_matches_quadrature(kappa, D, C2, a):
    j0, j1 = free_membrane_integrals(kappa, D, C2, a, _edge(kappa, D, C2, a), False)
    r0, r1 = _quad(kappa, D, C2, a, 1.0)
    assert j0 == pytest.approx(r0, rel=1e-13, abs=1e-14)
    assert j1 == pytest.approx(r1, rel=1e-13, abs=1e-14)


def test_through_root_path_matches_quadrature():
    """theta_a > pi/2 (eqs. 42, 47): sum of the integrals over [eta, a] and [eta, 1], eta^2 = u_minus."""
    kappa, C2, a = -1.5, 0.05, 0.4
    # choose D so that sin(theta) at r = a is 0.9 with the edge tangent past vertical
    D = 0.9 * np.sqrt(a * a + C2) - kappa * a * a
    q, um = quadratic_roots(kappa, D, C2)
    assert 0 < um < a * a
    j0, j1 = free_membrane_integrals(kappa, D, C2, a, _edge(kappa, D, C2, a), True)
    with mp.workdps(30):  # the root itself at 30 digits: a rounded eta truncates the 1/sqrt singularity
        k, Dm, C2m = mp.mpf(kappa), mp.mpf(D), mp.mpf(C2)
        B, C = 1 - 2 * k * Dm, C2m - Dm**2
        eta = mp.sqrt((B - mp.sqrt(B * B + 4 * k * k * C)) / (2 * k * k))
        r0a, r1a = _quad(kappa, D, C2, eta, a)
        r0b, r1b = _quad(kappa, D, C2, eta, 1.0)
    assert j0 == pytest.approx(r0a + r0b, rel=1e-12)
    assert j1 == pytest.approx(r1a + r1b, rel=1e-12)


def test_continuous_through_zero_pressure():
    """The root formulas never divide by kappa: J0, J1 are smooth through kappa = 0."""
    a, c = 0.3, 1.0
    ks = np.array([-1e-9, 0.0, 1e-9])
    D = -(ks + c) * a * a
    j0, j1 = free_membrane_integrals(ks, D, 0 * ks, a, _edge(ks, D, 0 * ks, a), False)
    assert np.all(np.isfinite(j0)) and np.all(np.isfinite(j1))
    assert np.ptp(j0) < 1e-8 and np.ptp(j1) < 1e-8


@pytest.mark.parametrize("x,y,z", [(1.0, 2.0, 3.0), (0.5, 1e-8, 7.0), (2.0, 2.0, 2.0), (1e-3, 1.0, 1e3),
                                   (0.0, 1.0, 2.0)])
def test_carlson_kernels_match_scipy(x, y, z):
    """The compiled duplication series against scipy.special (independent implementation)."""
    assert carlson_rf(x, y, z) == pytest.approx(float(elliprf(x, y, z)), rel=4e-15)
    if z > 0:
        assert carlson_rd(x, y, z) == pytest.approx(float(elliprd(x, y, z)), rel=4e-15)
    assert math.isnan(carlson_rf(-1.0, y, z))
