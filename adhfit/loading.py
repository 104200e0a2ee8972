"""Loading histories: displacement control (fixed p) and pressure control (fixed gap d).

A history runs making contact (a from 0 to a_max), contact pinning (alpha from 0 to the onset of
delamination, G = w) and delamination (a from the onset down to 1e-3 a_max, toward complete
detachment). Rows are placed per stage, clustered at the stage boundaries; the onset, the most
negative force and the turning point of the control variable are solved for (root of the exact
derivative along the branch), not picked from rows, and inserted as rows.

Everything here is dimensionless (DESIGN.md A1); no pandas.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import lru_cache

import numpy as np
from scipy.optimize import brentq

from .core import delamination
from .core.backend import (check_ok, compiled_kernels, evaluate, extremum, follow, mc_pressure,
                           solve_rows, solve_state)
from .core.continuation import BRENT_MAXITER, BRENT_RTOL, BRENT_XTOL
from .core.branches import BRANCHES, Context
from .core.inflation import apex_deflection, critical_pressure
from .core.solve import newton
from .errors import ConvergenceError, InputError
from .params import A_MAX_OVER_RS, DIMENSIONLESS, check_scene

__all__ = ["History", "history", "state_at", "STAGES", "COLUMNS"]

STAGES = ("making_contact", "pinning", "delamination")
COLUMNS = ("stage", "a", "alpha", "p", "d", "delta", "f", "G", "stable")
#: where the history stops on the way to detachment (a -> 0 is singular), relative to a_max
A_END = 1e-3
_KEYS = ("a", "alpha", "p", "d", "f", "G")
_STAGE_LABELS = np.array(STAGES, dtype=object)


@dataclass(frozen=True)
class History:
    """A dimensionless loading history.

    Attributes
    ----------
    columns : dict of str -> ndarray
        ``stage`` (str array) and ``a, alpha, p, d, delta, f, G`` (float; ``delta`` NaN where
        |p| > 1) and ``stable`` (bool), in history order.
    summary : dict
        ``f_max``, ``onset``, ``f_min``, ``turning_point`` (DESIGN.md A2 ``--json``).
    inputs : dict
        The validated inputs, with the resolved ``a_max``.
    """

    columns: dict
    summary: dict
    inputs: dict = field(default_factory=dict)


# ----------------------------------------------------------------------------------------------
# setup


def _prepare(control, slip, p, d, w, rs, a_max, delta_max, p_max, lambda0, points):
    v = check_scene(control, slip, p=p, d=d, w=w, rs=rs, a_max=a_max, delta_max=delta_max,
                    p_max=p_max, lambda0=lambda0, points=points)
    c = 0.0 if math.isinf(v["rs"]) else 1.0 / v["rs"]
    pc = control == "pressure"
    v["a_max"] = _loading_end(v, c, pc)
    return v, c, pc


def _a_cap(c):
    """Largest admissible a_max: the table's bound and 0.95 rs."""
    cap = DIMENSIONLESS["a_max"].upper
    return min(cap, A_MAX_OVER_RS / c) if c > 0 else cap


def _loading_end(v, c, pc):
    """Resolve a_max from delta_max or p_max when those end the loading (1-D solves in a)."""
    if "a_max" in v:
        return v["a_max"]
    mc = BRANCHES[("making_contact", "no-slip")]
    ctx = Context(c, v["w"])
    cap = _a_cap(c)
    if pc:
        kappa, name, target = v["p_max"], "p_max", v["d"]
        p_cr = float(critical_pressure(v["d"]))
        if kappa <= p_cr:
            raise InputError("p_max", kappa, f"above the critical pressure p_cr = {p_cr:.6g} "
                             f"at which contact starts for d = {v['d']:g}")

        def resid(a):
            e = evaluate(mc, None, kappa, a, ctx)
            return np.where(e["ok"], e["d"] - target, np.nan)
    else:
        kappa, name = v["p"], "delta_max"
        d0 = float(apex_deflection(kappa))
        target = d0 - v["delta_max"]

        def resid(a):
            e = evaluate(mc, None, kappa, a, ctx)
            return np.where(e["ok"], e["d"] - target, np.nan)
    r_cap = float(np.real(resid(np.array([cap]))[0]))
    if not np.isfinite(r_cap) or r_cap > 0:
        reach = d0 - (r_cap + target) if not pc else None
        valid = (f"a number in (0, {reach:.6g}] (the displacement at a_max = {cap:g})"
                 if (not pc and np.isfinite(r_cap)) else
                 f"reachable with a contact radius below {cap:g}")
        raise InputError(name, v[name], valid)
    lo = 1e-9 * cap
    if kappa > 1.0:  # Case I needs sin(theta) at the clamp <= 1: kappa (1 - a^2) - c a^2 <= 1
        lo = max(lo, math.sqrt((kappa - 1.0) / (kappa + c)) * (1 + 1e-9))
    a = newton(resid, np.array([0.5 * (lo + cap)]), np.array([lo]), np.array([cap]),
               what=f"contact radius for {name}", inputs={name: v[name]})
    return float(a[0])


def _ctx_after_loading(v, c, pc):
    """Solve the end of loading: (Context with a_m, L_m; kappa_m)."""
    ctx0 = Context(c, v["w"])
    mc = BRANCHES[("making_contact", v.get("slip", "no-slip"))]
    a = np.array([v["a_max"]])
    kappa = _mc_pressure(a, v, c) if pc else np.array([v["p"]])
    e = evaluate(mc, None, kappa, a, ctx0)
    check_ok(e, "end of loading", {"a_max": v["a_max"]})
    return Context(c, v["w"], v["a_max"], float(e["J0"][0])), float(kappa[0])


def _mc_pressure(a, v, c):
    """Pressure control, making contact: kappa with d(kappa, a) = d_fix, bracketed (d grows with kappa).

    Upper end: the clamp tangent turns vertical, sin(theta(1)) = kappa(1 - a^2) - c a^2 = 1 (Case I).
    """
    d_fix = v["d"]
    lo = np.full(a.shape, float(critical_pressure(d_fix)))
    hi = (1.0 + c * a * a) / (1.0 - a * a) * (1 - 1e-12)
    try:
        return mc_pressure(a, Context(c, v["w"]), d_fix, lo, hi)
    except ConvergenceError as err:
        raise InputError("a_max", v["a_max"], "reachable under pressure control at this gap",
                         "The membrane cannot reach this contact radius with a Case I shape "
                         "(its tangent would turn past vertical at the clamp).") from err


# ----------------------------------------------------------------------------------------------
# grids


def _cluster(n):
    """n points on [0, 1] clustered at both ends (cosine spacing)."""
    return 0.5 * (1.0 - np.cos(np.pi * np.arange(n) / (n - 1)))


@lru_cache(maxsize=64)
def _grids(points):
    """The row grids of a history with ``points`` rows (cached, read-only).

    Returns
    -------
    u_mc, u_pin, u_dl : ndarray
        Making contact: a / a_max in (0, 1], clustered at both ends. Pinning: in (0, 1], dense toward
        the onset only (the start of pinning is the end of loading). Delamination: the fraction of the
        way from the onset back to the end, (1 - u)^1.5 with u clustered (denser toward the end).
    """
    n_mc, n_pin, n_del = _split(points)
    u_pin = np.sin(0.5 * np.pi * np.arange(1, n_pin) / (n_pin - 1))
    grids = (_cluster(n_mc)[1:], u_pin, (1.0 - _cluster(n_del)[1:]) ** 1.5)
    for g in grids:
        g.flags.writeable = False
    return grids


def _split(points):
    n_mc = max(4, round(0.3 * points))
    n_pin = max(4, round(0.2 * points))
    return n_mc, n_pin, max(5, points - n_mc - n_pin + 2)


# ----------------------------------------------------------------------------------------------
# solving rows on a branch


def _solve_rows(branch, locs, ctx, pc, kappa, d_fix, kappa_guess, x_guess=None, start=None):
    """Solve many states of one branch at once; on failure fall back to continuation.

    ``start`` = (locator, x, kappa) of a solved state of the branch, from which pressure control
    follows the branch through the rows if the vectorised solve fails.

    Returns
    -------
    x, kappa, state
        The unknowns (None on explicit branches) and the observables (``evaluate`` output).
    """
    try:
        x, k, st = solve_rows(branch, locs, ctx, kappa=None if pc else kappa,
                              d_fix=d_fix if pc else None, kappa0=kappa_guess, x0=x_guess)
        if st["ok"].all() and np.isfinite(st["f"]).all():
            return x, k, st
        if locs.size == 1 and start is None:
            return x, k, st  # the caller's check_ok names the failure
    except ConvergenceError:
        if locs.size == 1 and start is None:
            raise
    if start is not None:
        # follow the branch through the rows themselves, from a solved state
        l0, x0, k0 = start
        (_, xs, ks), _ = _follow(branch, l0, locs, x0, k0, ctx, d_fix if pc else None,
                                 log=branch.locator == "a")
        xs = None if branch.target is None else xs
        return xs, ks, evaluate(branch, xs, ks, locs, ctx)
    # displacement control: each row starts from its predecessor
    xs, ks = np.empty(locs.shape), np.empty(locs.shape)
    x_prev = None
    for i, loc in enumerate(locs):
        x, k = solve_state(branch, np.array([loc]), ctx, kappa=kappa, x0=x_prev)
        xs[i] = np.nan if x is None else x[0]
        ks[i] = k[0]
        x_prev = x
    xs = None if branch.target is None else xs
    return xs, ks, evaluate(branch, xs, ks, locs, ctx)


def _check(state, what, info):
    """check_ok, skipped where the compiled backend has already found every state admissible."""
    if state.get("first_bad", 0) >= 0:
        check_ok(state, what, info)


def _detachment_end(ctx, kappa):
    """Where the history stops on the way to a -> 0: A_END a_max, or lower for very weak adhesion.

    Near detachment f ~ pi[(kappa + c) a^2 - a tan(alpha)], whose minimum (the pull-off) sits at
    a ~ tan(alpha) / (2 (kappa + c)) with tan(alpha) ~ sqrt(2 w): the end must lie well below it.
    """
    pull_off = np.sqrt(2.0 * ctx.w) / (2.0 * (abs(kappa) + ctx.c + 1.0))
    return min(A_END * ctx.a_m, 0.1 * pull_off)


def _delamination_start(slip, on_x, onset):
    """The unknown of the delamination branch at the onset (no slip: the same t as the pinned state)."""
    return float(on_x[0]) if slip == "no-slip" else None


def _pin_end(slip, ctx):
    """Locator of the onset on the pinning branch: G = w (no slip) or alpha = atan sqrt(2w)."""
    return ctx.w if slip == "no-slip" else float(delamination.frictionless_angle(ctx.w))


def _onset(slip, ctx, pc, kappa_m, d_fix):
    """The end of pinning, where G first reaches w.

    The pinning path is followed by continuation from the end of loading (under pressure control the
    pressure can also fall far below its end-of-loading value before G reaches w).

    Returns
    -------
    branch, loc, x, kappa, path
        ``path`` = (locators, x, kappa) along pinning (predictors for the rows).
    """
    branch = BRANCHES[("pinning", slip)]
    loc = np.array([_pin_end(slip, ctx)])
    # the physical state is the one connected to the start of pinning (G = 0, t = 1, a = a_m): at
    # fixed G the material condition can have a second root, which a bracket alone may pick
    path = _pinning_path(slip, ctx, kappa_m, d_fix if pc else None)
    return branch, loc, np.array([path[1][-1]]), np.array([path[2][-1]]), path


def _pinning_path(slip, ctx, kappa_m, d_fix):
    """Pressure control: pinning from its start (locator 0) to the onset, by continuation."""
    x0 = 1.0 if slip == "no-slip" else ctx.a_m
    pin = BRANCHES[("pinning", slip)]
    end = _pin_end(slip, ctx)
    # a coarse path of predictors; its last point is the onset
    return _follow(pin, 0.0, np.array([end]), x0, kappa_m, ctx, d_fix, log=False)[1]


def _follow(branch, l0, targets, x0, k0, ctx, d_fix, *, log, sqrt=False, max_steps=2000,
            allow_end=False):
    """Follow a branch from locator l0 (solved: x0, k0) through ``targets`` (continuation).

    See :func:`adhfit.core.continuation.follow` (one compiled call under the numba backend).
    """
    return follow(branch, l0, targets, x0, k0, ctx, d_fix, log=log, sqrt=sqrt, max_steps=max_steps,
                  allow_end=allow_end)


# ----------------------------------------------------------------------------------------------
# extrema


# ----------------------------------------------------------------------------------------------
# public


def history(control: str, slip: str, *, p: float | None = None, d: float | None = None, w: float,
            rs: float, a_max: float | None = None, delta_max: float | None = None,
            p_max: float | None = None, lambda0: float = 2.0, points: int = 200) -> History:
    """Compute a full dimensionless history (DESIGN.md A2).

    Parameters
    ----------
    control : {"displacement", "pressure"}
        Displacement control at fixed pressure ``p``, or pressure control at fixed gap ``d``.
    slip : {"no-slip", "frictionless"}
        Interface condition during pinning and delamination.
    p, d : float
        Fixed pressure P b/(2 mu h) (displacement control) or fixed gap d/b (pressure control).
    w : float
        W_ad/(mu h), > 0.
    rs : float
        R_s/b, ``inf`` for a flat substrate.
    a_max, delta_max, p_max : float
        Exactly one loading end: contact radius, displacement (displacement control) or pressure
        (pressure control) at the end of loading.
    lambda0 : float
        Pre-stretch; it cancels from every observable under the large-stretch approximation and is
        only validated here.
    points : int
        Approximate number of rows.

    Returns
    -------
    History

    Raises
    ------
    InputError
        A parameter out of range (the message names it, its value and the valid range).
    ConvergenceError
        A state of the history is outside the model (e.g. the free membrane would turn past
        vertical at the clamp) or a solve failed; carries the inputs.
    """
    v, c, pc = _prepare(control, slip, p, d, w, rs, a_max, delta_max, p_max, lambda0, points)
    v["slip"] = slip
    info = {"control": control, "slip": slip, **{k: v[k] for k in v if k != "slip"}}
    kernels = compiled_kernels()
    if kernels is not None:
        fast = _history_compiled(kernels, v, c, pc, info)
        if fast is not None:
            return fast
    return _history_steps(v, c, pc, info)


def _history_compiled(K, v, c, pc, info):
    """The whole history in one compiled call (``compiled.history_kernel``); None when it fails.

    The kernel repeats :func:`_history_steps` step by step; on failure the caller runs those steps,
    which raise the error with its full message.
    """
    d_fix = float(v["d"]) if pc else 0.0
    kappa_dc = 0.0 if pc else float(v["p"])
    p_cr = 2.0 * d_fix / (1.0 + d_fix * d_fix) if pc else 0.0  # critical_pressure
    u_mc, u_pin, u_dl = _grids(v["points"])
    status, out, counts, tp_pos, summ, f_max, branch_end = K.history_kernel(
        pc, v["slip"] == "no-slip", kappa_dc, d_fix, p_cr, c, float(v["w"]), float(v["a_max"]),
        u_mc, u_pin, u_dl, A_END, BRENT_XTOL, BRENT_RTOL, BRENT_MAXITER)
    if status != K.H_OK:
        return None
    cols = dict(zip(("a", "alpha", "p", "d", "f", "G", "delta"), out))
    cols["stage"] = np.repeat(_STAGE_LABELS, counts)
    cols["stable"] = np.arange(out.shape[1]) <= tp_pos
    dpt = d_fix if pc else None
    rows = [dict(zip(_KEYS, map(float, r))) for r in summ]
    summary = {"f_max": float(f_max), "onset": _point(rows[K.S_ONSET], pc, dpt),
               "f_min": _point(rows[K.S_FMIN], pc, dpt),
               "turning_point": _point(rows[K.S_TP], pc, dpt)}
    if branch_end == branch_end:  # not NaN
        info["delamination_ends_at_a"] = float(branch_end)
    return History(cols, summary, info)


def _history_steps(v, c, pc, info):
    """The history step by step (the readable reference of ``compiled.history_kernel``)."""
    slip = v["slip"]
    d_fix = v.get("d")
    kappa_dc = v.get("p")
    u_mc, u_pin, u_dl = _grids(v["points"])

    # 1. making contact, a in (0, a_m]; a = 0 is free inflation. The last row is the end of loading
    # (_cluster ends at 1.0 exactly), whose edge material coordinate L_m the later stages need.
    mc = BRANCHES[("making_contact", slip)]
    a_mc = v["a_max"] * u_mc
    k_mc = _mc_pressure(a_mc, v, c) if pc else np.full(a_mc.shape, kappa_dc)
    s_mc = solve_rows(mc, a_mc, Context(c, v["w"]), kappa=k_mc)[2]
    if s_mc.get("first_bad", 0) >= 0:
        check_ok({k: s_mc[k][-1:] for k in ("ok",) + _KEYS}, "end of loading", {"a_max": v["a_max"]})
        check_ok(s_mc, "making contact", info)
    ctx, kappa_m = Context(c, v["w"], v["a_max"], float(s_mc["J0"][-1])), float(k_mc[-1])
    p0 = float(critical_pressure(d_fix)) if pc else kappa_dc
    free = {"a": 0.0, "alpha": 0.0, "p": p0, "d": d_fix if pc else float(apex_deflection(p0)),
            "f": 0.0, "G": 0.0}

    # 2. pinning, locator in (0, end]: G (no slip, ~alpha^2 near 0) or alpha (frictionless), dense
    # toward the onset only (the start of pinning is the end of loading, and G ~ alpha^2 there). The
    # rows are solved by continuation from the start of pinning (G = 0, t = 1, a = a_m) through every
    # row: at fixed G the material condition can have a second root, and the physical state is the
    # one connected to the start. The last row is the onset of delamination, G = w.
    pin = BRANCHES[("pinning", slip)]
    end = _pin_end(slip, ctx)
    lp = end * (u_pin * u_pin if slip == "no-slip" else u_pin)
    (_, x_pin, k_pin), _ = _follow(pin, 0.0, lp, 1.0 if slip == "no-slip" else ctx.a_m, kappa_m,
                                   ctx, d_fix if pc else None, log=False, sqrt=slip == "no-slip")
    s_pin = evaluate(pin, x_pin, k_pin, lp, ctx)
    onset = {k: v[-1:] for k, v in s_pin.items()}
    on_x = x_pin[-1:]
    check_ok(onset, "onset of delamination", info)
    check_ok(s_pin, "pinning", info)
    a_on, k_on = (float(np.real(onset[k][0])) for k in ("a", "p"))

    # 3. delamination, a from a_on toward detachment (denser toward its end), by continuation from
    # the onset through every row. No slip: the branch can end at a finite radius, where the
    # stretch-mismatch part of G, (t - 1)^2 / 2, alone reaches w (alpha -> 0); no state with G = w
    # exists beyond it and detachment from there is dynamic. The rows are then spread up to that end.
    dl = BRANCHES[("delamination", slip)]
    a_end = _detachment_end(ctx, k_on)
    a_dl = a_end + (a_on - a_end) * u_dl
    branch_end = None
    x_start = None if dl.target is None else _delamination_start(slip, on_x, onset)
    if not pc and dl.target is None:  # explicit in displacement control when frictionless
        x_dl, k_dl, s_dl = _solve_rows(dl, a_dl, ctx, pc, kappa_dc, d_fix, None)
    else:
        reached, dpath = _follow(dl, a_on, a_dl, x_start, k_on, ctx, d_fix if pc else None,
                                 log=True, allow_end=slip == "no-slip")
        if reached[0].size == a_dl.size:
            x_dl = None if dl.target is None else reached[1]
            k_dl = reached[2]
            s_dl = evaluate(dl, x_dl, k_dl, a_dl, ctx)
        else:
            branch_end = a_end = float(dpath[0][-1])
            a_dl = a_end + (a_on - a_end) * u_dl
            order = np.argsort(dpath[0])
            k_guess = np.interp(a_dl, dpath[0][order], dpath[2][order])
            x_guess = None
            if dl.target is not None:
                x_guess = np.interp(a_dl, dpath[0][order], dpath[1][order])
                x_guess[-1] = dpath[1][-1]
            x_dl, k_dl, s_dl = _solve_rows(dl, a_dl, ctx, pc, kappa_dc, d_fix, k_guess, x_guess,
                                           start=(a_on, x_start, k_on))
    _check(s_dl, "delamination", info)

    stages = {"pinning": (pin, lp, s_pin, x_pin), "delamination": (dl, a_dl, s_dl, x_dl)}
    extra = _extrema(stages, ctx, pc, kappa_dc, d_fix, onset)
    cols = _assemble(free, (a_mc, s_mc), (lp, s_pin), (a_dl, s_dl), extra, pc, d_fix)
    summary = _summary(cols, s_mc, onset, extra, pc, d_fix)
    if branch_end is not None:
        info["delamination_ends_at_a"] = branch_end  # quasi-static branch ends; dynamic detachment
    return History(cols, summary, info)


def _real(state, i=None):
    return {k: float(np.real(state[k] if i is None else state[k][i])) for k in _KEYS}


def _extrema(stages, ctx, pc, kappa, d_fix, onset):
    """Refine the turning point (extremum of the control variable) and the force minimum.

    Returns a dict name -> (stage, locator, state dict).
    """
    out = {}
    # concatenated retraction path: onset is the last pinning row / first delamination row
    n_pin = stages["pinning"][1].size
    specs = (("turning_point", "p" if pc else "d", -1.0 if pc else 1.0), ("f_min", "f", -1.0))
    for name, key, sign in specs:
        vals = sign * np.concatenate([np.real(stages["pinning"][2][key]),
                                      np.real(stages["delamination"][2][key])])
        j = int(np.argmax(vals))
        stage, i = ("pinning", j) if j < n_pin else ("delamination", j - n_pin)
        branch, locs, st, xs = stages[stage]
        # the extremum lies between the neighbours of the best row on its own branch
        lo = locs[i - 1] if i > 0 else (0.0 if stage == "pinning" else float(np.real(onset["a"][0])))
        hi = locs[i + 1] if i + 1 < locs.size else locs[i]
        j0, j1 = max(i - 2, 0), min(i + 3, locs.size)
        rl = locs[j0:j1]
        order = np.argsort(rl)
        rows = (rl[order], (np.full(j1 - j0, np.nan) if xs is None else xs[j0:j1])[order],
                np.real(st["p"][j0:j1])[order])
        lo, hi = (min(lo, hi), max(lo, hi)) if lo != hi else (locs[i], locs[i])
        loc, solved = extremum(branch, lo, hi, ctx, d_fix if pc else None, kappa, key, sign, rows)
        _check(solved, name.replace("_", " "), {"stage": stage, branch.locator: float(loc)})
        state = _real(solved, 0)
        if sign * state[key] < vals[j]:
            # the row itself is better: the search could not re-solve an end of its bracket, which
            # happens where that row is the end of a no-slip delamination branch (a fold); the
            # extremum is then that end of the history
            loc, state = locs[i], _real(st, i)
        out[name] = (stage, float(loc), state)
    # each is also held against the other's state (a solved state of the history, inserted as a
    # row): next to such a fold the other search may have found the better state
    found = dict(out)
    for (name, key, sign), other in zip(specs, ("f_min", "turning_point")):
        if sign * found[other][2][key] > sign * found[name][2][key]:
            out[name] = found[other]
    return out


def _assemble(free, mc, pin, dl, extra, pc, d_fix):
    """Stack the stages in history order, insert the solved extrema, set ``delta`` and ``stable``."""
    parts = ((np.zeros(1), {k: np.array([free[k]]) for k in _KEYS}),) + (mc, pin, dl)
    locs = np.concatenate([lc for lc, _ in parts])
    # rows per stage; the free-inflation row belongs to making contact
    counts = [1 + mc[0].size, pin[0].size, dl[0].size]
    # history position: stage rank, then alpha ascending (pinning) or a descending (delamination);
    # ``take`` lists the rows (the extrema appended after them) in that order
    n0 = locs.size
    take = np.arange(n0)
    extra_rows = []
    tp_pos = None
    for name, (stg, lc, state) in sorted(extra.items()):
        rank = STAGES.index(stg)
        s0 = sum(counts[:rank])
        seg = locs[s0:s0 + counts[rank]]
        # first row of the stage that lies at or beyond the extremum
        beyond = np.flatnonzero(seg <= lc + 1e-15 if stg == "delamination" else seg >= lc - 1e-15)
        j = s0 + (int(beyond[0]) if beyond.size else seg.size)
        if not (beyond.size and abs(locs[j] - lc) <= 1e-14):
            extra_rows.append(state)
            take = np.concatenate((take[:j], [n0 + len(extra_rows) - 1], take[j:]))
            locs = np.concatenate((locs[:j], [lc], locs[j:]))
            counts[rank] += 1
            if tp_pos is not None and j <= tp_pos:
                tp_pos += 1
        if name == "turning_point":
            tp_pos = j
    cols = {}
    for k in _KEYS:
        col = np.concatenate([st[k] for _, st in parts] + [[r[k] for r in extra_rows]])
        cols[k] = np.real(col[take] if extra_rows else col) + 0.0  # + 0.0 turns -0.0 into 0.0
    cols["stage"] = np.repeat(_STAGE_LABELS, counts)
    n = locs.size
    if pc:
        cols["d"] = np.full(n, d_fix, dtype=float)  # exact by construction
        with np.errstate(invalid="ignore"):
            cols["delta"] = apex_deflection(cols["p"]) - cols["d"]
    else:  # |p| < 1: apex_deflection without the error-state switch
        cols["delta"] = cols["p"] / (1.0 + np.sqrt(1.0 - cols["p"] * cols["p"])) - cols["d"]
    cols["stable"] = np.arange(n) <= tp_pos
    return cols


def _point(state, pc, d_fix):
    p = state["p"]
    d = d_fix if pc else state["d"]
    delta = p / (1.0 + math.sqrt(1.0 - p * p)) - d if abs(p) <= 1 else None  # apex_deflection
    return {"f": state["f"], "delta": delta, "p": p, "a": state["a"]}


def _summary(cols, s_mc, onset, extra, pc, d_fix):
    return {"f_max": float(np.real(s_mc["f"][-1])),
            "onset": _point(_real(onset, 0), pc, d_fix),
            "f_min": _point(extra["f_min"][2], pc, d_fix),
            "turning_point": _point(extra["turning_point"][2], pc, d_fix)}


def state_at(control: str, slip: str, stage: str, *, p: float | None = None, d: float | None = None,
             w: float, rs: float, a_max: float, a: float | None = None,
             alpha: float | None = None) -> dict:
    """One state of a history, at a given locator (for tests and reference comparisons).

    Parameters
    ----------
    stage : {"making_contact", "pinning", "delamination"}
        Making contact and delamination take the contact radius ``a``; pinning takes the contact
        angle ``alpha`` (0 <= alpha <= alpha at onset).
    Other parameters as :func:`history`.

    Returns
    -------
    dict
        ``a, alpha, p, d, delta, f, G`` as floats (``delta`` NaN where |p| > 1).
    """
    if stage not in STAGES:
        raise InputError("stage", stage, f"one of {', '.join(STAGES)}")
    v, c, pc = _prepare(control, slip, p, d, w, rs, a_max, None, None, 2.0, 200)
    v["slip"] = slip
    d_fix, kappa = v.get("d"), v.get("p")
    locator = "alpha" if stage == "pinning" else "a"
    loc = alpha if stage == "pinning" else a
    if loc is None or not np.isfinite(loc):
        raise InputError(locator, loc, f"a number (the locator of stage '{stage}')")
    branch = BRANCHES[(stage, slip)]
    if stage == "making_contact":
        ctx = Context(c, v["w"], v["a_max"], np.nan)
        k = _mc_pressure(np.array([loc]), v, c) if pc else np.array([kappa])
        st = evaluate(branch, None, k, np.array([loc]), ctx)
    else:
        ctx, kappa_m = _ctx_after_loading(v, c, pc)
        ob, ol, ox, okp, path = _onset(slip, ctx, pc, kappa_m, d_fix)
        on = evaluate(ob, ox, okp, ol, ctx)
        k_on = float(np.real(on["p"][0]))
        if stage == "pinning":
            alpha_on = float(np.real(on["alpha"][0]))
            if not 0.0 <= loc <= alpha_on * (1 + 1e-12):
                raise InputError("alpha", loc, f"in [0, {alpha_on:.10g}] (the onset of delamination)")
            st = _pinning_at_alpha(branch, min(loc, alpha_on), ctx, pc, kappa, d_fix, kappa_m, on, path)
            return _finish(st, stage, control, slip, locator, loc, pc, d_fix)
        a_on = float(np.real(on["a"][0]))
        if not 0.0 < loc <= a_on * (1 + 1e-12):
            raise InputError("a", loc, f"in (0, {a_on:.10g}] (delamination runs from the onset inward)")
        # follow the branch from the onset, as the history does (selects the physical root)
        x_on = _delamination_start(slip, ox, on)
        if loc >= a_on:
            x, k = (None if x_on is None else np.array([x_on])), np.array([k_on])
        else:
            (_, xs, ks), _ = _follow(branch, a_on, np.array([loc]), x_on, k_on, ctx,
                                     d_fix if pc else None, log=True)
            x, k = (None if branch.target is None else xs), ks
        st = evaluate(branch, x, k, np.array([min(loc, a_on)]), ctx)
    return _finish(st, stage, control, slip, locator, loc, pc, d_fix)


def _pinning_at_alpha(branch, alpha, ctx, pc, kappa, d_fix, kappa_m, onset, path):
    """Pinned state at a given contact angle (no slip: the G with that angle, by brentq)."""
    def at(loc):
        if path is not None:
            kg = np.array([np.interp(loc, path[0], path[2])])
            xg = np.array([np.interp(loc, path[0], path[1])])
        else:
            kg, xg = np.array([kappa_m]), None
            if branch.slip == "frictionless":
                frac = loc / _pin_end(branch.slip, ctx)
                xg = np.array([ctx.a_m + (float(np.real(onset["a"][0])) - ctx.a_m) * frac])
        return _solve_rows(branch, np.array([loc]), ctx, pc, kappa, d_fix, kg, xg)[2]

    if branch.slip == "frictionless":
        return at(alpha)
    if alpha == 0.0:
        return at(0.0)
    def gap(g):
        return float(np.real(at(g)["alpha"][0])) - alpha

    if gap(ctx.w) <= 0.0:  # alpha is the onset's angle (to rounding): the state at G = w
        return at(ctx.w)
    G = brentq(gap, 0.0, ctx.w, xtol=1e-15, rtol=4 * np.finfo(float).eps, maxiter=200)
    return at(G)


def _finish(st, stage, control, slip, locator, loc, pc, d_fix):
    check_ok(st, stage, {"control": control, "slip": slip, locator: loc})
    out = _real(st, 0)
    if pc:
        out["d"] = d_fix
    out["delta"] = float(apex_deflection(out["p"])) - out["d"] if abs(out["p"]) <= 1 else float("nan")
    return out
