"""An independent high-precision solution of the exact neo-Hookean membrane, for tests only.

Formulated differently from adhfit.exact on purpose: adaptive scipy DOP853 at rtol 1e-13 in the
material coordinate, the tangential equilibrium carried as Q = T1 r / (mu h) (eq. 4: dQ/drho =
T2 dr/drho), lambda1 recovered from Q by a scalar root solve at every evaluation, a leading-order
apex start at rho = 1e-7 beta and brentq on the centre stretch.
"""
from __future__ import annotations

import math

from scipy.integrate import solve_ivp
from scipy.optimize import brentq

RTOL, ATOL = 1e-13, 1e-15


def _t(l1, l2):
    j = (l1 * l2) ** -3
    return l1 / l2 - j, l2 / l1 - j


def _l1_of(t1, l2, guess):
    """Invert t1(l1, l2) for l1 (monotone increasing)."""
    lo, hi = 1e-3, max(4 * guess, 10.0)
    while _t(hi, l2)[0] < t1:
        hi *= 2
    return brentq(lambda x: _t(x, l2)[0] - t1, lo, hi, xtol=1e-16, rtol=1e-15)


def _free_rhs(p):
    def f(rho, y):
        r, z, th, q = y
        l2 = r / rho
        l1 = _l1_of(q / r, l2, l2)
        t1, t2 = _t(l1, l2)
        c, s = math.cos(th), math.sin(th)
        return [l1 * c, l1 * s, l1 * (2 * p - t2 * s / r) / t1, t2 * l1 * c]
    return f


def _contact_rhs(crv):
    def f(rho, y):
        r, q = y
        l2 = r / rho
        l1 = _l1_of(q / r, l2, l2)
        t2 = _t(l1, l2)[1]
        c = math.sqrt(1 - (r * crv) ** 2)
        return [l1 * c, t2 * l1 * c]
    return f


def _free_end(p, y0, rho0, beta):
    sol = solve_ivp(_free_rhs(p), (rho0, beta), y0, method="DOP853", rtol=RTOL, atol=ATOL)
    return sol.y[:, -1]


def free_inflation(p, lambda0):
    """(d0, lc) of Case I free inflation."""
    beta = 1 / lambda0
    rho0 = 1e-7 * beta

    def end(lc):
        k = lc * p / (1 - lc ** -6)
        t = _t(lc, lc)[0]
        return _free_end(p, [lc * rho0, 0.5 * lc * k * rho0 ** 2, k * rho0, t * lc * rho0], rho0, beta)

    hi = lambda0 * 1.05
    while end(hi)[0] < 1:
        hi *= 1.2
    lc = brentq(lambda x: end(x)[0] - 1, lambda0, hi, xtol=1e-15, rtol=1e-15)
    return end(lc)[1], lc


def making_contact(p, lambda0, rs, rho_a):
    """(a, d, f) of adhesionless making contact with the contact edge at material point rho_a."""
    beta = 1 / lambda0
    crv = 0.0 if math.isinf(rs) else 1 / rs
    rho0 = 1e-7 * rho_a

    def edge(lc):
        t = _t(lc, lc)[0]
        sol = solve_ivp(_contact_rhs(crv), (rho0, rho_a), [lc * rho0, t * lc * rho0], method="DOP853",
                        rtol=RTOL, atol=ATOL)
        return sol.y[:, -1]

    def end(lc):
        a, q = edge(lc)
        th = -math.asin(a * crv)
        z_a = -a * a * crv / (1 + math.sqrt(1 - (a * crv) ** 2))
        return _free_end(p, [a, z_a, th, q], rho_a, beta), a, q

    hi = lambda0 * 1.05
    while end(hi)[0][0] < 1:
        hi *= 1.2
    lc = brentq(lambda x: end(x)[0][0] - 1, lambda0 * 0.9, hi, xtol=1e-15, rtol=1e-15)
    y, a, q = end(lc)
    t1 = q / a
    f = math.pi * a * (a * p + t1 * a * crv)
    return a, y[1], f


def _g23(alpha, l1p, l1m, l2):
    t1p = _t(l1p, l2)[0]
    q = l1m / l1p
    return t1p * (1 - math.cos(alpha)) + 0.5 * ((l1p - l1m) ** 2 / (l1m * l2)
                                                + (1 - 3 * q * q + 2 * q ** 3) / (l1m * l2) ** 3)


def edge_state(p, lambda0, rs, lc, rho_a, alpha, edge, l1p=None):
    """(r_end, d, f, G) of the state with contact field centre stretch lc, edge at rho_a, contact angle
    alpha; edge 'frictionless' (T1+ cos alpha = T1-) or 'given' (lambda1+ = l1p)."""
    beta = 1 / lambda0
    crv = 0.0 if math.isinf(rs) else 1 / rs
    rho0 = 1e-7 * rho_a
    t = _t(lc, lc)[0]
    sol = solve_ivp(_contact_rhs(crv), (rho0, rho_a), [lc * rho0, t * lc * rho0], method="DOP853",
                    rtol=RTOL, atol=ATOL)
    a, q = sol.y[:, -1]
    l2 = a / rho_a
    l1m = _l1_of(q / a, l2, l2)
    if edge == "frictionless":
        l1p = _l1_of(q / a / math.cos(alpha), l2, l2)
    th = alpha - math.asin(a * crv)
    z_a = -a * a * crv / (1 + math.sqrt(1 - (a * crv) ** 2))
    t1p = _t(l1p, l2)[0]
    y = _free_end(p, [a, z_a, th, t1p * a], rho_a, beta)
    f = math.pi * a * (a * p - t1p * math.sin(th))
    return y[0], y[1], f, _g23(alpha, l1p, l1m, l2)
