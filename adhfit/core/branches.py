"""Solvable branches: each (stage, slip) pair as a locator, at most one unknown, and a residual.

A state on a branch is fixed by its locator (the contact radius ``a`` while making contact or
delaminating, the contact angle ``alpha`` while pinned), the pressure kappa and, where the stage is
implicit, one unknown ``x`` solved from the material condition J0 = ln(beta/rho) (eqs. 41-42, 57).
Under pressure control kappa is a second unknown, solved from the gap condition d = d_fix.

=====================  =======  =========  ==============================================
branch                 locator  unknown x  condition
=====================  =======  =========  ==============================================
making_contact         a        --         explicit (eqs. 19, 25, 26)
pinning, no-slip       G        t          J0 = L_m at a = a_m (eqs. 39, 41/42, 52)
pinning, frictionless  alpha    a          J0 = L_m (eq. 57)
delamination, no-slip  a        t          J0 = L_d(a) (eq. 61), alpha from G = w (eq. 62)
delamination, frict.   a        --         explicit, alpha = atan sqrt(2w) (eq. 63)
=====================  =======  =========  ==============================================

No-slip pinning is located by its energy release rate G (0 -> w), not by alpha: at fixed a = a_m the
state with release rate G is the delamination solve of eq. (62) with w replaced by G, whose residual
is monotone in t on the bracket where alpha is real; at fixed alpha the material condition can have
several roots in t near the onset. The onset is simply G = w.

Dimensionless throughout (DESIGN.md A1/B1).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from ..errors import ConvergenceError
from . import delamination, making_contact, pinning
from .membrane import free_membrane, substrate_cos
from .solve import STEP, XTOL, newton

__all__ = ["Context", "Branch", "BRANCHES", "evaluate", "solve_unknown", "solve_state", "derivative"]


@dataclass(frozen=True)
class Context:
    """Per-history constants: substrate curvature c = 1/rs, w, and the end of loading.

    Attributes
    ----------
    c : float
        b/R_s (0 for a flat substrate).
    w : float
        W_ad/(mu h).
    a_m : float
        Contact radius at the end of loading.
    L_m : float
        ln(beta/rho_am), material coordinate of the edge at the end of loading (eq. 37).
    """

    c: float
    w: float
    a_m: float = float("nan")
    L_m: float = float("nan")


@dataclass(frozen=True)
class Branch:
    """One stage under one slip condition (see the module table)."""

    stage: str
    slip: str
    locator: str
    unpack: Callable          # (x, kappa, loc, ctx) -> (a, alpha, D, C2, G)
    target: Callable | None   # (loc, ctx) -> L, the J0 the state must have; None when explicit
    bracket: Callable | None  # (kappa, loc, ctx) -> (lo, hi) for x


def _mc(x, kappa, loc, ctx):
    D, C2 = making_contact.constants(kappa, loc, ctx.c)
    z = np.zeros_like(D)
    return loc + z, z, D, C2, z


def _pin_ns(x, kappa, loc, ctx):
    a = ctx.a_m + 0.0 * x
    alpha = delamination.noslip_angle(x, loc)  # G = loc (eq. 52 solved for alpha)
    D, C2 = pinning.noslip_constants(kappa, a, ctx.c, alpha, x)
    return a, alpha, D, C2, loc + 0.0 * x


def _pin_fr(x, kappa, loc, ctx):
    D, C2 = pinning.frictionless_constants(kappa, x, ctx.c, loc)
    return x, loc + 0.0 * x, D, C2, pinning.frictionless_release_rate(loc) + 0.0 * x


def _del_ns(x, kappa, loc, ctx):
    alpha = delamination.noslip_angle(x, ctx.w)
    D, C2 = pinning.noslip_constants(kappa, loc, ctx.c, alpha, x)
    return loc + 0.0 * x, alpha, D, C2, ctx.w + 0.0 * D


def _del_fr(x, kappa, loc, ctx):
    alpha = delamination.frictionless_angle(ctx.w)
    D, C2 = pinning.frictionless_constants(kappa, loc, ctx.c, alpha)
    return loc + 0.0 * D, alpha + 0.0 * D, D, C2, ctx.w + 0.0 * D


def _a_limit(ctx):
    # contact stays on the upper hemisphere and inside the clamp
    return (1.0 - 1e-9) * (min(1.0, 1.0 / ctx.c) if ctx.c > 0 else 1.0)


BRANCHES: dict[tuple[str, str], Branch] = {
    ("making_contact", "no-slip"): Branch("making_contact", "no-slip", "a", _mc, None, None),
    ("making_contact", "frictionless"): Branch("making_contact", "frictionless", "a", _mc, None, None),
    ("pinning", "no-slip"): Branch(
        "pinning", "no-slip", "G", _pin_ns, lambda loc, ctx: ctx.L_m,
        lambda kappa, loc, ctx: delamination.noslip_stretch_bracket(loc)),
    ("pinning", "frictionless"): Branch(
        "pinning", "frictionless", "alpha", _pin_fr, lambda loc, ctx: ctx.L_m,
        lambda kappa, loc, ctx: (1e-9 * ctx.a_m, _a_limit(ctx))),
    ("delamination", "no-slip"): Branch(
        "delamination", "no-slip", "a", _del_ns,
        lambda loc, ctx: delamination.noslip_material(loc, ctx.a_m, ctx.c, ctx.L_m),
        lambda kappa, loc, ctx: delamination.noslip_stretch_bracket(ctx.w)),
    ("delamination", "frictionless"): Branch("delamination", "frictionless", "a", _del_fr, None, None),
}


def evaluate(branch: Branch, x, kappa, loc, ctx: Context) -> dict:
    """All observables of the states (x, kappa) at locators ``loc``; complex-safe.

    Returns
    -------
    dict
        ``a, alpha, p, d, f, G, J0, ok`` arrays (``p`` is kappa; ``ok`` False outside the model).
    """
    a, alpha, D, C2, G = branch.unpack(x, kappa, loc, ctx)
    _, cos_ta = _edge_cos(a, ctx.c, alpha)
    J0, d, ok = free_membrane(kappa, D, C2, a, ctx.c, cos_ta)
    return {"a": a, "alpha": alpha, "p": kappa + 0.0 * D, "d": d, "f": -np.pi * D, "G": G,
            "J0": J0, "ok": ok}


def _edge_cos(a, c, alpha):
    s, ac = substrate_cos(a, c), a * c
    return s * np.sin(alpha) - ac * np.cos(alpha), s * np.cos(alpha) + ac * np.sin(alpha)


def _residual(branch, x, kappa, loc, ctx):
    e = evaluate(branch, x, kappa, loc, ctx)
    # NaN outside the model, also under complex evaluation (where a sqrt of a negative stays finite)
    return np.where(e["ok"], e["J0"] - branch.target(loc, ctx), np.nan)


def solve_unknown(branch: Branch, kappa, loc, ctx: Context, x0=None, on_fail: str = "raise"):
    """Solve the branch's unknown x at real (kappa, loc); None for explicit branches.

    ``on_fail="nan"`` marks failed elements NaN instead of raising (see :func:`~.solve.newton`).
    """
    if branch.target is None:
        return None
    kappa, loc = np.broadcast_arrays(np.asarray(kappa, float), np.asarray(loc, float))
    lo, hi = branch.bracket(kappa, loc, ctx)
    lo, hi = np.broadcast_to(lo, loc.shape), np.broadcast_to(hi, loc.shape)
    what = (f"{branch.stage} ({branch.slip}): {'t' if branch.slip == 'no-slip' else 'a'} "
            f"from the material condition")
    inputs = {"w": ctx.w, "rs": 1 / ctx.c if ctx.c else np.inf, "a_m": ctx.a_m}

    def resid(x):
        return _residual(branch, x, kappa, loc, ctx)

    if x0 is None:
        return newton(resid, 0.5 * (lo + hi), lo, hi, on_fail=on_fail, what=what, inputs=inputs)
    # from a continuation predictor: the nearby root, even where a second root has entered the
    # bracket and removed its sign change; the bracket is the fallback, row by row (rows are
    # independent problems)
    x0 = np.broadcast_to(np.asarray(x0, float), loc.shape)
    start = np.isfinite(x0)
    x = np.full(loc.shape, np.nan)
    if np.any(start):
        x = newton(resid, np.where(start, x0, 0.5 * (lo + hi)), on_fail="nan", what=what,
                   inputs=inputs)
    inside = start & np.isfinite(x) & (x >= np.minimum(lo, hi)) & (x <= np.maximum(lo, hi))
    if np.all(inside):
        return x
    rest = np.flatnonzero(~inside.ravel())

    def resid_rest(z):
        return _residual(branch, z, kappa.ravel()[rest], loc.ravel()[rest], ctx)

    lo_r, hi_r = lo.ravel()[rest], hi.ravel()[rest]
    try:
        xr = newton(resid_rest, 0.5 * (lo_r + hi_r), lo_r, hi_r, on_fail=on_fail, what=what,
                    inputs=inputs)
    except ConvergenceError as err:  # name the row of the whole array
        if "index" not in err.inputs:
            raise
        raise ConvergenceError(err.what, {**err.inputs, "index": int(rest[err.inputs["index"]])}) \
            from None
    x = x.ravel().copy()
    x[rest] = xr
    return x.reshape(loc.shape)


def _propagate(branch, x, kappa_r, kappa_c, loc_c, ctx):
    """One Newton step in complex arithmetic from the real root x: carries d x/d(kappa, loc)."""
    if x is None:
        return None
    r_x = np.imag(_residual(branch, x + 1j * STEP, kappa_r, np.real(loc_c), ctx)) / STEP
    return x - _residual(branch, x + 0j, kappa_c, loc_c, ctx) / r_x


def solve_state(branch: Branch, loc, ctx: Context, *, kappa=None, d_fix=None, kappa0=None, x0=None):
    """Solve the state(s) at real locators ``loc``.

    Displacement control: give ``kappa``. Pressure control: give ``d_fix`` and a start ``kappa0``;
    kappa is then solved from the gap by Newton, its derivative carried exactly through the inner
    solve of x.

    Returns
    -------
    x, kappa : ndarray or None, ndarray
    """
    loc = np.asarray(loc, float)
    if d_fix is None:
        kappa = np.broadcast_to(np.asarray(kappa, float), loc.shape)
        return solve_unknown(branch, kappa, loc, ctx, x0), kappa
    k0 = np.broadcast_to(np.asarray(kappa0, float), loc.shape)
    if branch.target is not None and x0 is None:
        return _solve_nested(branch, loc, ctx, d_fix, k0, x0)
    if branch.target is not None:
        x0 = np.broadcast_to(np.asarray(x0, float), loc.shape)
        x, kappa, good = _joint_newton(branch, loc, ctx, d_fix, k0, x0)
        if not np.all(good):
            # next to a fold (det -> 0) the differences' ~1e-8 error can stall the iteration: the
            # exact Jacobian is tried before the nested solve
            retry = ~good
            xr, kr, gr = _joint_newton(branch, loc[retry], ctx, d_fix, k0[retry], x0[retry],
                                       fd=False)
            x, kappa, good = x.copy(), kappa.copy(), good.copy()
            x[retry], kappa[retry], good[retry] = xr, kr, gr
    else:
        x0, x = None, None
        kappa, good = _gap_newton(branch, loc, ctx, d_fix, k0)
    if np.all(good):
        return x, kappa
    rest = ~good
    try:
        xr, kr = _solve_nested(branch, loc[rest], ctx, d_fix, k0[rest],
                               None if x0 is None else x0[rest])
    except ConvergenceError as err:  # name the row of the whole array
        if "index" not in err.inputs:
            raise
        index = int(np.flatnonzero(rest.ravel())[err.inputs["index"]])
        raise ConvergenceError(err.what, {**err.inputs, "index": index}) from None
    kappa = kappa.copy()
    kappa[rest] = kr
    if x is not None:
        x = x.copy()
        x[rest] = xr
    return x, kappa


#: iterations of the joint (x, kappa) Newton before the nested solve takes over
JOINT_MAXITER = 12
#: a chord step (the last Jacobian reused) is kept up while each step is below this fraction of the
#: step before it; otherwise the next iteration takes a fresh Jacobian
CHORD_RATE = 0.01
#: relative step of the forward differences of the joint Newton's Jacobian, sqrt(machine epsilon)
FD_STEP = 1.4901161193847656e-08


def _converged(fresh, size, prev):
    """Converged after a step of relative ``size`` (``prev``: the step before it, inf if none).

    The error left is estimated from the observed convergence: a Newton step (fresh Jacobian)
    leaves ~M size^2 with M ~ size / prev^2, a chord step ~(size / prev) size; it must be below
    XTOL. A first step has no estimate and must itself be below XTOL. (A fixed threshold on the
    step is not safe: next to a fold of the branch M is large.)
    """
    r = np.minimum(1.0, size / prev)
    est = np.where(np.isfinite(prev), size * np.where(fresh, r * r, r), size)
    return est <= XTOL


def _jacobian(branch, x, k, loc, ctx, e0, fd):
    """d(J0, d)/d(x, kappa) at real states ``e0`` (their ``evaluate``): Rx, Gx, Rk, Gk.

    Forward differences with steps FD_STEP (1 + |x|) and FD_STEP (1 + |kappa|): two real
    evaluations, good to ~1e-8 relative, which only sets how fast the joint Newton converges (its
    residuals are exact). Rows where a perturbed state is outside the model, or all rows when
    ``fd`` is False, take two complex steps (exact).
    """
    hx, hk = FD_STEP * (1.0 + np.abs(x)), FD_STEP * (1.0 + np.abs(k))
    ex = evaluate(branch, x + hx, k, loc, ctx)
    ek = evaluate(branch, x, k + hk, loc, ctx)
    e1 = evaluate(branch, x + 1j * STEP, k + 0j, loc, ctx)
    e2 = evaluate(branch, x + 0j, k + 1j * STEP, loc, ctx)
    fd = fd & ex["ok"] & ek["ok"]
    return (np.where(fd, (ex["J0"] - e0["J0"]) / hx, np.imag(e1["J0"]) / STEP),
            np.where(fd, (ex["d"] - e0["d"]) / hx, np.imag(e1["d"]) / STEP),
            np.where(fd, (ek["J0"] - e0["J0"]) / hk, np.imag(e2["J0"]) / STEP),
            np.where(fd, (ek["d"] - e0["d"]) / hk, np.imag(e2["d"]) / STEP))


def _joint_newton(branch, loc, ctx, d_fix, k0, x0, fd=True):
    """Pressure control: Newton on (material condition, gap) in (x, kappa) jointly, from predictors.

    The first iteration takes the 2x2 Jacobian (:func:`_jacobian`, by differences if ``fd``);
    later ones reuse it (chord steps, one real evaluation each) while each step is below CHORD_RATE
    times the one before and take a fresh Jacobian otherwise. From a continuation predictor a row converges in two or three
    iterations, several times cheaper than the nested solve. It stops when the error left, estimated
    from the observed rate of convergence, is below XTOL (:func:`_converged`; the Newton rule only
    with the exact Jacobian).

    No safeguard: a non-finite or inadmissible iterate, a singular Jacobian, no convergence in
    JOINT_MAXITER iterations or a root outside x's bracket marks the row failed (``good`` False);
    the caller solves those rows by the nested, safeguarded method.

    Returns
    -------
    x, kappa : ndarray
    good : ndarray of bool
    """
    x, k = np.array(x0, float), np.array(k0, float)
    alive = np.isfinite(x) & np.isfinite(k)
    done = np.zeros(loc.shape, bool)
    fresh = np.ones(loc.shape, bool)
    prev = np.full(loc.shape, np.inf)
    Rx, Gx, Rk, Gk = (np.zeros(loc.shape) for _ in range(4))
    target = np.real(branch.target(loc + 0j, ctx))
    with np.errstate(all="ignore"):
        for _ in range(JOINT_MAXITER):
            run = alive & ~done
            if not run.any():
                break
            e0 = evaluate(branch, x, k, loc, ctx)
            J = _jacobian(branch, x, k, loc, ctx, e0, fd)
            Rx, Gx, Rk, Gk = (np.where(fresh, new, old) for new, old in zip(J, (Rx, Gx, Rk, Gk)))
            R, G = e0["J0"] - target, e0["d"] - d_fix
            det = Rx * Gk - Rk * Gx
            fine = e0["ok"] & np.isfinite(R) & np.isfinite(G) & np.isfinite(det) & (det != 0)
            alive &= fine | done
            run &= fine
            exact = (R == 0) & (G == 0)
            dx = np.where(exact, 0.0, -(R * Gk - Rk * G) / det)
            dk = np.where(exact, 0.0, -(Rx * G - R * Gx) / det)
            size = np.maximum(np.abs(dx) / (1.0 + np.abs(x)), np.abs(dk) / (1.0 + np.abs(k)))
            # the Newton stopping rule holds only for a step with the exact Jacobian
            small = _converged(fresh & (not fd), size, prev)
            x = np.where(run, x + dx, x)
            k = np.where(run, k + dk, k)
            done |= run & (exact | small)
            fresh = np.where(run, ~(size <= CHORD_RATE * prev), fresh)
            prev = np.where(run, size, prev)
    lo, hi = branch.bracket(k, loc, ctx)
    inside = (x >= np.minimum(lo, hi)) & (x <= np.maximum(lo, hi))
    return x, k, alive & done & inside


def _gap_newton(branch, loc, ctx, d_fix, k0):
    """Pressure control on an explicit branch: kappa for the gap from predictors, Newton with chord
    steps and the stopping rule of :func:`_joint_newton`; (kappa, good)."""
    k = np.array(k0, float)
    alive = np.isfinite(k)
    done = np.zeros(loc.shape, bool)
    fresh = np.ones(loc.shape, bool)
    prev = np.full(loc.shape, np.inf)
    dr = np.zeros(loc.shape)
    with np.errstate(all="ignore"):
        for _ in range(JOINT_MAXITER):
            run = alive & ~done
            if not run.any():
                break
            e1 = evaluate(branch, None, k + 1j * STEP, loc, ctx)
            e0 = evaluate(branch, None, k, loc, ctx)
            dr = np.where(fresh, np.imag(e1["d"]) / STEP, dr)
            r = np.where(fresh, np.real(e1["d"]), e0["d"]) - d_fix
            ok = np.where(fresh, e1["ok"], e0["ok"])
            fine = ok & np.isfinite(r) & np.isfinite(dr) & (dr != 0)
            alive &= fine | done
            run &= fine
            step = np.where(r == 0, 0.0, -r / dr)
            size = np.abs(step) / (1.0 + np.abs(k))
            small = _converged(fresh, size, prev)
            k = np.where(run, k + step, k)
            done |= run & ((r == 0) | small)
            fresh = np.where(run, ~(size <= CHORD_RATE * prev), fresh)
            prev = np.where(run, size, prev)
    return k, alive & done


def _solve_nested(branch, loc, ctx, d_fix, k0, x0):
    """Pressure control, safeguarded: Newton on kappa for the gap around the inner solve of x."""
    memo = {"x": None if x0 is None else np.broadcast_to(np.asarray(x0, float), loc.shape)}

    def gap(kc):
        kr = np.real(kc)
        # a kappa iterate with no inner solution gives NaN, so the outer Newton backs off; each row
        # restarts from its own last finite inner solution
        x = solve_unknown(branch, kr, loc, ctx, memo.get("x"), on_fail="nan")
        if x is not None:
            memo["x"] = x if memo["x"] is None else np.where(np.isfinite(x), x, memo["x"])
        xc = _propagate(branch, x, kr, kc, loc + 0j, ctx)
        e = evaluate(branch, xc, kc, loc, ctx)
        return np.where(e["ok"], e["d"] - d_fix, np.nan)

    kappa = newton(gap, k0, what=f"{branch.stage} ({branch.slip}): pressure from the fixed gap",
                   inputs={"d": d_fix, "w": ctx.w, "a_m": ctx.a_m})
    x = solve_unknown(branch, kappa, loc, ctx, memo.get("x"))
    return x, kappa


def derivative(branch: Branch, loc, ctx: Context, x, kappa, *, pressure_control: bool) -> dict:
    """d(observable)/d(locator) along the branch at solved states, by one complex step.

    Under displacement control kappa is fixed; under pressure control the 2x2 system
    (material condition, gap condition) is linearised with its exact Jacobian.
    """
    loc = np.asarray(loc, float)
    lc = loc + 1j * STEP
    if not pressure_control:
        xc = _propagate(branch, x, kappa, kappa + 0j, lc, ctx)
        out = evaluate(branch, xc, kappa + 0j, lc, ctx)
        return {k: np.imag(v) / STEP for k, v in out.items() if k != "ok"}
    d0 = np.real(evaluate(branch, x, kappa, loc, ctx)["d"])

    def F(xx, kk, ll):
        e = evaluate(branch, xx, kk, ll, ctx)
        g = e["d"] - d0
        return (e["J0"] - branch.target(ll, ctx) if branch.target else None), g

    kr = np.asarray(kappa, float)
    if x is None:
        gk = np.imag(F(None, kr + 1j * STEP, loc)[1]) / STEP
        gl = np.imag(F(None, kr + 0j, lc)[1]) / STEP
        kc = kr - 1j * STEP * gl / gk
        out = evaluate(branch, None, kc, lc, ctx)
        return {k: np.imag(v) / STEP for k, v in out.items() if k != "ok"}
    Rx, Gx = (np.imag(v) / STEP for v in F(x + 1j * STEP, kr + 0j, loc))
    Rk, Gk = (np.imag(v) / STEP for v in F(x + 0j, kr + 1j * STEP, loc))
    Rl, Gl = (np.imag(v) / STEP for v in F(x + 0j, kr + 0j, lc))
    det = Rx * Gk - Rk * Gx
    dx = -(Rl * Gk - Rk * Gl) / det
    dk = -(Rx * Gl - Rl * Gx) / det
    out = evaluate(branch, x + 1j * STEP * dx, kr + 1j * STEP * dk, lc, ctx)
    return {k: np.imag(v) / STEP for k, v in out.items() if k != "ok"}


def mc_pressure(a, ctx: Context, d_fix: float, lo, hi):
    """Pressure control, making contact: kappa with d(kappa, a) = d_fix on the bracket [lo, hi].

    Bracketed Newton (:func:`~.solve.newton`) on the gap; d grows with kappa along the bracket.
    """
    mc = BRANCHES[("making_contact", "no-slip")]

    def gap(k):
        e = evaluate(mc, None, k, a, ctx)
        return np.where(e["ok"], e["d"] - d_fix, np.nan)

    return newton(gap, 0.5 * (lo + hi), lo, hi, what="making contact: pressure from the fixed gap",
                  inputs={"d": d_fix})


def check_ok(state: dict, what: str, inputs: dict) -> None:
    """Raise ConvergenceError when a solved state is outside the model or not finite."""
    bad = ~np.asarray(state["ok"], bool)
    for k in ("a", "alpha", "p", "d", "f", "G"):
        bad |= ~np.isfinite(np.real(state[k]))
    if np.any(bad):
        i = int(np.flatnonzero(bad)[0])
        raise ConvergenceError(f"{what}: state outside the model's domain (free membrane past "
                               f"vertical at the clamp, or no real solution)",
                               {**inputs, "index": i})
