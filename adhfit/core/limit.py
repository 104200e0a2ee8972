"""Where a branch leaves Case I: the clamp tangent turns vertical, |sin theta(1)| = 1 (B1, B5).

A continuation that stalls on a state at that limit has met the end of the model, not a solver
failure: past it the membrane would turn past vertical at the clamp (Case II, which the model, as
the paper, leaves out). :func:`case_one_end` confirms such a stall by a second, independent method:
it solves for the limit state directly, on the limit itself, where the equations are smooth, and
where that state lies farther from the stall than a tangential approach leaves (AGREE), follows the
branch on from the stall to it in sqrt(1 - |sin theta(1)|) (:func:`_bridged`).

On the limit, sin theta(1) = (kappa + D)/sqrt(1 + C2) = sigma (+-1) fixes the pressure explicitly
(D = D0 - kappa a^2 on every branch), Q(r) = kappa^2 (1 - r^2)(r^2 - u_minus) has its root at the
clamp, and the two integrals are taken by adaptive quadrature with the algebraic endpoint weights
(``scipy.integrate.quad``; not the closed forms the engine uses). The unknowns are the branch's
locator and, on an implicit branch, its unknown x; the equations are the material condition (implicit
branches), the gap (pressure control) and, under displacement control, the fixed pressure.
Python and scipy: it runs only on the way to an error.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .branches import CLAMP_NEAR, is_implicit, material_target, state, unpack
from .membrane import substrate_cos

__all__ = ["NEAR", "CaseOneEnd", "clamp_sine", "case_one_end", "EQUATOR_NEAR", "EquatorEnd", "equator_end"]

#: a stalled state within this of |sin theta(1)| = 1 is taken to the limit solve
NEAR = CLAMP_NEAR
#: the limit solve confirms the stall when its locator is within this (relative) of the stall's.
#: Where the branch meets the limit tangentially (1 - |sin theta(1)| falling as the square of the
#: distance, seen in the issue-24 stress run) the continuation stalls at 1 - |sin theta(1)| ~ 1e-9,
#: up to 8e-5 short of the limit in the locator; transversally, within ~1e-8
AGREE = 2e-4
_QUAD = dict(epsabs=1e-13, epsrel=1e-13, limit=200)


@dataclass(frozen=True)
class CaseOneEnd:
    """The state where a branch reaches the Case I limit.

    Attributes
    ----------
    loc, x, kappa : float
        Locator, unknown (NaN on an explicit branch) and pressure of the limit state.
    sigma : float
        sin theta at the clamp there (+1 or -1).
    residual : float
        Largest residual of the limit equations at the solution.
    bridged : bool
        The limit state lies farther than AGREE from the stall and the branch was followed on from
        the stall to it (:func:`_bridged`).
    """

    loc: float
    x: float
    kappa: float
    sigma: float
    residual: float
    bridged: bool = False


def clamp_sine(code: int, x: float, kappa: float, loc: float, c: float, w: float, a_m: float) -> float:
    """sin theta at the clamp, (kappa + D)/sqrt(1 + C2), of one state (NaN if not finite)."""
    _, _, D, C2, _ = unpack(code, x, kappa, loc, c, w, a_m)
    return float((kappa + D) / math.sqrt(1.0 + C2))


def _limit_kappa(code, x, loc, c, w, a_m, sigma):
    """The pressure that puts the clamp tangent at sin theta(1) = sigma, with D0, C2, a, alpha."""
    a, alpha, D0, C2, _ = (float(v) for v in unpack(code, x, 0.0, loc, c, w, a_m))
    kappa = (sigma * math.sqrt(1.0 + C2) - D0) / (1.0 - a * a)
    return kappa, D0 - kappa * a * a, C2, a, alpha


def _integrals(kappa, D, C2, a, through):
    """J0 and J1 from the contact edge to the clamp on the limit (quad, algebraic weights)."""
    from scipy.integrate import quad  # noqa: PLC0415 - only on the way to an error

    um = (D * D - C2) / (kappa * kappa)
    k = abs(kappa)
    if not through:
        # 1/sqrt(Q) = (1 - r)^(-1/2) / (|kappa| sqrt((1 + r)(r^2 - u_minus)))
        g0 = lambda r: 1.0 / (k * math.sqrt((1.0 + r) * (r * r - um)))  # noqa: E731
        g1 = lambda r: (kappa * r * r + D) * g0(r)  # noqa: E731
        w_ = dict(weight="alg", wvar=(0.0, -0.5))
        return quad(g0, a, 1.0, **w_, **_QUAD)[0], quad(g1, a, 1.0, **w_, **_QUAD)[0]
    # theta_a > pi/2: r runs from a down to eta = sqrt(u_minus), then up to the clamp
    eta = math.sqrt(um)
    h0 = lambda r: 1.0 / (k * math.sqrt((1.0 - r * r) * (r + eta)))  # noqa: E731
    h1 = lambda r: (kappa * r * r + D) * h0(r)  # noqa: E731
    e0 = lambda r: 1.0 / (k * math.sqrt((1.0 + r) * (r + eta)))  # noqa: E731
    e1 = lambda r: (kappa * r * r + D) * e0(r)  # noqa: E731
    lo, both = dict(weight="alg", wvar=(-0.5, 0.0)), dict(weight="alg", wvar=(-0.5, -0.5))
    j0 = quad(h0, eta, a, **lo, **_QUAD)[0] + quad(e0, eta, 1.0, **both, **_QUAD)[0]
    j1 = quad(h1, eta, a, **lo, **_QUAD)[0] + quad(e1, eta, 1.0, **both, **_QUAD)[0]
    return j0, j1


def _equations(z, code, pressure, c, w, a_m, L_m, d_fix, kappa_dc, sigma, x_fixed):
    implicit = is_implicit(code)
    x, loc = (z[0], z[1]) if implicit else (x_fixed, z[0])
    kappa, D, C2, a, alpha = _limit_kappa(code, x, loc, c, w, a_m, sigma)
    cos_ta = substrate_cos(a, c) * math.cos(alpha) + a * c * math.sin(alpha)
    j0, j1 = _integrals(kappa, D, C2, a, cos_ta < 0.0)
    out = []
    if implicit:
        out.append(j0 - float(material_target(code, loc, c, a_m, L_m)))
    if pressure:
        out.append(j1 - a * a * c / (1.0 + substrate_cos(a, c)) - d_fix)
    else:
        out.append(kappa - kappa_dc)
    return np.array(out), kappa


def case_one_end(code: int, pressure: bool, x0: float, kappa0: float, loc0: float, c: float, w: float,
                 a_m: float, L_m: float, d_fix: float) -> CaseOneEnd | None:
    """The Case I limit of a branch near a stalled state, solved on the limit itself.

    Parameters
    ----------
    code : int
        Branch code (:mod:`.branches`).
    pressure : bool
        Pressure control (the gap ``d_fix`` holds) or displacement control (``kappa0`` holds).
    x0, kappa0, loc0 : float
        The last state the continuation accepted (``x0`` NaN on an explicit branch).
    c, w, a_m, L_m : float
        Substrate curvature, work of adhesion, end of loading and its J0.
    d_fix : float
        The fixed gap (pressure control).

    Returns
    -------
    CaseOneEnd or None
        The limit state when the stalled state lies within NEAR of the limit and the limit
        equations solve within AGREE of it, or farther along a branch followed from the stall to it
        (:func:`_bridged`); else None (the stall is not shown to be the model's end).
    """
    from scipy.optimize import root  # noqa: PLC0415 - only on the way to an error

    if not all(math.isfinite(v) for v in (kappa0, loc0)):
        return None
    s = clamp_sine(code, x0, kappa0, loc0, c, w, a_m)
    if not (math.isfinite(s) and 1.0 - abs(s) <= NEAR):
        return None
    sigma = math.copysign(1.0, s)
    implicit = is_implicit(code)
    if implicit and not math.isfinite(x0):
        return None
    z0 = np.array([x0, loc0]) if implicit else np.array([loc0])
    args = (code, pressure, c, w, a_m, L_m, d_fix, kappa0, sigma, x0)
    try:
        sol = root(lambda z: _equations(z, *args)[0], z0, method="hybr", options={"xtol": 1e-13})
        res, kappa = _equations(sol.x, *args)
    except (ValueError, ZeroDivisionError, OverflowError):
        return None
    loc = float(sol.x[-1])
    if not (np.all(np.isfinite(res)) and float(np.max(np.abs(res))) <= 1e-9):
        return None
    far = abs(loc - loc0) > AGREE * max(1.0, abs(loc0))
    if far and not _bridged(z0, sol.x, 1.0 - abs(s), code, pressure, c, w, a_m, L_m, d_fix, kappa0,
                            sigma):
        return None
    # the limit state is a state of the model (Case I to rounding, Q >= 0 at the contact edge)
    x = float(sol.x[0]) if implicit else math.nan
    ok = state(code, x if implicit else 0.0, kappa, loc, c, w, a_m, False)[6]
    if not ok and not _edge_ok(code, x, kappa, loc, c, w, a_m):
        return None
    return CaseOneEnd(loc=loc, x=x, kappa=float(kappa), sigma=sigma, residual=float(np.max(np.abs(res))),
                      bridged=far)


#: steps of :func:`_bridged` in sqrt(1 - |sin theta(1)|), from the stalled state to the limit
BRIDGE_STEPS = 40


def _off_limit(z, code, pressure, c, w, a_m, L_m, d_fix, kappa_dc, sine, x_fixed):
    """The branch's equations at a state whose clamp sine is ``sine`` (|sine| < 1): the pressure
    from the sine, as on the limit (:func:`_limit_kappa`), the integrals by the engine's closed
    forms (``branches.state``); NaN outside the model."""
    implicit = is_implicit(code)
    x, loc = (z[0], z[1]) if implicit else (x_fixed, z[0])
    kappa = _limit_kappa(code, x, loc, c, w, a_m, sine)[0]
    st = state(code, x if implicit else 0.0, kappa, loc, c, w, a_m, True)
    if not st[6]:
        return np.full(len(z), np.nan)
    out = []
    if implicit:
        out.append(float(st[5]) - float(material_target(code, loc, c, a_m, L_m)))
    out.append(float(st[2]) - d_fix if pressure else kappa - kappa_dc)
    return np.array(out)


def _bridged(z0, z_lim, margin0, code, pressure, c, w, a_m, L_m, d_fix, kappa_dc, sigma):
    """Whether the branch runs on from the stalled state ``z0`` (clamp margin ``margin0``) to the
    limit state ``z_lim`` found farther than AGREE from it.

    Where the branch meets the limit tangentially, 1 - |sin theta(1)| falls as the square of the
    distance to it and a continuation in the locator can stall well short of it (issue-24 stress
    scene: no-slip pinning under pressure control stalled at 1.3e-7, 2e-3 short in G). Here the
    branch is followed in q = sqrt(1 - |sin theta(1)|), in which it is smooth, from the stalled state
    down to q = 0: each state solved from the one before, extrapolated linearly (scipy's ``hybr``,
    residual <= 1e-9), the locator moving one way only, toward the limit state, which the last
    states must extrapolate to within 1e-6 (relative). A root that jumps or a failed solve is no
    bridge: the stall then stays unproven."""
    from scipy.optimize import root  # noqa: PLC0415 - only on the way to an error

    q0 = math.sqrt(max(margin0, 0.0))
    if not q0 > 0:
        return False
    qs = q0 * (1.0 - np.arange(1, BRIDGE_STEPS) / BRIDGE_STEPS)
    zs, q_prev = [np.asarray(z0, float)], q0
    direction = math.copysign(1.0, z_lim[-1] - z0[-1])
    for q in qs:
        guess = zs[-1] if len(zs) < 2 else zs[-1] + (zs[-1] - zs[-2]) * (q - q_prev) / step_prev
        args = (code, pressure, c, w, a_m, L_m, d_fix, kappa_dc, sigma * (1.0 - q * q),
                z0[0] if is_implicit(code) else math.nan)
        try:
            sol = root(lambda z: _off_limit(z, *args), guess, method="hybr", options={"xtol": 1e-13})
            r = _off_limit(sol.x, *args)
        except (ValueError, ZeroDivisionError, OverflowError):
            return False
        if not (np.all(np.isfinite(r)) and float(np.max(np.abs(r))) <= 1e-9):
            return False
        if (sol.x[-1] - zs[-1][-1]) * direction < 0:
            return False  # the locator turned back: not the way to the limit state
        step_prev = q - q_prev
        zs.append(sol.x)
        q_prev = q
    # the last two states, linear in q, reach the limit state at q = 0
    z_end = zs[-1] + (zs[-1] - zs[-2]) * (0.0 - q_prev) / step_prev
    scale = np.maximum(1.0, np.abs(z_lim))
    return bool(np.all(np.abs(z_end - np.asarray(z_lim)) <= 1e-6 * scale))


def _edge_ok(code, x, kappa, loc, c, w, a_m):
    """The state a hair inside the limit is admissible (the kernel's test rounds either way on it)."""
    for k in (kappa * (1 - 1e-12), kappa * (1 + 1e-12)):
        if state(code, x if is_implicit(code) else 0.0, k, loc, c, w, a_m, False)[6]:
            return True
    return False


# ----------------------------------------------------------------------------------------------
# the sphere's equator: frictionless pinning whose contact edge reaches a = rs

#: a stalled frictionless pinning state whose contact radius lies within this (relative) of rs is
#: taken to the equator solve (the unknown a is bracketed below (1 - 1e-9) rs)
EQUATOR_NEAR = 1e-6


@dataclass(frozen=True)
class EquatorEnd:
    """The state where frictionless pinning's contact edge reaches the sphere's equator (a = rs).

    Attributes
    ----------
    loc, kappa : float
        Contact angle alpha and pressure there.
    residual : float
        Largest residual of the equations at the solution.
    """

    loc: float
    kappa: float
    residual: float


def equator_end(pressure: bool, x0: float, kappa0: float, loc0: float, c: float, w: float, a_m: float,
                L_m: float, d_fix: float) -> EquatorEnd | None:
    """Where a stalled frictionless pinning branch reaches the sphere's equator, solved there.

    Frictionless pinning keeps the contact region on the substrate, a <= rs: the contact edge on the
    equator (a = rs, the substrate's tangent vertical) is the model's end; past it the edge would run
    onto the sphere's far side (a falling again at a growing substrate angle), which the model does
    not describe. A continuation in alpha meets it tangentially (rs - a falls as the square of the
    distance in alpha, the substrate angle crossing pi/2 transversally), so it stalls just short of
    it. The second method solves the branch's equations at a = rs itself, where they are regular in
    the remaining unknowns: alpha (and the pressure under pressure control) from the material
    condition J0 = L_m (and the gap), scipy's ``hybr`` from the stalled state. It confirms the stall
    (returns the state) when the stalled radius lies within EQUATOR_NEAR of rs, the solve's residuals
    are within 1e-10 and its alpha within AGREE of the stall's; else None.
    """
    from scipy.optimize import root  # noqa: PLC0415 - only on the way to an error

    from .branches import PIN_FR  # noqa: PLC0415

    if not (c > 0 and all(math.isfinite(v) for v in (x0, kappa0, loc0))):
        return None
    rs = 1.0 / c
    if not x0 >= (1.0 - EQUATOR_NEAR) * rs:
        return None
    a_eq = rs * (1.0 - 1e-15)  # (a c)^2 <= 1 in floating point

    def equations(z):
        loc, kappa = z[0], (z[1] if pressure else kappa0)
        st = state(PIN_FR, a_eq, kappa, loc, c, w, a_m, True)
        if not st[6]:
            return np.full(len(z), np.nan)
        out = [float(st[5]) - L_m]
        if pressure:
            out.append(float(st[2]) - d_fix)
        return np.array(out)

    z0 = np.array([loc0, kappa0]) if pressure else np.array([loc0])
    try:
        sol = root(equations, z0, method="hybr", options={"xtol": 1e-13})
        res = equations(sol.x)
    except (ValueError, ZeroDivisionError, OverflowError):
        return None
    if not (np.all(np.isfinite(res)) and float(np.max(np.abs(res))) <= 1e-10):
        return None
    loc = float(sol.x[0])
    if abs(loc - loc0) > AGREE * max(1.0, abs(loc0)):
        return None
    return EquatorEnd(loc=loc, kappa=float(sol.x[1]) if pressure else float(kappa0),
                      residual=float(np.max(np.abs(res))))
