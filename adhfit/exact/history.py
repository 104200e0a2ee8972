"""A full loading history of the exact membrane: making contact, pinning, delamination (docs/contracts.md A2)."""
from __future__ import annotations

import math

import numpy as np
from scipy.optimize import brentq, minimize_scalar

from ..errors import ConvergenceError, DomainError, InputError
from ..histories import History
from .control import Control, prepare
from .march import PREDICT, vertex
from . import kernels as K
from .stages import PastVertical, Stage, branch_end, delamination, making_contact, onset, pinning
from .state import DEFAULT_N, Config, State

__all__ = ["exact_history", "COLUMNS"]

END_TOL = 1e-11  # the loading end condition (delta = delta_max or p = p_max) is solved to this
EXTREMUM_TOL = 1e-12  # residuals of the stencil states of an extremum (``_extremum``): 1e-14 took ~10 more
# shots a history and moved the summary by <= 1e-10 (lambda0 = 1.1-3, the four base cases), 1e-11 by 7e-10
SPLIT_FROM_STATE = 3  # march's first splits of a failed step continue from the last solved state
STENCIL_TOL = 1e-13  # the extremum's stencil states (``_extremum``): a row's observables carry ~10x its
# tolerance (the shotless last Newton step), and the stencil's vertex ~1e3x the observables' error:
# at 1e-12 a flat f_min's contact radius moved by 7e-9 with the row grid
COLUMNS = ("stage", "a", "alpha", "p", "d", "delta", "f", "G", "stable")
TURN_TOL = 1e-10  # a row counts as past the first turning point when the control has come back up by this
H_FINAL = 2e-3  # width of the extremum's last stencil, relative to the onset's rho_a (``_extremum``)


def _cluster(n):
    return 0.5 * (1.0 - np.cos(np.pi * np.arange(n) / (n - 1)))


def _split(points):
    n_mc = max(4, round(0.3 * points))
    n_pin = max(4, round(0.2 * points))
    return n_mc, n_pin, max(5, points - n_mc - n_pin + 2)


def _predict(v, vs, xs, x0):
    """Lagrange extrapolation through the last (up to) ``PREDICT`` solved states (as the compiled
    ``march.predict``; a failed step is split by ``march``)."""
    k = min(len(xs), PREDICT)
    if k == 0:
        return list(x0)
    if len(set(vs[-k:])) < k:
        return list(xs[-1])
    out = [0.0] * len(xs[-1])
    for i in range(1, k + 1):
        li = 1.0
        for j in range(1, k + 1):
            if j != i:
                li *= (v - vs[-j]) / (vs[-i] - vs[-j])
        out = [o + li * float(q) for o, q in zip(out, xs[-i])]
    return out


def march(stage: Stage, values, x0, depth: int = 0, *, stop_ok: bool = False, start=None,
          deep: int = None) -> list:
    """Solve ``stage`` at each value in turn, continuing from the previous states (Lagrange
    predictor); a failed step is split in two (up to 12 times). With ``stop_ok`` a branch that ends
    (a fold the parameter cannot pass) returns the states solved up to there instead of raising.
    ``start`` = (value, state): a solved state of the stage the march continues from (not returned),
    so that the first step too is split when it fails (a delamination march from the onset whose
    first row lies far from it, on a coarse grid); the first ``deep`` (``SPLIT_FROM_STATE``) splits of a
    step continue from it. Runs of rows are solved in one compiled call
    (``Stage.path``); a row that fails there is retried here (its error, or the split)."""
    out = []  # the states solved at values[:len(out)]
    vs = [] if start is None else [float(start[0])]  # their parameters (after the start's)
    xs = [] if start is None else [stage.x(start[1])]  # unknowns of the last (up to) PREDICT states
    last = None if start is None else start[1]
    k0 = len(vs)
    values = list(values)
    while len(out) < len(values):
        got = stage.path(values[len(out):], vs[-PREDICT:], xs, x0)
        out.extend(got)
        vs.extend(values[len(vs) - k0:len(vs) - k0 + len(got)])
        xs = (xs + [stage.x(st) for st in got[-PREDICT:]])[-PREDICT:]
        last = out[-1] if out else last
        if len(out) == len(values):
            break
        v = values[len(out)]
        try:
            st = stage.solve(v, _predict(v, vs, xs, x0))
        except ConvergenceError:
            if depth >= 12 or last is None:
                if stop_ok:
                    return out
                raise
            # the halves continue from the last solved state for the first few splits only: each split
            # of a step that fails for good (a branch end) costs a failed Newton solve, and 12 of them at
            # every stop doubled the time of a history (as before, deeper halves start from its unknowns)
            deep = SPLIT_FROM_STATE if deep is None else deep
            mid = march(stage, [0.5 * (vs[-1] + v), v], xs[-1], depth + 1, stop_ok=stop_ok,
                        start=(vs[-1], last) if depth < deep else None, deep=deep)
            if len(mid) < 2:
                out.extend(mid)
                if stop_ok:
                    return out
                raise
            st = mid[-1]
        out.append(st)
        last = st
        xs = (xs + [stage.x(st)])[-PREDICT:]
        vs.append(v)
    return out


def _loading_end(stage: Stage, c: Control) -> float:
    """a_max from delta_max or p_max: march the loading in a (a geometric grid, runs of 8 in one
    compiled call), then solve the end condition between the grid values that bracket it."""
    name, target = c.end
    value = (lambda s: c.free.d - s.d) if name == "delta_max" else (lambda s: s.p)
    cap = 0.95 * min(1.0, c.rs)
    grid = list(np.geomspace(1e-3 * cap, cap, 60))
    x0 = [c.free.lc, 1e-3 * cap / c.free.lc] + ([c.free.p] if c.control == "pressure" else [])
    vs, xs, sts = [], [], []
    while len(vs) < len(grid):
        got = stage.path(grid[len(vs):len(vs) + 8], vs[-PREDICT:], xs[-PREDICT:], x0)
        if not got:  # retried with march's step splitting; the loading ends where that fails
            try:
                got = march(stage, [grid[len(vs)]], xs[-1] if xs else x0)[-1:]
            except ConvergenceError:
                break
        for st in got:
            if value(st) >= target:
                if not vs:
                    raise InputError(name, target, "a value reached by a contact radius above 1e-3 a_max")
                return _end_root(stage, lambda s: value(s) - target, vs + [grid[len(vs)]], sts + [st])
            vs.append(grid[len(vs)])
            xs.append(stage.x(st))
            sts.append(st)
    top, a_top = (value(sts[-1]), vs[-1]) if vs else (value(c.free), 0.0)
    raise InputError(name, target, f"a value reached on loading (at most {top:.6g} here, "
                                   f"with contact radius {a_top:.4g})")


def _end_root(stage: Stage, resid, avals: list, sts: list) -> float:
    """The contact radius where ``resid`` of the state is 0, between the last two of ``avals`` (resid
    below 0, then at or above): inverse interpolation through the last (up to) four states and each
    new solve, bisection where it leaves the bracket, to |resid| < ``END_TOL`` (states are solved to
    1e-10: resid is not resolved much below that); the best of 10 solves otherwise."""
    lo, hi = avals[-2], avals[-1]
    pts = [(resid(st), a, st) for a, st in zip(avals[-4:], sts[-4:])]
    prev = hi
    for _ in range(10):
        a = _predict(0.0, [q[0] for q in pts[-4:]], [[q[1]] for q in pts[-4:]], [0.5 * (lo + hi)])[0]
        if not lo < a < hi:
            a = 0.5 * (lo + hi)
        st = stage.solve(a, stage.x(min(pts, key=lambda q: abs(q[1] - a))[2]))
        f = resid(st)
        pts.append((f, a, st))
        if abs(f) < END_TOL or abs(a - prev) <= 1e-14 * (1.0 + a):
            return a
        lo, hi, prev = (lo, a, a) if f >= 0.0 else (a, hi, a)
    return min(pts, key=lambda q: abs(q[0]))[1]


def _loading(cfg: Config, c: Control) -> tuple[list, State]:
    stage = making_contact(cfg, c.control, c.p, c.d)
    free = c.free
    if c.a_max is None:
        c.a_max = _loading_end(stage, c)
    a_vals = _cluster(c.n_mc)[1:] * c.a_max
    x0 = [free.lc, a_vals[0] / free.lc] + ([free.p] if c.control == "pressure" else [])
    raw = march(stage, a_vals, x0, stop_ok=True)
    vals = list(a_vals)
    if not raw:
        # the first row failed from the free state (the march has no solved state to split the step from):
        # led in on a geometric ramp from 1e-2 of it (on 10 rows the first row lies at a quarter of a_max:
        # Newton from the free state landed past vertical at the clamp, or lost its line search, where the
        # branch is Case I; 50 rows and more reach it)
        lead = [float(v) for v in np.geomspace(1e-2 * a_vals[0], a_vals[0], 9)[:-1]]
        vals = lead + vals
        raw = march(stage, vals, [free.lc, lead[0] / free.lc] + x0[2:], stop_ok=True)
    states = _at_values(raw, vals)[len(vals) - len(a_vals):]
    if len(states) < len(a_vals):
        # the Case I checks from the last states solved (the last one may lie at a split of the step to the
        # next row: its own contact radius, the next row's value past it)
        if raw:
            _case_one_end(stage, c, raw[-1], next((v for v in vals if v > raw[-1].a * (1.0 + 1e-9)), vals[-1]))
        if len(raw) > 1:
            _case_one_in_control(stage, c, raw[-2], raw[-1])
        march(stage, a_vals, x0)  # not shown to be the Case I limit: the march's own error
    states[-1] = _tight(stage, a_vals[-1], states[-1])
    return [free] + states, states[-1]


def _at_values(states, values):
    """The making-contact states up to the first whose contact radius is not its row's value: a march that
    stops while splitting a step returns the state it solved at the split (``march``), not at the row
    (seen on 10 rows: the row at a = 0.1044 was the state at 0.0979, next to the clamp's vertical, and the
    history went on from it where every finer grid proves the Case I end before a_max)."""
    k = next((i for i, (v, st) in enumerate(zip(values, states)) if abs(st.a - v) > 1e-9 * (1.0 + abs(v))),
             len(states))
    return states[:k]


def _tight(stage, value, st):
    """``st`` solved again to EXTREMUM_TOL: rows are solved to 1e-10 and agree with re-solves to ~1e-9,
    from predictors that depend on the row grid; the states the summary reports (the end of loading,
    the onset) and every later stage starts from must not (f_max moved by 3e-9 between 50 and 1001
    rows). ``st`` itself where that solve fails."""
    try:
        return stage.solve(value, stage.x(st), tol=EXTREMUM_TOL)
    except ConvergenceError:
        return st


def _case_one_end(stage, c, good, a_bad):
    """Making contact stopped between the solved Case I state ``good`` and ``a_bad``: when the state
    at ``a_bad`` solves and turns past vertical at the clamp, bisect the solved states between them
    for the Case I limit (every state solved from ``good``; one side Case I, the other past vertical)
    and raise the bound: an InputError for a_max under pressure control, a DomainError under
    displacement control (as the large-stretch model words them). Returns when not shown."""
    lo, hi = good.a, a_bad
    try:
        stage.solve(hi, stage.x(good))
        return
    except PastVertical:
        pass
    except ConvergenceError:
        return
    found = _bisect_case_one(stage, good, lo, hi)
    if found is None:
        return
    lo, good = found
    _raise_case_one(c, lo, "solved states either side of it, to 1e-10")


def _raise_case_one(c, lo, how):
    """The Case I limit of making contact at contact radius ``lo``: an InputError for a_max under pressure
    control, a DomainError under displacement control (as the large-stretch model words them)."""
    if c.control == "pressure":
        raise InputError("a_max", c.a_max, f"a number in [0.001, {lo:.6g}], the largest contact radius "
                         f"with a Case I exact membrane at d = {c.d:g}, lambda0 = {c.lambda0:g}",
                         "The membrane cannot reach a larger contact radius (its tangent would turn "
                         "past vertical at the clamp): lower a_max.")
    raise DomainError("the exact membrane would turn past vertical at the clamp while making contact "
                      "(Case I ends)", f"a_max must stay below {lo:.6g} at p = {c.p:g}, rs = {c.rs:g}, "
                      f"lambda0 = {c.lambda0:g} ({how})",
                      "lower a_max, or raise p",
                      {"control": c.control, "slip": c.slip, "p": c.p, "rs": c.rs, "lambda0": c.lambda0,
                       "a_max": c.a_max})


def _case_one_in_control(stage, c, before, good):
    """Making contact stopped at the solved Case I state ``good`` with no state at the next contact radius
    (near the Case I limit the branch can meet the clamp's vertical tangentially, with the contact
    radius nearly stationary): continue it in the control variable (d, or p under pressure control)
    from ``good`` the way it was going; a state past vertical at the clamp is bisected against the last
    solved one in the control to 1e-10 and raised as ``_case_one_end`` raises it. Returns when the
    continuation passes a_max (not an end) or stalls (not shown)."""
    val = _control_value(c)
    if c.control == "displacement":
        ctl = Stage(stage.cfg, "continuous", {"p": c.p}, ("lc", "rho_a"), ("clamp", "d"), {"d": good.d}, "d")
    else:
        ctl = Stage(stage.cfg, "continuous", {"p": good.p}, ("lc", "rho_a"), ("clamp", "d"), {"d": c.d}, "p")
    sgn = math.copysign(1.0, val(good) - val(before))
    h = max(abs(val(good) - val(before)), 1e-6)
    top = good.a
    for _ in range(400):
        v = val(good) + sgn * h
        try:
            st = ctl.solve(v, ctl.x(good))
        except PastVertical:
            found = _bisect_case_one(ctl, good, val(good), v, floor=1.0)
            if found is None:
                return
            good = found[1]
            _raise_case_one(c, max(top, good.a), "the largest contact radius on the branch, whose end "
                            "is bracketed by solved states in the control to 1e-10")
        except ConvergenceError:
            h *= 0.5
            if h < 1e-12 * (1.0 + abs(val(good))):
                return
            continue
        if st.a >= c.a_max:
            return
        good, h, top = st, 1.5 * h, max(top, st.a)


def _bisect_case_one(stage, good, lo: float, hi: float, floor: float = 0.0):
    """Bisect between the solved Case I state ``good`` (at ``lo``) and a parameter ``hi`` whose state turns
    past vertical at the clamp, to 1e-10 (relative to ``floor`` + |hi|; either direction): ``(lo, good)`` at
    the limit, or None when a state between them does not solve (the limit is then not shown)."""
    while abs(hi - lo) > 1e-10 * (floor + abs(hi)):
        mid = 0.5 * (lo + hi)
        try:
            good, lo = stage.solve(mid, stage.x(good)), mid
        except PastVertical:
            hi = mid
        except ConvergenceError:
            return None
    return lo, good


def _bracket(pin, c, m, top):
    """Steps in alpha along pinning from the loading end ``m`` until G >= w: (last state below w, its
    alpha, first state at or above w, its alpha), in one compiled call (``march.bracket_rows``: each
    step aims 3 % past where G ~ alpha^2 reaches w; failed steps and long steps finding G falling are
    halved)."""
    if _alpha_starts_elsewhere(c, m, pin):
        return _bracket_in_control(c, m, m)
    prev, prev_a, st, alpha = pin.bracket(pin.x(m), m.G, c.w, top)
    prev = m if prev is None else prev
    if (_presses_on(c, m, prev) or (st is not None and _presses_on(c, m, st))) and not _enters_at_once(c, m):
        # the alpha march took a branch that presses on: the one that retracts, where there is one (none
        # where its states have alpha < 0 at once, no slip: ``_enters_at_once``)
        try:
            return _bracket_in_control(c, m, m)
        except DomainError:
            raise
        except ConvergenceError:
            # none found: the branch that presses on is the history (docs/contracts.md A2: the control
            # rises at once, the end of loading is the turning point), and its ends are its own
            pass
    if st is None:
        _pinning_case_one_end(pin, c, prev, prev_a)
        return _bracket_in_control(c, m, prev)
    return prev, prev_a, st, alpha, None


def _enters_at_once(c, m) -> bool:
    """No slip: whether the pinning branch that retracts the control from the end of loading ``m`` has
    alpha < 0 at once (the membrane beside the pinned edge turned into the substrate: ``_enters``), shown
    by the state a small retraction away (1e-6 of the control, Newton from ``m`` at alpha = 0) and one ten
    times further, both with alpha < 0, the second ~10 times the first (alpha ~ the retraction). Then no
    admissible pinned state retracts the control: the branch that presses on is the history (docs/
    contracts.md A2: the end of loading is the turning point), as where none is found."""
    if c.slip != "no-slip":
        return False
    ctl = _control_stage(Config(c.lambda0, c.crv, c.n), c, m)
    val = _control_value(c)
    sgn = 1.0 if c.control == "displacement" else -1.0
    got = []
    for h in (1e-6, 1e-5):
        try:
            got.append(ctl.solve(val(m) + sgn * h * (1.0 + abs(val(m))), ctl.x(m)[:1] + [0.0]).alpha)
        except ConvergenceError:
            return False
    return got[0] < 0.0 and 5.0 < got[1] / got[0] < 20.0


def _presses_on(c, m, st) -> bool:
    """Whether the pinning state ``st`` lies beyond the end of loading ``m`` in the loading direction
    (d below its value, or p above it): off the branch that retracts from ``m``
    (``_alpha_starts_elsewhere``)."""
    v = _control_value(c)
    return (v(st) < v(m)) if c.control == "displacement" else (v(st) > v(m))


def _alpha_starts_elsewhere(c, m, pin) -> bool:
    """Whether the pinning branch that retracts the control (d rising, or p falling) from the end of
    loading is not the one a march in alpha from it follows. Near the end of loading two branches can
    leave it with alpha > 0, one retracting the control and one pressing on (seen: frictionless pinning on
    a small sphere, the second running to the sphere's equator); in alpha they are not told apart, in
    the control they are: the state a small retraction away (Newton from the end of loading) is solved
    again at its own alpha, and if that lands elsewhere the branch is followed in the control."""
    cfg = pin.cfg
    ctl = _control_stage(cfg, c, m)
    val = _control_value(c)
    sgn = 1.0 if c.control == "displacement" else -1.0
    try:
        s_r = ctl.solve(val(m) + sgn * 1e-4 * (1.0 + abs(val(m))), ctl.x(m)[:1] + [0.0])
    except ConvergenceError:
        return False
    if not s_r.alpha > 0.0:
        return False
    try:
        s_a = pin.solve(s_r.alpha, pin.x(m))
    except ConvergenceError:
        return True
    return abs(val(s_a) - val(s_r)) > 1e-7 * (1.0 + abs(val(m)))


def _pinning_case_one_end(pin, c, good, alpha_good):
    """Pinning stopped after the solved Case I state ``good`` (at ``alpha_good``) before G reached w:
    when a state a little further solves and turns past vertical at the clamp, bisect the solved
    states between them for the Case I limit and raise it as a DomainError. Returns when not shown."""
    lo, hi = alpha_good, None
    for step in (1e-8, 1e-6, 1e-4):
        try:
            pin.solve(alpha_good * (1.0 + step), pin.x(good))
        except PastVertical:
            hi = alpha_good * (1.0 + step)
            break
        except ConvergenceError:
            continue  # no state from this guess: a longer step may still show the limit
        else:
            return  # a Case I state past the stop: not its end
    if hi is None:
        return
    found = _bisect_case_one(pin, good, lo, hi)
    if found is None:
        return
    lo, good = found
    raise DomainError(f"the exact pinning branch ({c.slip}) turns past vertical at the clamp at alpha = "
                      f"{lo:.8g}, G = {good.G:.6g}, before G reaches w = {c.w:g} (the onset of "
                      "delamination; Case II beyond, outside the model)",
                      "solved states either side of it, to 1e-10 in alpha",
                      "lower w, or change the loading end",
                      {"control": c.control, "slip": c.slip, "w": c.w, "lambda0": c.lambda0,
                       "a_max": c.a_max, "locator": lo})


def _onset(cfg, c, m):
    """Bracket G = w along pinning (``_bracket``), then solve it. Returns (onset, the pinning stage in
    alpha, the stage in the control that continued it or None, the state where the march in alpha
    handed over to it)."""
    pin = pinning(cfg, c.control, c.slip, m, c.p, c.d)
    top = 0.5 * math.pi if c.slip == "frictionless" else math.pi
    prev, prev_a, st, alpha, ctl = _bracket(pin, c, m, top)
    turn = None
    if ctl is not None:
        ctl, turn = ctl
    on_stage = onset(cfg, c.control, c.slip, m, c.w, c.p, c.d)
    t = (c.w - prev.G) / (st.G - prev.G)
    guess = [a + t * (b - a) for a, b in zip(pin.x(prev), pin.x(st))]
    guess = guess[:1] + [prev.alpha + t * (st.alpha - prev.alpha)] + guess[1:]
    try:
        on = on_stage.solve(c.w, guess)
    except ConvergenceError:
        stage, par = (pin, lambda s: s.alpha) if ctl is None else (ctl, _control_value(c))
        on = _onset_between(stage, par, on_stage, pin, c, prev, st)
    on = _tight(on_stage, c.w, on)
    return on, pin, ctl, turn


def _onset_between(stage, par, on_stage, pin, c, prev, st):
    """The onset between the pinning states ``prev`` (G < w) and ``st`` (G >= w) when Newton on it from
    their interpolation failed: march the stage across the bracket on 8 steps, then Brent's method on
    G - w between the two states that bracket it, each solve started from the nearer of them."""
    vals = list(np.linspace(par(prev), par(st), 9)[1:])
    sts = [prev] + march(stage, vals, stage.x(prev), stop_ok=True)
    vs = [par(prev)] + vals[:len(sts) - 1]
    i = next((j for j in range(1, len(sts)) if sts[j].G >= c.w), None)
    if i is None:
        lo, hi, a, b = prev, st, par(prev), par(st)
    else:
        lo, hi, a, b = sts[i - 1], sts[i], vs[i - 1], vs[i]

    def g(v):
        near = lo if abs(v - a) <= abs(v - b) else hi
        return stage.solve(v, stage.x(near)).G - c.w
    try:
        v_on = brentq(g, a, b, xtol=1e-14)
        s_on = stage.solve(v_on, stage.x(lo))
        return on_stage.solve(c.w, pin.x(s_on)[:1] + [s_on.alpha] + pin.x(s_on)[1:])
    except (ValueError, ConvergenceError) as exc:
        raise ConvergenceError("exact pinning: onset G = w", {"w": c.w, "alpha": st.alpha}) from exc


def _pinning(cfg, c, m):
    """The pinning rows (sine-clustered toward the onset) and the onset. Marched in alpha; when the branch
    was continued in the control past a fold in alpha (``_bracket_in_control``), the first half of the
    rows is marched in alpha up to where that march handed over, the second half in the control."""
    on, pin, ctl, turn = _onset(cfg, c, m)
    c.pin_parts = []  # (stage, its states in path order, m or the handover and the onset included)
    if c.n_pin <= 2:
        return [on], on
    u = np.sin(0.5 * np.pi * np.arange(1, c.n_pin) / (c.n_pin - 1))[:-1]
    if ctl is None:
        try:
            rows, failed = _rows(pin, u * on.alpha, pin.x(m), c, (0.0, m)), None
        except (ConvergenceError, DomainError) as exc:
            # (seen on 1001 rows: the small steps took the branch that presses on, p rising to 1.21 above
            # the loading end's 0.99, and stalled near vertical at the clamp at alpha = 0.366, where 200
            # rows and the onset (alpha = 0.900) follow the one that retracts)
            rows, failed = None, exc
        if rows is None and _presses_on(c, m, on):
            raise failed
        if rows is None or not _presses_on(c, m, on) and any(_presses_on(c, m, s) for s in rows):
            # the rows' small first steps in alpha took the branch that presses on, the bracket's long step
            # the one that retracts (the onset's): two branches leave the end of loading with alpha > 0
            # (``_alpha_starts_elsewhere``). The history retracts: its rows are marched in alpha back from
            # the onset, on its branch (seen: frictionless, p = -0.496, rs = 0.116, lambda0 = 1.296; rows to
            # delta = 0.329 above delta_max = 0.277 and G = 1.014 w, then the onset at delta = 0.221)
            back = march(pin, list(u[::-1] * on.alpha), pin.x(on), stop_ok=True)
            if len(back) != len(u) or any(_presses_on(c, m, s) or not s.G <= c.w for s in back):
                if failed is not None:
                    raise failed
                raise ConvergenceError("exact pinning: rows on the onset's branch", {"w": c.w, "alpha": on.alpha})
            rows = back[::-1]
        c.pin_parts = [(pin, [m] + rows + [on])]
        return rows + [on], on
    val = _control_value(c)
    if turn is m:
        values = val(m) + u * (val(on) - val(m))
        rows = _rows_on_path(ctl, values, c) or _rows(ctl, values, ctl.x(m)[:1] + [0.0], c)
        c.pin_parts = [(ctl, [m] + rows + [on])]
        return rows + [on], on
    alphas = 2.0 * u[u < 0.5] * turn.alpha
    # a row at the handover itself (2 u = 1 to rounding: sin(pi/6) < 0.5 on 10 and 11 rows) is ``turn``: there
    # alpha is at its fold, where Newton in alpha does not converge (seen: no slip, p = -0.578)
    at = alphas >= turn.alpha * (1.0 - 1e-12)
    first = _rows(pin, alphas[~at], pin.x(m), c, (0.0, m)) + [turn] * int(np.count_nonzero(at))
    values = val(turn) + (2.0 * u[u >= 0.5] - 1.0) * (val(on) - val(turn))
    second = _rows_on_path(ctl, values, c) or _rows(ctl, values, ctl.x(turn), c)
    c.pin_parts = [(pin, [m] + first + [turn]), (ctl, [turn] + second + [on])]
    return first + second + [on], on


def _rows_on_path(stage, values, c):
    """Pinning rows in the control, each solved from the unknowns interpolated on the continuation that
    found the onset (``_bracket_in_control``, adaptive steps); None when there is none or a row fails
    (the caller then marches them). Marched from row to row (a Lagrange predictor through rows evenly
    spaced in d) the rows could not follow alpha rising from 0.4 to 2.6 while d moved by 0.05 (near a
    fold in d): Newton ran off to alpha + 2 pi k (alpha = 2.4e6) and the march failed later, a
    ConvergenceError in the stress run (p = -0.921, rs = 0.076, lambda0 = 1.557)."""
    out = []
    for v in values:
        g = _on_path(c, v, None)
        if g is None:
            return None
        try:
            st = stage.solve(v, g)
        except ConvergenceError:
            return None
        if abs(st.alpha - g[-1]) > 0.1 or _outside(c, st) is not None:
            return None  # not the continuation's state: the march decides (and names any end)
        out.append(st)
    return out


def _on_path(c, v, x0):
    """The unknowns at control value ``v`` interpolated on the continuation in the control that found the
    onset (``_bracket_in_control``), else ``x0``."""
    path = getattr(c, "ctl_path", None)
    if not path or len(path[0]) < 2:
        return x0
    vs, xs = np.asarray(path[0], dtype=float), np.asarray(path[1], dtype=float)
    order = np.argsort(vs)
    if not vs[order[0]] <= v <= vs[order[-1]]:
        return x0
    return [float(np.interp(v, vs[order], xs[order, j])) for j in range(xs.shape[1])]


def _rows(stage, values, x0, c, ref=None):
    """``march`` over pinning rows; a row whose state turns past vertical at the clamp (the bracket's
    long steps can pass over a stretch of the branch that leaves Case I) is bisected against the last
    solved row to 1e-10 and raised as the branch's Case I limit (a DomainError). ``ref`` = (value, state):
    the solved state ``x0`` is taken from, against which the first row is checked (``_march_smooth``)."""
    states = _march_smooth(stage, list(values), x0, ref=ref)
    if len(states) == len(values):
        return states
    good = states[-1] if states else None
    if good is not None:
        v_bad = values[len(states)]
        try:
            stage.solve(v_bad, stage.x(good))
        except PastVertical:
            lo = getattr(good, stage.param) if stage.param == "alpha" else _control_value(c)(good)
            found = _bisect_case_one(stage, good, lo, v_bad, floor=1.0)
            if found is not None:
                lo, good = found
                name = stage.param if stage.param == "alpha" else ("d" if c.control == "displacement" else "p")
                _pinning_end(c, name, lo, good, "turns past vertical at the clamp (Case II beyond, outside the "
                             f"model)", f"alpha = {good.alpha:.8g}, theta at the clamp {good.theta_end:.8g}")
        except ConvergenceError:
            pass
    # not shown to be the Case I limit: on a grid four times finer from the last row (each split from the
    # last solved state; on 10 rows a step in alpha jumped onto a state past vertical at the clamp that
    # 1001 rows never meet), else the march's own error
    values = list(values)
    base = states[-1] if states else None
    fine = ([getattr(base, stage.param)] if base is not None else [2 * values[0] - values[1]] if len(values) > 1
            else [values[0]]) + values[len(states):]
    rest = list(np.concatenate([np.linspace(a, b, 5)[1:] for a, b in zip(fine[:-1], fine[1:])]))
    try:
        more = march(stage, rest, stage.x(base) if base is not None else x0, stop_ok=True,
                     start=(getattr(base, stage.param), base) if base is not None else None, deep=12)
    except ConvergenceError:
        more = []
    if len(more) == len(rest) and all(abs(st.theta_end) < 0.5 * math.pi for st in more):
        return states + more[3::4]
    return march(stage, values, x0)




JUMP = 0.1  # the largest change of the clamp tangent theta(1) between pinning rows taken without a check


def _march_smooth(stage, values, x0, start=None, depth: int = 0, ref=None) -> list:
    """``march`` (stop_ok) whose rows do not jump between branches: a row whose clamp tangent differs from
    the previous row's by more than JUMP (over a step longer than 1e-3, as ``march.bracket_rows`` checks
    its steps) is marched again from the previous row on eight steps, each checked the same way (up to
    4 times deep); the rows up to where such a march stops (the caller handles the stop). Seen: no
    slip, displacement control, p = -0.578, 200 rows: from alpha = 0.42 (theta(1) = -1.10, lambda1+ =
    1.00) the next row (alpha = 0.63) solved on another branch (theta(1) = -0.15, lambda1+ = 0.70) and the
    march stalled on it; on steps of 1e-3 the branch has theta(1) = -1.18 and lambda1+ = 0.98 there; on 50
    rows the first row did, checked against ``ref`` (the solved state ``x0`` is from, when not ``start``)."""
    states = march(stage, values, x0, stop_ok=True, start=start)
    prev = start or ref
    for k, st in enumerate(states):
        if prev is not None and abs(st.theta_end - prev[1].theta_end) > JUMP and abs(values[k] - prev[0]) > 1e-3 \
                and depth < 4:
            sub = list(np.linspace(prev[0], values[k], 9)[1:])
            got = _march_smooth(stage, sub, stage.x(prev[1]), prev, depth + 1)
            if len(got) < len(sub):
                return states[:k]
            return states[:k] + [got[-1]] + _march_smooth(stage, values[k + 1:], stage.x(got[-1]),
                                                          (values[k], got[-1]), depth)
        prev = (values[k], st)
    return states


def _control_value(c):
    """The control variable of a state: the gap d under displacement control, p under pressure control."""
    return (lambda s: s.d) if c.control == "displacement" else (lambda s: s.p)


def _control_stage(cfg, c, m) -> Stage:
    """Pinning parameterized by the control variable (d, or p under pressure control) with the contact
    angle among the unknowns: it follows the branch through a fold in alpha (alpha rising to a maximum
    and falling again while d keeps rising and G keeps growing), which a march in alpha cannot pass."""
    fx = {"rho_a": m.rho_a}
    if c.slip == "frictionless":
        edge, unk = "frictionless", ("lc", "alpha")
    else:
        edge, unk = "given", ("l1p", "alpha")
        fx["lc"] = m.lc
    if c.control == "displacement":
        return Stage(cfg, edge, {**fx, "p": c.p}, unk, ("clamp", "d"), {"d": m.d}, "d")
    return Stage(cfg, edge, {**fx, "p": m.p}, unk, ("clamp", "d"), {"d": c.d}, "p")


def _outside(c, st) -> str | None:
    """Why a solved Case I state is outside the membrane model, or None: a line tension at the contact
    edge (either side: the contact region's least tension is at its edge) that is not positive (the
    membrane slack or in compression: it would wrinkle), or a contact edge at or past the equator of
    the sphere (a >= rs: the membrane would wrap under it)."""
    # the contact field's r = rs sin(s/rs) reaches rs at a finite s and sticks there (dr = 0 beyond):
    # an edge within 1e-6 of rs has its material past the equator
    if st.rho_a > 0.0 and c.crv > 0.0 and not st.a * c.crv < 1.0 - 1e-6:
        return "equator"
    t = min(min(K.tensions(st.l1m, st.l2a)), min(K.tensions(st.l1p, st.l2a)))
    return None if t > 0.0 else "slack"


def _enters(c, st) -> str | None:
    """"enters" when the no-slip pinning state ``st`` has alpha < 0: the free membrane beside the pinned
    edge turned below the substrate's tangent, i.e. into the substrate (the contact edge would advance,
    outside the pinning model; as delamination's branch end, docs/numerics.md B5); else None."""
    return "enters" if c.slip == "no-slip" and st.alpha < 0.0 else None


def _bracket_in_control(c, m, prev):
    """The alpha march of pinning stopped at ``prev`` before G reached w: continue the branch in the
    control variable (``_control_stage``) until G >= w (returns the bracket as ``_bracket``), or prove
    where it ends before that: the clamp turning past vertical, a line tension at the contact edge
    reaching 0 (frictionless pinning: T1- = T1+ cos(alpha) -> 0 as alpha -> pi/2; or a compressive
    hoop tension), or the contact edge reaching the sphere's equator. Each is bisected between solved
    states in the control to 1e-10 and raised as a DomainError; a continuation that stalls anywhere
    else is a ConvergenceError."""
    cfg = Config(c.lambda0, c.crv, c.n)
    ctl = _control_stage(cfg, c, m)
    val = _control_value(c)
    v0, v1 = val(m), val(prev)
    # from the end of loading: the way the control retracts (d rising, p falling); from the alpha march's
    # last state: on the way it was going
    sgn = math.copysign(1.0, v1 - v0) if v1 != v0 else (1.0 if c.control == "displacement" else -1.0)
    h = max(abs(v1 - v0) / 20.0, 1e-3 * (1.0 + abs(v0)))
    good = prev  # solved (in alpha): the same equations
    # from the end of loading alpha starts at 0 with an infinite slope in the control (alpha ~ (d - d_m)^2
    # where two branches leave it): Newton starts from a small alpha > 0
    vs, xs = [v1], [ctl.x(prev)[:1] + [prev.alpha if prev is not m else 1e-3]]
    for _ in range(2000):
        v = vs[-1] + sgn * h
        why = None
        try:
            st = ctl.solve(v, _predict(v, vs[-3:], xs[-3:], xs[-1]))
            if abs(st.theta_end - good.theta_end) > 0.1 or abs(st.alpha - good.alpha) > 0.1:
                raise ConvergenceError("a step onto another branch")  # as the alpha march's guard
            why = _outside(c, st) or _enters(c, st)
        except PastVertical:
            why = "vertical"
        except ConvergenceError:
            h *= 0.5
            if h < 1e-10 * (1.0 + abs(vs[-1])):
                break
            continue
        if why is not None:
            _control_end(ctl, c, good, vs[-1], v, why)  # raises when the end is shown
            h *= 0.5
            if h < 1e-10 * (1.0 + abs(vs[-1])):
                break
            continue
        if st.G >= c.w:
            c.ctl_path = (vs + [v], xs + [ctl.x(st)])  # start guesses for pinning's rows (``_pinning``)
            return good, good.alpha, st, st.alpha, (ctl, prev)
        good = st
        vs.append(v)
        xs.append(ctl.x(st))
        h *= 1.5
    last = good
    if c.slip == "frictionless" and last.alpha > 0.5 * math.pi - SLACK_NEAR:
        _slack_end(cfg, c, ctl, last)  # raises where the branch's own states show the end below w
    if c.crv > 0.0 and last.a * c.crv > 1.0 - 1e-4:
        raise DomainError(f"the exact pinning branch ({c.slip}) carries the contact edge to the sphere's "
                          f"equator (a = rs) before G reaches w = {c.w:g}: wrapping past it is outside the "
                          "model", f"the branch stalls at a = {last.a:.8g} (rs = {c.rs:.8g}, "
                          f"{c.control} control at {val(last):.8g}) with G = {last.G:.6g} < w",
                          "lower w, or change the loading end",
                          {"control": c.control, "slip": c.slip, "w": c.w, "lambda0": c.lambda0,
                           "a_max": c.a_max, "rs": c.rs})
    _control_fold(cfg, c, ctl, last, prev)  # raises where the stall is the branch's extremum of the control
    raise ConvergenceError("exact pinning: G does not reach w before the pinning branch (continued in "
                           "the control variable) stalls",
                           {"w": c.w, "alpha": last.alpha, "G": last.G, "lc": last.lc, "lambda0": c.lambda0})


SLACK_NEAR = 1e-3  # a frictionless pinning continuation stalled this close to alpha = pi/2 is followed to its end
SLACK_LAST = 1e-10  # ... in the contact stretch, down to lambda_c - 1 = this (T1- ~ 6e-10)
SLACK_GAP = 1e-6  # ... or to pi/2 - alpha = this (Newton's difference step in alpha is 1.6e-7)
SLACK_STATES = 6  # ... on at least this many states
SLACK_ANCHOR = 4.0  # ... from a state this many SLACK_GAP from pi/2 where it stalled closer
SLACK_STEP = 0.5  # ... on steps of lambda_c - 1 by this factor (0.25 from pi/2 - 1.3e-5 did not solve)


def _slack_end(cfg, c, ctl, last):
    """Frictionless pinning continued in the control stalled at ``last`` near alpha = pi/2 with G < w: the
    edge's balance T1- = T1+ cos(alpha) takes the contact region's tension to 0 as alpha -> pi/2 (its
    stretch lambda_c -> 1: slack, outside a membrane model), where the continuation in the control meets
    a singular Jacobian (seen at pi/2 - 1.1e-5, seed 11). Followed on the branch parameterized by the
    contact stretch itself (unknowns alpha, and p under pressure control, as ``_control_fold``) from
    ``last`` toward lambda_c = 1 on geometric steps (to ``SLACK_LAST``, or pi/2 - alpha = ``SLACK_GAP``;
    back from ``last`` too where that leaves fewer than ``SLACK_STATES`` states): when every state solves
    in Case I, alpha rises toward pi/2, G stays below w and its rise shrinks geometrically (the rest of
    it bounded by the last step's, summed as a geometric series, twice), G does not reach w before the
    branch ends slack: raised as a DomainError. Returns when not shown."""
    name = ctl.unknowns[0]  # lc (frictionless)
    if c.control == "displacement":
        st = Stage(cfg, ctl.edge, {**ctl.fixed, name: last.lc}, ("alpha",), ("clamp",), {}, name)
    else:
        fixed = {k: v for k, v in ctl.fixed.items() if k != "p"}
        st = Stage(cfg, ctl.edge, {**fixed, name: last.lc}, ("alpha", "p"), ("clamp", "d"), {"d": c.d}, name)

    def step(seq, r):
        # cos(alpha) = T1-/T1+ with T1- ~ 6 (lambda_c - 1): pi/2 - alpha (and p) linear in lambda_c - 1
        # along the branch's end; a guess at the last alpha put T1+ far off and the free membrane's shot
        # failed
        prev = seq[-1]
        guess = [0.5 * math.pi - (0.5 * math.pi - prev.alpha) * r]
        if len(st.unknowns) > 1:
            guess.append(prev.p if len(seq) < 2 else prev.p + (prev.p - seq[-2].p) * (r - 1.0) / (
                1.0 - (seq[-2].lc - 1.0) / (prev.lc - 1.0)))
        seq.append(st.solve(1.0 + (prev.lc - 1.0) * r, guess))

    gap = 0.5 * math.pi - last.alpha
    if 0.0 < gap < SLACK_GAP and last.lc > 1.0:
        # a stall closer to pi/2 than Newton's difference step allows (seen: pi/2 - 1.2e-8 on 50 rows, where
        # 10, 11 and 200 rows stall farther out): a step back doubling lambda_c - 1 did not converge there.
        # The branch is followed from a state at pi/2 - alpha = SLACK_ANCHOR * SLACK_GAP instead (pi/2 - alpha
        # is linear in lambda_c - 1 along the end), as a stall there is
        r = SLACK_ANCHOR * SLACK_GAP / gap
        guess = [0.5 * math.pi - SLACK_ANCHOR * SLACK_GAP] + ([last.p] if len(st.unknowns) > 1 else [])
        try:
            last = st.solve(1.0 + (last.lc - 1.0) * r, guess)
        except ConvergenceError:
            return
        if not (last.G < c.w and 0.0 < 0.5 * math.pi - last.alpha):
            return
    down, up = [last], [last]
    try:
        # toward the end down to pi/2 - alpha = SLACK_GAP (Newton's difference step in alpha, 1.6e-7, must
        # not cross pi/2: T1+ = T1- / cos(alpha) is undefined beyond) or lambda_c - 1 = SLACK_LAST ...
        while len(down) < 60 and down[-1].lc - 1.0 > SLACK_LAST and 0.5 * math.pi - down[-1].alpha > SLACK_GAP:
            step(down, SLACK_STEP)
        # ... and back from it (a stall closer to pi/2 than that) until there are SLACK_STATES states
        while len(down) + len(up) - 1 < SLACK_STATES:
            step(up, 1.0 / SLACK_STEP)
    except ConvergenceError:
        return
    seq = up[::-1] + down[1:]
    al = [q.alpha for q in seq]
    gs = [q.G for q in seq]
    if not all(a0 < a1 < 0.5 * math.pi for a0, a1 in zip(al, al[1:])):
        return
    if any(_outside(c, q) not in (None, "slack") for q in seq) or not max(gs) < c.w:
        return
    steps = np.diff(gs)
    ratio = max(abs(steps[-1] / steps[-2]) if steps[-2] != 0.0 else 0.0,
                abs(steps[-2] / steps[-3]) if steps[-3] != 0.0 else 0.0)
    if not ratio < 0.9:
        return
    top = gs[-1] + 2.0 * abs(steps[-1]) * ratio / (1.0 - ratio)  # twice the geometric series' rest
    if not top < c.w:
        return
    end = seq[-1]
    t = min(K.tensions(end.l1m, end.l2a))
    raise DomainError(f"the exact pinning branch (frictionless) {_END_WORDS['slack']} as alpha -> pi/2 "
                      f"(T1- = T1+ cos(alpha)), before G reaches w = {c.w:g}",
                      f"followed in the contact stretch to lambda_c - 1 = {end.lc - 1.0:.2g} (alpha = pi/2 - "
                      f"{0.5 * math.pi - end.alpha:.2g}, least edge tension {t:.3g}): G = {end.G:.8g} < w, at most "
                      f"{top:.8g} at the slack end (its rise shrinking by {ratio:.3g} a step)",
                      "lower w, or change the loading end",
                      {"control": c.control, "slip": c.slip, "w": c.w, "lambda0": c.lambda0,
                       "a_max": c.a_max})


def _control_fold(cfg, c, ctl, last, start):
    """The continuation of pinning in the control stalled at ``last`` with G < w: when that is the
    branch's largest retraction of the control (a fold in d, or in p under pressure control), shown on
    the branch parameterized by the edge's other unknown (lambda1+ with no slip, lc frictionless) -- solved
    states either side of it retracting the control less, the extremum located between them -- with G
    < w there and falling past it, raise it as a DomainError: no pinned state retracts the control
    further and the edge does not delaminate (the membrane would come off dynamically, outside the
    quasi-static model). ``start``: where the continuation started (the fold's other side is past it).
    Returns when not shown."""
    name = ctl.unknowns[0]
    if c.control == "displacement":
        fx = Stage(cfg, ctl.edge, {**ctl.fixed, name: getattr(last, name)}, ("alpha",), ("clamp",), {}, name)
    else:
        fixed = {k: v for k, v in ctl.fixed.items() if k != "p"}
        fx = Stage(cfg, ctl.edge, {**fixed, name: getattr(last, name)}, ("alpha", "p"), ("clamp", "d"),
                   {"d": c.d}, name)
    val = _control_value(c)
    sgn = 1.0 if c.control == "displacement" else -1.0  # retracting: d rising, p falling
    x0 = float(getattr(last, name))
    try:
        mid = fx.solve(x0, fx.x(last))
    except ConvergenceError:
        return
    sts = _fold_bracket(fx, mid, x0, val, sgn, 1e-3 * (1.0 + abs(x0)))
    if sts is None:
        # (seed 7: the first step of 1.9e-3 in lambda1+ past the fold, onto states with alpha < 0, failed
        # from the fold's unknowns; on steps of 1.9e-4 each side solves)
        sts = _fold_bracket(fx, mid, x0, val, sgn, 1e-4 * (1.0 + abs(x0)))
    if sts is None:
        return
    xs = sorted(sts)
    states = [sts[x] for x in xs]
    fold = _extremum(fx, states, val, -sgn, scale=xs[-1] - xs[0])
    if not fold.G < c.w or not all(st.G < c.w for st in states) or abs(fold.theta_end) >= 0.5 * math.pi:
        return
    if _outside(c, fold) is not None:
        return
    # past the fold (the side the continuation did not reach) G falls: it does not reach w there either
    k = int(np.argmax([sgn * val(st) for st in states]))
    ahead = states[k + 1:] if float(getattr(start, name)) < xs[k] else states[:k][::-1]
    if not ahead:
        return
    vname = "d" if c.control == "displacement" else "p"
    how = "G falling past it"
    if not ahead[-1].G < fold.G:
        # G rises past the fold: shown not to reach w there only where that side of the branch ends first,
        # at alpha = 0 (the membrane tangent to the substrate at the pinned edge; alpha < 0 would enter it)
        end = _fold_side_to_alpha_zero(fx, c, fold, ahead[-1])
        if end is None:
            return
        how = (f"past it the branch returns ({vname} going back) to alpha = 0 at {vname} = {val(end):.8g}, G < w "
               f"on the way and G = {end.G:.6g} there (the membrane tangent to the substrate at the pinned "
               "edge; beyond, it would enter it)")
    raise DomainError(f"the exact pinning branch ({c.slip}) retracts the control at most to {vname} = "
                      f"{val(fold):.10g} (alpha = {fold.alpha:.8g}, G = {fold.G:.6g}), before G reaches w = "
                      f"{c.w:g}: no pinned state beyond it, and the contact edge does not delaminate there "
                      "(the membrane would come off dynamically, outside the quasi-static model)",
                      f"the control's extremum along the branch parameterized by {name}, between solved "
                      f"states either side retracting it less; {how}",
                      "lower w, or change the loading end",
                      {"control": c.control, "slip": c.slip, "w": c.w, "lambda0": c.lambda0,
                       "a_max": c.a_max, "locator": val(fold)})


def _fold_bracket(fx, mid, x0, val, sgn, h):
    """States of ``fx`` about ``mid`` (at ``x0``) on steps starting at ``h`` and doubling, widened until
    both sides retract the control (sgn * val) less than a state between them: {parameter: state}, or
    None when a step fails or 12 widenings do not bracket it."""
    sts = {x0: mid}
    for _ in range(12):
        for side in (-1.0, 1.0):
            xs = sorted(sts)
            near = xs[0] if side < 0 else xs[-1]
            v = near + side * h
            try:
                sts[v] = fx.solve(v, fx.x(sts[near]))
            except ConvergenceError:
                return None
        xs = sorted(sts)
        vals = [sgn * val(sts[x]) for x in xs]
        k = int(np.argmax(vals))
        if 0 < k < len(xs) - 1:
            return sts
        h *= 2.0
    return None


def _fold_side_to_alpha_zero(fx, c, fold, beyond):
    """Past a fold of the control on pinning (``_control_fold``, the branch ``fx`` parameterized by the
    edge's other unknown), on the side of the solved state ``beyond``: march from it away from the fold on
    steps of ``FOLD_STEP`` (each failed step split) while alpha > 0 and G < w, and locate alpha = 0 between
    the last state with alpha > 0 and the first with alpha < 0 (regula falsi, each state solved from the
    nearer, to |alpha| < 1e-12 or the parameter to 1e-14). Returns the end state (every state on the way
    with G < w, in Case I and inside the model), or None when that is not shown."""
    par = lambda st: float(getattr(st, fx.param))  # noqa: E731
    sgn = math.copysign(1.0, par(beyond) - par(fold))
    h = FOLD_STEP * (1.0 + abs(par(fold)))
    values = [par(beyond) + sgn * h * j for j in range(1, FOLD_STEPS + 1)]
    try:
        sts = march(fx, values, fx.x(beyond), stop_ok=True, start=(par(beyond), beyond), deep=12)
    except ConvergenceError:
        return None
    lo = beyond
    for st in sts:
        if not st.G < c.w or abs(st.theta_end) >= 0.5 * math.pi:
            return None
        if st.alpha < 0.0:
            hi = st
            break
        if _outside(c, st) is not None:
            return None
        lo = st
    else:
        return None
    try:
        for _ in range(100):
            if abs(par(hi) - par(lo)) <= 1e-14 * (1.0 + abs(par(lo))) or 0.0 <= lo.alpha < 1e-12:
                break
            t = min(max(lo.alpha / (lo.alpha - hi.alpha), 0.05), 0.95)
            v = par(lo) + t * (par(hi) - par(lo))
            st = fx.solve(v, fx.x(lo if t < 0.5 else hi))
            if st.alpha >= 0.0:
                lo = st
            else:
                hi = st
    except ConvergenceError:
        return None
    if not lo.G < c.w or _outside(c, lo) is not None or not abs(lo.alpha) < 1e-8:
        return None
    return lo


FOLD_STEP = 2.5e-4  # steps of ``_fold_side_to_alpha_zero`` in the edge's other unknown (relative to 1 + |it|)
FOLD_STEPS = 400  # ... at most this many


_END_WORDS = {
    "vertical": "turns past vertical at the clamp (Case II beyond, outside the model)",
    "slack": "has a line tension at the contact edge fall to 0 (the membrane going slack, or into "
             "compression, where it would wrinkle: outside a membrane model)",
    "equator": "carries the contact edge to the sphere's equator (a = rs: wrapping past it is outside "
               "the model)",
    "enters": "turns the membrane beside the pinned edge into the substrate (alpha < 0 beyond: the contact "
              "edge would advance, outside the pinning model)"}


def _control_end(ctl, c, good, v_good, v_bad, why):
    """Bisect in the control between the valid state ``good`` (at ``v_good``) and ``v_bad`` whose state is
    outside the model for the reason ``why``; raise the end as a DomainError when every state between
    solves (returns otherwise: not shown)."""
    lo, hi = v_good, v_bad
    while abs(hi - lo) > 1e-10 * (1.0 + abs(hi)):
        mid = 0.5 * (lo + hi)
        try:
            st = ctl.solve(mid, ctl.x(good))
            bad = _outside(c, st) or _enters(c, st)
        except PastVertical:
            bad = "vertical"
        except ConvergenceError:
            return
        if bad is None:
            good, lo = st, mid
        elif bad == why:
            hi = mid
        else:
            return
    name = "d" if c.control == "displacement" else "p"
    _pinning_end(c, name, lo, good, _END_WORDS[why], f"alpha = {good.alpha:.8g}, a = {good.a:.6g}")


def _pinning_end(c, name: str, lo: float, good, what: str, state: str):
    """Raise the DomainError of a pinning branch that ends (``what``) at control or alpha ``lo`` before G
    reaches w, bracketed by solved states to 1e-10; ``state`` describes the last solved one."""
    raise DomainError(f"the exact pinning branch ({c.slip}) {what} at {name} = {lo:.10g} ({state}), before G "
                      f"reaches w = {c.w:g}: G = {good.G:.6g} there (the onset of delamination)",
                      f"solved states either side of it, to 1e-10 in {name}",
                      "lower w, or change the loading end",
                      {"control": c.control, "slip": c.slip, "w": c.w, "lambda0": c.lambda0,
                       "a_max": c.a_max, "locator": lo})


def _delamination(cfg, c, m, on):
    """Delamination rows from the onset toward detachment: (states, stage, branch end or None).

    A no-slip branch that ends (alpha reaches 0, docs/numerics.md B5) stops at that state and
    returns its contact radius as the branch end. A march that stops anywhere else is retried on a
    grid four times finer from where it stopped; if that stops too, the history is not finished and
    a ConvergenceError says where (never a truncated history labelled as a branch end)."""
    stage = delamination(cfg, c.control, c.slip, m, c.w, c.p, c.d)
    g = (1.0 - _cluster(c.n_del)[1:]) ** 1.5
    g[-1] = min(g[-2] * 0.5, 1e-3)
    rho = on.rho_a * g
    # continued from the onset itself, so that a first step that fails is split (on 10 rows the first
    # delamination row lies 20 % of rho_a from the onset: the step failed, or passed the branch end)
    # on steps no longer than DEL_STEP of the onset's rho_a, the history's rows picked from them: on 10 rows
    # the first step (rho_a 0.646 -> 0.510) landed on another branch (a = 0.955 beyond the onset's 0.915,
    # p rising to 11 where 50 and 1001 rows have it fall to 2.9), and the march stalled on it at a = 0.661
    # (seen: pressure control, frictionless, d = 0.000476, rs = 10.47, lambda0 = 1.398)
    fine, keep = _fine_grid(on.rho_a, rho, DEL_STEP * on.rho_a)
    sol = march(stage, fine, stage.x(on), stop_ok=True, start=(on.rho_a, on))
    states = [sol[i] for i in keep if i < len(sol)]
    no_slip = c.slip == "no-slip"
    cut = next((i for i, s in enumerate(sol) if no_slip and s.alpha < 0.0), len(sol))
    _equator_between(stage, c, [on] + sol[:cut], fine[cut] if cut < len(fine) else None)
    past = None
    if no_slip:  # past alpha = 0 the membrane would enter the substrate: the branch ends there
        k = next((i for i, s in enumerate(states) if s.alpha < 0.0), len(states))
        past = states[k] if k < len(states) else None
        states = states[:k]
    crossed = False
    ends = lambda sts: no_slip and (crossed or (sts[-1] if sts else on).alpha < 0.2)  # noqa: E731
    if len(states) < len(rho) and not ends(states):
        try:
            states = _finish(stage, states, rho, c, no_slip, on)
        except ConvergenceError:
            # the march on the fine steps itself passed alpha = 0 between two of its states (the history's
            # rows skip them): the branch end is bracketed there (seen: no slip, 10 rows, the last row before
            # it at alpha = 0.55, the retry from it stalling at alpha = 0.204 where 50 rows reach the end)
            j = next((i for i, st in enumerate(sol) if st.alpha < 0.0), 0) if no_slip else 0
            if j == 0 or (states and states[-1].rho_a <= sol[j - 1].rho_a):
                raise
            states, past, crossed = states + [sol[j - 1]], sol[j], True
    if len(states) < len(rho) and ends(states) and (states or on.alpha >= 0.0):
        # (an onset at alpha < 0, reached by pinning continued in the control, has no branch from it)
        last = states[-1] if states else on
        x = [last.l1p, last.rho_a] + ([last.p] if c.control == "pressure" else [])
        off = lambda st: st is None or not (st.rho_a <= last.rho_a and st.a <= on.a * (1.0 + 1e-12))  # noqa: E731
        try:
            end = branch_end(cfg, c.control, m, c.w, c.p, c.d).solve(0.0, x, tol=EXTREMUM_TOL)
        except ConvergenceError:
            end = None  # (seen on 10 rows: Newton from the onset, alpha = 0.049, lost its line search)
        if off(end) and past is not None:  # else bracketed between the last row and the next (alpha < 0)
            end = _alpha_zero(stage, last, past) or end
        if off(end):
            # retried: the branch marched from the last state on short steps in rho_a until alpha < 0,
            # the end bracketed between the states either side (``_alpha_zero``)
            end = _end_by_march(stage, last, on) or end
        if end is None:
            raise ConvergenceError("exact delamination (no-slip): the branch end (alpha = 0) from the last "
                                   f"state (a = {last.a:.6g}, alpha = {last.alpha:.4g}) and on short steps "
                                   "toward it", {"w": c.w, "lambda0": c.lambda0, "a_max": c.a_max})
        if off(end):
            # another state of the end equations (seen: a = 0.2405 beyond the onset's 0.2369, solved
            # from the onset on 10 rows), not this branch's end
            raise ConvergenceError("exact delamination (no-slip): the branch end (alpha = 0) solved off the "
                                   f"branch (a = {end.a:.6g}, onset a = {on.a:.6g})",
                                   {"w": c.w, "lambda0": c.lambda0, "a_max": c.a_max})
        states.append(end)
        return states, stage, states[-1].a
    if not states:
        raise ConvergenceError("exact delamination: no quasi-static branch from the onset",
                               {"w": c.w, "lambda0": c.lambda0})
    return states, stage, None


EQUATOR_NEAR = 0.05  # a sampled local minimum of 1 - a/rs along delamination below this is refined (``_equator_between``)


def _equator_between(stage, c, sts, nxt=None):
    """The contact edge at the sphere's equator between delamination states: the rows are checked
    (``_check_membrane``), not what lies between them, and the edge can approach the equator and turn
    back inside one step (coarse rows gave a history where 1001 rows reach a = rs). Every solved state of
    the march (``sts``, on steps of at most DEL_STEP of the onset's rho_a, in path order) is checked, and
    each sampled local minimum of the margin 1 - a/rs below ``EQUATOR_NEAR`` is refined by marching the
    branch between its neighbours on finer steps (``_equator_refine``); a state whose edge is at the
    equator (``_outside``) is raised as ``_check_membrane`` raises it. ``nxt``: the value the
    march failed at (it stopped after ``sts[-1]``): a least margin at the last state is refined toward it.
    Returns when none is."""
    if not c.crv > 0.0 or len(sts) < 2:
        return
    _check_membrane(c, [("delamination", s) for s in sts[1:]])
    par = lambda st: float(st.rho_a)  # noqa: E731
    marg = [1.0 - st.a * c.crv for st in sts]
    n = len(sts)
    for j in range(n):
        # a sampled local minimum, the march's ends included (the onset: the edge can run to the equator
        # within the first step, seen on 10 rows where 1001 rows have it there at once)
        left = marg[j - 1] if j > 0 else math.inf
        right = marg[j + 1] if j + 1 < n else math.inf
        if j == n - 1 and nxt is not None and marg[j] <= left and marg[j] < EQUATOR_NEAR:
            # the march stopped here: the edge may reach the equator before the value it failed at
            _equator_refine(stage, c, sts[j], float(nxt), marg[j])
        if not (marg[j] <= left and marg[j] <= right and marg[j] < EQUATOR_NEAR):
            continue
        _equator_refine(stage, c, sts[max(j - 1, 0)], par(sts[min(j + 1, n - 1)]), marg[j])


EQUATOR_SUB = 64  # ... on this many steps between its neighbours
EQUATOR_LEVELS = 3  # ... and again about the least of them, this many times


def _equator_refine(stage, c, s0, v1, m0):
    """March the delamination branch from the solved state ``s0`` to rho_a = ``v1`` on ``EQUATOR_SUB`` steps in
    rho_a (each failed step split), raising the first state whose edge is at the sphere's equator
    (``_check_membrane``); about the least margin found (when below ``m0``, the sampled one), again, up
    to ``EQUATOR_LEVELS`` deep. Near the equator 1 - a/rs falls steeply in rho_a (seen: from 1e-5 to
    past 0 in 3e-4 of rho_a) and a march on the history's steps lands past it on another branch, its a
    falling again (10 rows: 1 - a/rs = 1.8e-5 at the last state before it)."""
    par = lambda st: float(st.rho_a)  # noqa: E731
    for _ in range(EQUATOR_LEVELS):
        sub = [float(v) for v in np.linspace(par(s0), v1, EQUATOR_SUB + 1)[1:]]
        try:
            got = march(stage, sub, stage.x(s0), stop_ok=True, start=(par(s0), s0), deep=12)
        except ConvergenceError:
            return
        if not got:
            return
        for k, st in enumerate(got):
            if _outside(c, st) == "equator":
                _check_membrane(c, [("delamination", st)])
            if k and abs(st.a - got[k - 1].a) > 0.25 * c.rs:
                got = got[:k]  # a jump onto another branch: not followed
                break
        seq = [s0] + got
        marg = [1.0 - st.a * c.crv for st in seq]
        k = int(np.argmin(marg))
        if not marg[k] < m0:
            return
        if k == len(seq) - 1:  # the least at the last state solved: toward the next value (or v1)
            v1 = sub[len(got)] if len(got) < len(sub) else v1
            s0 = seq[max(k - 1, 0)]
        else:
            s0, v1 = seq[max(k - 1, 0)], par(seq[k + 1])
        m0 = marg[k]


DEL_STEP = 0.05  # the longest step in rho_a of the delamination march, as a fraction of the onset's


def _fine_grid(v0, values, h):
    """``values`` (marched from ``v0``) with each step split into equal ones no longer than ``h``: (the
    finer values, the index of each of ``values`` among them)."""
    out, keep, prev = [], [], float(v0)
    for v in values:
        k = max(1, int(math.ceil(abs(v - prev) / h - 1e-9)))
        out.extend(prev + (v - prev) * np.arange(1, k + 1) / k)
        out[-1] = float(v)
        keep.append(len(out) - 1)
        prev = float(v)
    return [float(x) for x in out], keep


def _end_by_march(stage, last, on):
    """The no-slip branch end (alpha = 0) past the delamination state ``last`` (alpha >= 0): the branch
    marched from it on steps of DEL_STEP / 4 of the onset's rho_a (each failed step split) until a state
    has alpha < 0, then bracketed between it and the state before (``_alpha_zero``); None when the march
    stops first or the bracket fails."""
    h = 0.25 * DEL_STEP * on.rho_a
    k = max(1, int(math.ceil(last.rho_a / h)))
    values = [last.rho_a - h * j for j in range(1, k) if last.rho_a - h * j > 0.0]
    try:
        sts = march(stage, values, stage.x(last), stop_ok=True, start=(last.rho_a, last), deep=12)
    except ConvergenceError:
        return None
    prev = last
    for st in sts:
        if st.alpha < 0.0:
            return _alpha_zero(stage, prev, st)
        prev = st
    return None


def _alpha_zero(stage, good, past):
    """The no-slip branch end (alpha = 0) between the delamination states ``good`` (alpha >= 0) and
    ``past`` (alpha < 0, the next row), by Brent's method on alpha in rho_a (each state solved from the
    nearer end), the state on the alpha >= 0 side; None where a solve fails."""
    lo, hi = good, past
    try:
        for _ in range(200):
            if abs(lo.rho_a - hi.rho_a) <= 1e-13 * (1e-3 + lo.rho_a):
                break
            t = lo.alpha / (lo.alpha - hi.alpha)  # regula falsi, kept off the ends (Illinois-like)
            t = min(max(t, 0.05), 0.95)
            v = lo.rho_a + t * (hi.rho_a - lo.rho_a)
            st = stage.solve(v, stage.x(lo if t < 0.5 else hi), tol=EXTREMUM_TOL)
            if st.alpha >= 0.0:
                lo = st
            else:
                hi = st
            if 0.0 <= lo.alpha < 1e-13:
                break
    except ConvergenceError:
        return None
    return lo


def _finish(stage, states, rho, c, no_slip, on):
    """Retry a delamination march that stopped early on a four times finer grid from its last state
    (the onset when none solved); raise a ConvergenceError naming where it stopped if that fails too."""
    k = len(states)
    base = states[-1] if states else on
    # a branch that meets the clamp's vertical (nearly tangentially: theta_end rises steeply in rho_a)
    # stalls the march there; the finer march below, from its last state, can land past the limit on
    # another branch (seen on 10 rows: a = 1.08, beyond the clamp) and must not be taken for this one
    _delamination_end(stage, c, base, rho[k])
    fine = [base.rho_a] + list(rho[k:])
    rest = np.concatenate([np.linspace(a, b, 5)[1:] for a, b in zip(fine[:-1], fine[1:])])
    more = march(stage, rest, stage.x(base), stop_ok=True, start=(base.rho_a, base), deep=12)
    cut = next((i for i, s in enumerate(more) if no_slip and s.alpha < 0.0), len(more))
    _equator_between(stage, c, [base] + more[:cut], rest[cut] if cut < len(rest) else None)
    if no_slip:
        more = more[:next((i for i, s in enumerate(more) if s.alpha < 0.0), len(more))]
    kept = more[3::4]  # the history's own rows (every fourth value of the finer grid)
    if len(more) == len(rest):
        return states + kept
    if no_slip and more and more[-1].alpha < 0.2:  # the branch end, reached on the finer grid
        return states + kept + ([] if kept and kept[-1] is more[-1] else [more[-1]])
    if not states and not more:
        raise ConvergenceError("exact delamination: no quasi-static branch from the onset",
                               {"w": c.w, "lambda0": c.lambda0})
    last = (more or states)[-1]
    _check_membrane(c, [("delamination", s) for s in states + more])  # e.g. the edge stuck at the equator
    _delamination_end(stage, c, last, rest[len(more)])
    if c.crv > 0.0 and last.a * c.crv > 1.0 - 1e-4:
        raise DomainError(f"the exact delamination branch ({c.slip}) carries the contact edge to the sphere's "
                          "equator (a = rs: wrapping past it is outside the model) before detachment",
                          f"the march stalls at a = {last.a:.8g} (a/rs = {last.a * c.crv:.8g}), alpha = "
                          f"{last.alpha:.6g}, on the history's grid and on one four times finer",
                          "lower w, or change the loading end",
                          {"control": c.control, "slip": c.slip, "w": c.w, "lambda0": c.lambda0,
                           "a_max": c.a_max, "rs": c.rs})
    raise ConvergenceError(f"exact delamination ({c.slip}): the march stopped at a = {last.a:.6g} "
                           f"(alpha = {last.alpha:.4g}) before detachment, on the history's grid and "
                           "on one four times finer",
                           {"w": c.w, "lambda0": c.lambda0, "a_max": c.a_max, "control": c.control})


def _delamination_end(stage, c, good, v_bad):
    """The delamination march stopped after the solved state ``good``: when the state at ``v_bad`` (the
    next rho_a) solves and turns past vertical at the clamp, bisect in rho_a between solved states for
    the Case I limit and raise it as a DomainError. The state at ``v_bad`` is approached from ``good`` on
    steps growing from 2^-12 of the way (each solved from the last one), since near a limit met nearly
    tangentially Newton from ``good`` straight at ``v_bad`` fails (seen: 50-300 rows stopped 1e-6 in
    rho_a before it where 1001 rows found it). Returns when not shown."""
    span, h = v_bad - good.rho_a, 2.0 ** -12
    for _ in range(60):
        v = v_bad if h >= 1.0 else good.rho_a + span * h
        try:
            nxt = stage.solve(v, stage.x(good))
        except PastVertical:
            v_bad = v
            break
        except ConvergenceError:
            h *= 0.25
            if h < 2.0 ** -24:
                return
            continue
        if v == v_bad:
            return
        span, good, h = v_bad - v, nxt, 2.0 * h
    else:
        return
    found = _bisect_case_one(stage, good, good.rho_a, v_bad)
    if found is None:
        return
    good = found[1]
    raise DomainError(f"the exact delamination branch ({c.slip}) turns past vertical at the clamp at a = "
                      f"{good.a:.8g} (alpha = {good.alpha:.6g}, d = {good.d:.8g}), before detachment (Case II "
                      "beyond, outside the model)",
                      "solved states either side of it, to 1e-10 in the edge's material coordinate",
                      "lower w, or change the loading end",
                      {"control": c.control, "slip": c.slip, "w": c.w, "lambda0": c.lambda0,
                       "a_max": c.a_max, "locator": good.a})


def _check_membrane(c, rows):
    """Every solved state of the history must be one the membrane model represents (``_outside``):
    positive line tensions at the contact edge and a contact edge below the sphere's equator. The
    first that is not is raised as a DomainError (the state itself shows it). Vectorized: the tensions
    of all rows at once (``kernels.tensions`` called row by row cost ~1.5 ms a history)."""
    if not rows:
        return
    v = np.array([(st.rho_a, st.a, st.l1m, st.l1p, st.l2a) for _, st in rows], dtype=float)
    rho, a, l1m, l1p, l2 = v.T

    def least(l1):
        j = 1.0 / (l1 * l2) ** 3
        return np.minimum(l1 / l2 - j, l2 / l1 - j)
    bad = (rho > 0.0) & ~(np.minimum(least(l1m), least(l1p)) > 0.0)
    if c.crv > 0.0:
        bad |= (rho > 0.0) & ~(a * c.crv < 1.0 - 1e-6)
    if not bad.any():
        return
    stage, st = rows[int(np.argmax(bad))]
    why = _outside(c, st)
    t = min(min(K.tensions(st.l1m, st.l2a)), min(K.tensions(st.l1p, st.l2a)))
    raise DomainError(f"a {stage} state of the exact membrane {_END_WORDS[why]}",
                      f"at a = {st.a:.8g} (a/rs = {st.a * c.crv:.10g}), alpha = {st.alpha:.6g}: "
                      f"least edge tension {t:.3g}",
                      "lower w, or change the loading end",
                      {"control": c.control, "slip": c.slip, "w": c.w, "lambda0": c.lambda0,
                       "a_max": c.a_max, "rs": c.rs})


def _vertex(x, y, c, h):
    """The minimum of the polynomial through (x, y) nearest the centre c (scale h) (``march.vertex``,
    compiled); None if Newton on its derivative does not converge within 2.5 h of c."""
    v = vertex(np.asarray(x, dtype=float), np.asarray(y, dtype=float), float(c), float(h))
    return None if math.isnan(v) else float(v)


def _extremum(stage, states, key, sign, scale=None, limits=None):
    """The minimum of sign*key along ``stage`` near the least of ``states`` (solved states of the
    stage, in path order), located on the continuous branch whatever the row grid: Brent's method on
    the solved states between the least row's neighbours (one-sided at an end of ``states``: the
    minimum may lie between an end and its neighbour, e.g. just before a no-slip branch end, or just
    after the onset), then the vertex of the quartic through five states solved to EXTREMUM_TOL on a
    stencil of ``H_FINAL`` * ``scale`` (the path's extent in its parameter; the onset's rho_a by
    default) around it, inside ``limits`` (the parameter's range where the branch is smooth) (the
    objective is flat there: its derivative, not its value, locates the minimum). An end of ``states``
    is returned when the minimum is there."""
    par = lambda st: float(getattr(st, stage.param))  # noqa: E731
    vals = [sign * key(s) for s in states]
    i = int(np.argmin(vals))
    n = len(states)
    if n < 2:
        return states[i]
    lo, hi = sorted((par(states[max(i - 1, 0)]), par(states[min(i + 1, n - 1)])))
    if not hi > lo:
        return states[i]
    known = {par(st): st for st in states[max(0, i - 3):i + 4]}

    def solve(v, tol=EXTREMUM_TOL):
        # the predictor's nodes: the nearest solved states, spread at least as far apart as the nearest is
        # from v (Brent's last states lie within 1e-9 of each other: a cubic through them, extrapolated
        # to a stencil point 1e-3 away, led Newton onto another branch)
        near = []
        for q in sorted(known, key=lambda q: abs(q - v)):
            if len(near) == 4:
                break
            if not near or min(abs(q - r) for r in near) >= 0.5 * abs(near[0] - v):
                near.append(q)
        xs = [stage.x(known[q]) for q in near]
        got = stage.path([v], near, xs, xs[0], tol=tol)
        try:
            st = got[0] if got else stage.solve(v, xs[0], tol=tol)
        except ConvergenceError:
            if tol >= EXTREMUM_TOL:
                raise
            st = stage.solve(v, xs[0], tol=EXTREMUM_TOL)
        known[v] = st
        return st

    worst = max(vals) + 1.0 + abs(max(vals))

    def objective(v):
        try:
            return sign * key(solve(v))
        except ConvergenceError:
            return worst
    width = hi - lo
    scale = abs(par(states[0])) if scale is None else scale

    def stencil(x):
        """The final stencil's spacing about x: ``H_FINAL`` * scale, inside ``limits`` (a no-slip branch end
        at alpha = 0 is not smooth through: a stencil reaching 4e-4 rho_a past it put the vertex 2e-8
        off), down to a hundredth of that; toward detachment (rho_a -> 0) the observables vary on the
        scale of rho_a itself: a stencil of +-0.26 rho_a put the quartic's vertex 2.5e-7 off; at
        +-0.06 rho_a its O(h^4) error is ~1e-10."""
        h = H_FINAL * scale
        if stage.param == "rho_a":
            h = min(h, 0.03 * x)
        if limits is not None:
            h = min(h, max(0.4 * min(x - limits[0], limits[1] - x), 0.01 * h))
        return h

    def polish(x):
        """The vertex of the quartic through the stencil about x, re-centred (up to 5 times) until it
        lies within 0.005 h of the centre: (x, converged: within 1.5 h at the last). (Within 0.05 h was
        taken once: a vertex 0.042 h off the centre, a turning point's a 3.3e-8 off the centred one, seed 2's
        pressure-control scene on 10 rows; re-centred, the next vertex lies ~1e-4 h off.)"""
        h = stencil(x)
        near = False
        if not h > 0.0:
            return x, False
        for _ in range(5):
            grid = list(x + h * np.array([-2.0, -1.0, 0.0, 1.0, 2.0]))
            try:
                pts = [solve(v, STENCIL_TOL) for v in grid]
            except ConvergenceError:
                h *= 0.25  # a stencil reaching off the branch (past its end): a narrower one
                continue
            v = _vertex(grid, [sign * key(st) for st in pts], x, h)
            if v is None:
                return x, False
            if abs(v - x) <= 0.005 * h:
                return v, True
            # re-centred on the vertex: off-centre the quartic's vertex carries its O(h^4) error (a
            # vertex 0.075 h off the centre was 5e-8 off the centred one)
            near = abs(v - x) <= 1.5 * h
            x = min(max(v, lo), hi)
        return x, near

    x, done = None, False
    if 0 < i < n - 1:
        # on a grid dense next to the stencil, from the vertex of the rows' own polynomial (no solve)
        j0, j1 = max(0, i - 2), min(n, i + 3)
        c0 = _vertex([par(st) for st in states[j0:j1]], vals[j0:j1], par(states[i]), width)
        if c0 is not None and lo < c0 < hi and width <= 8.0 * stencil(c0):
            x, done = polish(c0)
    best = states[i]
    if not done:
        # else (or where that did not converge) Brent's method on the values first: to a fifth of the
        # stencil, which then locates the minimum by its derivative
        res = minimize_scalar(objective, bounds=(lo, hi), method="bounded",
                              options={"xatol": max(0.2 * stencil(par(states[i])), 1e-9 * width),
                                       "maxiter": 200})
        x = float(res.x)
        if not res.fun < vals[i] and i in (0, n - 1):
            return states[i]  # the minimum is the end of the path (a kink, a branch end)
        # (an interior least row may lie closer to the minimum than its values resolve: polished all the same)
        best = known[x] if x in known and res.fun < vals[i] else states[i]
        x, _ = polish(x)
    if not lo - 1e-12 * width <= x <= hi + 1e-12 * width:
        return best
    try:
        fin = solve(x, STENCIL_TOL)
    except ConvergenceError:
        return best
    # the vertex, unless clearly worse than the best state seen (a vertex of another feature): the values
    # themselves carry the states' rounding (~1e-12 with p an unknown), Brent's minimum is only as good
    # as the values (a locator ~1e-6 off on a flat minimum), the vertex's derivative is not
    # (held against every state solved in the bracket, the stencils' too)
    best = min([best] + [st for v, st in known.items() if lo <= v <= hi], key=lambda st: sign * key(st))
    if sign * key(fin) <= sign * key(best) + 1e-10 * (1.0 + abs(sign * key(best))):
        return fin
    # the vertex is not the minimum (the observable is not smooth on the stencil's scale: near detachment,
    # at a = 5e-4, successive vertices wandered by 6e-7): Brent's method on the values about the best
    # state, to 1e-7 of the stencil (its locator as good as the values; the same on every row grid to 1e-9)
    xb = par(best)
    h = stencil(xb)
    res = minimize_scalar(objective, bounds=(max(lo, xb - 2.0 * h), min(hi, xb + 2.0 * h)), method="bounded",
                          options={"xatol": 1e-7 * h, "maxiter": 200})
    got = known.get(float(res.x))
    return got if got is not None and sign * key(got) < sign * key(best) else best


def _first_turn(stage, m, pin, dl, key, sign, parts=(), found=None, limits=None):
    """The turning point: where the control variable (sign * key falling) first stops falling on the
    way out (docs/contracts.md), not its least value over the branch. The end of loading ``m`` when
    it rises at once; on pinning when it turns there (``parts``: the pinning stages and their states,
    ``_pinning``), else on delamination, each refined on its stage (``_extremum`` over the states up
    to just past the first turn: between rows, or between the end of loading or the onset and the
    next row). ``pin`` ends with the onset. A state refined on pinning is recorded in ``found``
    (its id: its part)."""
    seq = [m] + pin + dl
    vals = [sign * key(s) for s in seq]
    j = next((i for i in range(len(seq) - 1) if vals[i + 1] > vals[i] + TURN_TOL * (1.0 + abs(vals[i]))),
             len(seq) - 1)
    n_on = len(pin)  # index of the onset in seq
    if j < n_on:
        return _on_pinning(parts, seq[j], key, sign, first=True, found=found)
    return _extremum(stage, seq[n_on:j + 2], key, sign, limits=limits)


def _on_pinning(parts, row, key, sign, first=False, found=None):
    """The minimum of sign*key on the pinning part through the row ``row``, refined between its states
    (``_extremum``); with ``first``, over its states up to just past ``row`` only (the first turn of
    the control, which is monotone along a part continued in the control: only a part in alpha is
    searched then). ``row`` when it lies on no such part. ``found`` (a dict) records the part of a new
    state under its id."""
    for part in parts:
        stage, sts = part
        if first and stage.param != "alpha":
            continue
        k = next((q for q, st in enumerate(sts) if st is row), None)
        if k is None:
            continue
        span = abs(float(getattr(sts[-1], stage.param)) - float(getattr(sts[0], stage.param)))
        lim = (0.0, math.inf) if stage.param == "alpha" else None
        st = _extremum(stage, sts[:k + 2] if first else sts, key, sign, scale=span, limits=lim)
        if found is not None:
            found[id(st)] = part
        return st
    return row


def exact_history(control: str, slip: str, *, p: float | None = None, d: float | None = None, w: float,
                  rs: float, lambda0: float, a_max: float | None = None, delta_max: float | None = None,
                  p_max: float | None = None, points: int = 200, n: int = DEFAULT_N) -> History:
    """Compute a full history of the exact neo-Hookean membrane (docs/contracts.md A2 columns).

    Parameters
    ----------
    control, slip, p, d, w, rs, a_max, delta_max, p_max, points
        As ``adhfit.simulate`` (dimensionless, docs/contracts.md A1).
    lambda0 : float
        Pre-stretch, > 1; every observable depends on it.
    n : int
        Integration steps per membrane segment (the default 8 gives <= 5e-8 on every row against
        n = 128 over lambda0 = 1.1-3; benchmarks/results/exact_n.md).

    Returns
    -------
    adhfit.histories.History
        ``columns`` (the A2 columns as arrays), ``summary`` (the A2 ``--json`` object), ``inputs``.

    Raises
    ------
    InputError
        A parameter out of range.
    DomainError
        The history leaves the model's domain, at a bound bisected between solved states: the clamp
        tangent past vertical either way (Case I only), a line tension at the contact edge falling to 0
        (slack or compressive), the contact edge at the sphere's equator, a tensile adhesionless
        contact force.
    ConvergenceError
        A failed solve where a solution may exist.
    """
    c = prepare(control, slip, p, d, w, rs, lambda0, a_max, delta_max, p_max, points, n)
    cfg = Config(c.lambda0, c.crv, c.n)
    mc, m = _loading(cfg, c)
    pin, on = _pinning(cfg, c, m)
    _check_compressive(c, mc, m)
    _check_membrane(c, [("making_contact", s) for s in mc[1:]] + [("pinning", s) for s in pin])
    dl, stage, ends_at = _delamination(cfg, c, m, on)
    _check_membrane(c, [("delamination", s) for s in dl])
    key = (lambda s: s.d) if control == "displacement" else (lambda s: s.p)
    sign = -1.0 if control == "displacement" else 1.0
    parts, found = getattr(c, "pin_parts", []), {}
    # delamination is smooth from rho_a = 0 (or the no-slip branch end) on, through the onset
    limits = (dl[-1].rho_a if ends_at is not None else 0.0, math.inf)
    turn = _first_turn(stage, m, pin, dl, key, sign, parts, found, limits)
    fmin = _extremum(stage, [on] + dl, lambda s: s.f, 1.0, limits=limits)
    low = min(pin, key=lambda s: s.f)
    if low.f <= fmin.f:  # the most negative force of the history (A2) on pinning (or at the onset's kink)
        fmin = min([fmin, _on_pinning(parts, low, lambda s: s.f, 1.0, found=found)], key=lambda s: s.f)
    rows = mc + pin + dl
    extra = [s for s in (turn, fmin) if all(s is not t for t in rows)]
    if len(extra) == 2 and extra[0] is extra[1]:
        extra = extra[:1]
    for s in extra:
        if id(s) in found:
            pin = _insert_pinning(pin, *found[id(s)], s)
        else:
            dl.append(s)
    dl = sorted(dl, key=lambda s: -s.rho_a)
    out = _assemble(c, mc, pin, dl, m, on, turn, fmin)
    if ends_at is not None:
        # the no-slip quasi-static branch ends at a finite contact radius (detachment from there is dynamic)
        out.inputs["delamination_ends_at_a"] = ends_at
    return out


def _insert_pinning(pin, stage, sts, s):
    """``pin`` with the refined state ``s`` of the pinning part (stage, states) inserted in path order."""
    par = lambda st: float(getattr(st, stage.param))  # noqa: E731
    sgn = 1.0 if par(sts[-1]) >= par(sts[0]) else -1.0
    mine = [q for q, st in enumerate(pin) if any(st is t for t in sts)]
    pos = next((q for q in mine if sgn * par(pin[q]) > sgn * par(s)), mine[-1] + 1 if mine else len(pin) - 1)
    return pin[:pos] + [s] + pin[pos:]


def _check_compressive(c, mc, m):
    """The exact membrane's own domain check: without adhesion the substrate can only push, so the
    contact force of every making-contact state (the end of loading included) must be compressive.
    A tensile one means the free membrane is more concave at its apex than the substrate (its apex
    curvature p / (1 - lambda_c^-6) below -1/rs, a stricter bound than the large-stretch p > -1/rs):
    contact would not start at the apex, outside the model.

    The sign is decided by proof, not by a floor on the rows' f: while making contact (alpha = 0, the
    edge on the substrate, tangent to it) the global balance of a state is f = pi a^2 (p + T1+ / rs)
    exactly (``kernels.shot_from_edge``: sin(theta_a) = -a/rs), so f > 0 if and only if
    q = p + T1+ / rs > 0, with the edge tension T1+ from the state's own stretches. As a -> 0, q tends
    to the free apex's p + (1 - lambda_c^-6) / rs (the apex-curvature condition). A state is tensile
    when q < 0 beyond the error of its terms (``Q_TOL`` of |p| + |T1+| / rs: the stretches carry ~1e-8);
    the row's f itself is not used for that (its last Newton step is taken on the Jacobian, with an
    absolute error of ~1e-10 of the O(p) terms: f = -1.2e-10 at a = 1.3e-6, where pi a^2 q = +6e-12).
    The end of loading (solved to 1e-12) must have f > 0 itself."""
    crv = c.crv
    fr = c.free
    q0 = fr.p + crv * (1.0 - fr.lc ** -6)
    apex = q0 < -Q_TOL * (abs(fr.p) + crv)
    bad = []
    if len(mc) > 1:  # T1+ = l1/l2 - (l1 l2)^-3 (``kernels.tensions``), vectorized over the rows
        p, l1, l2 = np.array([(s.p, s.l1p, s.l2a) for s in mc[1:]], dtype=float).T
        t = l1 / l2 - 1.0 / (l1 * l2) ** 3
        q = p + crv * t
        bad = [mc[1 + i] for i in np.flatnonzero(q < -Q_TOL * (np.abs(p) + crv * np.abs(t)))]
    if not m.f > 0.0:
        bad = [m] + bad
    if not (apex or bad):
        return
    show = bad[0] if bad else m
    crv_s = 0.0 if math.isinf(c.rs) else -1.0 / c.rs
    where = "pressure p" if c.control == "displacement" else "gap d"
    raise DomainError("the adhesionless contact force is tensile while making contact (the exact "
                      "membrane's apex is more concave than the substrate, so contact would not start "
                      "at the apex)",
                      f"f = {m.f:.6g} at the end of loading (a_max = {c.a_max:.6g}), f = {show.f:.6g} "
                      f"at a = {show.a:.6g}, free apex p + (1 - lambda_c^-6)/rs = {q0:.6g}; it must be > 0 "
                      f"(the free apex curvature must exceed -1/rs = {crv_s:.6g})",
                      f"raise the {where}, or lambda0 = {c.lambda0:g}",
                      {"control": c.control, "slip": c.slip, "rs": c.rs, "lambda0": c.lambda0,
                       **({"p": c.p} if c.control == "displacement" else {"d": c.d})})


Q_TOL = 1e-7  # relative error of p + T1+/rs's terms (stretches to ~1e-8, T1+ to ~4e-8) in ``_check_compressive``


def _row(st, delta):
    return {"f": st.f, "delta": None if math.isnan(delta) else float(delta), "p": st.p, "a": st.a}


def _assemble(c, mc, pin, dl, m, on, turn, fmin):
    rows = [("making_contact", s) for s in mc] + [("pinning", s) for s in pin] + \
           [("delamination", s) for s in dl]
    turn_i = next(i for i, (_, s) in enumerate(rows) if s is turn)
    cols = {"stage": np.array([r[0] for r in rows])}
    vals = np.array([(s.a, s.alpha, s.p, s.d, s.f, s.G) for _, s in rows], dtype=float)
    for j, k in enumerate(("a", "alpha", "p", "d", "f", "G")):
        cols[k] = vals[:, j].copy()
    cols["G"][: len(mc)] = 0.0
    cols["delta"] = c.deltas([s for _, s in rows])
    cols["stable"] = np.arange(len(rows)) <= turn_i
    at = {id(s): i for i, (_, s) in enumerate(rows)}  # the summary's delta: its row's (no new d0 solve)
    summary = {"f_max": m.f, **{k: _row(s, cols["delta"][at[id(s)]])
                                for k, s in (("onset", on), ("f_min", fmin), ("turning_point", turn))}}
    return History(cols, summary, c.inputs(), states=[s for _, s in rows])
