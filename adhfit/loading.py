"""Loading histories: displacement control (fixed p) and pressure control (fixed gap d).

A history runs making contact (a from 0 to a_max), contact pinning (alpha from 0 to the onset of
delamination, G = w) and delamination (a from the onset down to 1e-3 a_max, toward complete
detachment). Rows are placed per stage, clustered at the stage boundaries; the onset, the most
negative force and the turning point of the control variable are solved for (root of the exact
derivative along the branch), not picked from rows, and inserted as rows.

Everything here is dimensionless (docs/contracts.md A1); no pandas.
"""
from __future__ import annotations

import math
from functools import lru_cache

import numpy as np

from .core.inflation import apex_deflection, critical_pressure
from .errors import ConvergenceError, DomainError, InputError
from .histories import History
from .params import A_MAX_OVER_RS, DIMENSIONLESS, check_scene

__all__ = ["History", "history", "state_at", "STAGES", "COLUMNS"]

STAGES = ("making_contact", "pinning", "delamination")
COLUMNS = ("stage", "a", "alpha", "p", "d", "delta", "f", "G", "stable")
#: where the history stops on the way to detachment (a -> 0 is singular), relative to a_max
A_END = 1e-3
_KEYS = ("a", "alpha", "p", "d", "f", "G")
_STAGE_LABELS = np.array(STAGES, dtype=object)


class _Kernels:
    """The compiled kernels, imported on first use: ``import adhfit`` does not import numba."""

    def __getattr__(self, name):
        from .core import branches, continuation, ends, history, newton, solve  # noqa: PLC0415
        for mod in (history, branches, continuation, newton, solve, ends):
            if hasattr(mod, name):
                setattr(self, name, getattr(mod, name))
                return getattr(mod, name)
        raise AttributeError(name)


K = _Kernels()


# ----------------------------------------------------------------------------------------------
# setup


def _prepare(control, slip, p, d, w, rs, a_max, delta_max, p_max, lambda0, points):
    """Validated inputs, c = 1/rs, pressure control?, and the loading end's arguments of the kernel."""
    v = check_scene(control, slip, p=p, d=d, w=w, rs=rs, a_max=a_max, delta_max=delta_max,
                    p_max=p_max, lambda0=lambda0, points=points)
    c = 0.0 if math.isinf(v["rs"]) else 1.0 / v["rs"]
    pc = control == "pressure"
    return v, c, pc, _loading_end(v, c, pc)


def _a_cap(c):
    """Largest admissible a_max: the table's bound and 0.95 rs."""
    cap = DIMENSIONLESS["a_max"].upper
    return min(cap, A_MAX_OVER_RS / c) if c > 0 else cap


def _resolve_end(v, c, pc, kappa_dc, d_fix, p_cr):
    """a_max from delta_max or p_max, along the making-contact branch (:mod:`.core.ends`); an end the
    branch never reaches is an InputError naming the largest value it does reach, and where."""
    name = "p_max" if pc else "delta_max"
    target = float(v[name])
    res = K.resolve_end(pc, kappa_dc, d_fix, p_cr, c, target, _a_cap(c))
    if math.isfinite(res.a):
        return float(res.a)
    if not math.isfinite(res.top):
        raise InputError(name, target, "reached on loading", f"No contact state is inside the model: {res.why}.")
    low = f"{p_cr:.6g}" if pc else "0"
    raise InputError(name, target, f"a number in ({low}, {res.top:.6g}], the largest "
                     f"{'pressure' if pc else 'displacement'} reached on loading (at contact radius "
                     f"{res.a_top:.4g}): {res.why}",
                     f"Lower {name}, or give a_max.")


def _loading_end(v, c, pc):
    """(a_max or NaN, kappa, gap aimed at, lo, hi): the kernel solves a_max from delta_max or p_max,
    the radius where the making-contact gap at that pressure reaches the target, in [lo, hi]."""
    if "a_max" in v:
        return float(v["a_max"]), 0.0, 0.0, 0.0, 0.0
    cap = _a_cap(c)
    if pc:
        kappa, target = float(v["p_max"]), float(v["d"])
        p_cr = float(critical_pressure(v["d"]))
        if kappa <= p_cr:
            raise InputError("p_max", kappa, f"above the critical pressure p_cr = {p_cr:.6g} "
                             f"at which contact starts for d = {v['d']:g}")
    else:
        kappa = float(v["p"])
        target = float(apex_deflection(kappa)) - v["delta_max"]
    lo = 1e-9 * cap
    if kappa > 1.0:  # Case I needs sin(theta) at the clamp <= 1: kappa (1 - a^2) - c a^2 <= 1
        lo = max(lo, math.sqrt((kappa - 1.0) / (kappa + c)) * (1 + 1e-9))
    return math.nan, kappa, target, lo, cap


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
# public


def history(control: str, slip: str, *, p: float | None = None, d: float | None = None, w: float,
            rs: float, a_max: float | None = None, delta_max: float | None = None,
            p_max: float | None = None, lambda0: float = 2.0, points: int = 200, retry: bool = True) -> History:
    """Compute a full dimensionless history (docs/contracts.md A2).

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
    retry : bool
        Retry a failed history on other row grids (:func:`retry_points`) before reporting it.  A fit
        passes False: it has its own, cheaper retries, and a failed evaluation must cost one history
        (with the engine's retries a truncated pressure-control test took minutes instead of seconds).

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
    v, c, pc, end = _prepare(control, slip, p, d, w, rs, a_max, delta_max, p_max, lambda0, points)
    d_fix = float(v["d"]) if pc else 0.0
    kappa_dc = 0.0 if pc else float(v["p"])
    p_cr = float(critical_pressure(d_fix)) if pc else 0.0
    failures = []
    for pts in retry_points(v["points"]) if retry else (v["points"],):
        (status, err, a_m, out, counts, tp_pos, summ, f_max, branch_end) = K.run(
            pc, slip == "no-slip", kappa_dc, d_fix, p_cr, c, float(v["w"]), *end, *_grids(pts), A_END)
        if status in (K.H_END_UNREACHABLE, K.H_END_SOLVE) and not math.isfinite(end[0]):
            # the compiled solve of the loading end (one call, ~0.2 ms) failed: the end along the
            # making-contact states (core/ends.py, ~1 ms) finds it or says where the branch stops
            end = (_resolve_end(v, c, pc, kappa_dc, d_fix, p_cr),) + end[1:]
            (status, err, a_m, out, counts, tp_pos, summ, f_max, branch_end) = K.run(
                pc, slip == "no-slip", kappa_dc, d_fix, p_cr, c, float(v["w"]), *end, *_grids(pts), A_END)
        if status == K.H_OK:
            break
        failures.append((pts, int(status), err.copy()))
        limit = (_case_one_end(err, v, c, pc, slip == "no-slip", float(a_m), _grids(pts)[0])
                 if status == K.H_FOLLOW else None)
        if limit is None and status == K.H_FOLLOW and slip == "frictionless":
            limit = _equator_end(err, v, c, pc, float(a_m), _grids(pts)[0])
        if limit is not None:
            break  # the branch's own end, shown by a second method: no other grid changes it
        if status in (K.H_END_UNREACHABLE, K.H_MC_PRESSURE, K.H_MC_STATE):
            break  # explicit states at a given radius: no other row grid changes them
        if len(failures) >= 3 and _agree(failures, SETTLED) and not (slip == "no-slip" and int(err[0]) == 2):
            break  # three grids stall at one state (a branch end if to AGREE, see _raise): more grids cost, not tell
    v["a_max"] = float(a_m)
    info = {"control": control, "slip": slip, **v}
    if status != K.H_OK:
        _raise(failures, v, info, c, pc, limit)
    cols = dict(zip(("a", "alpha", "p", "d", "f", "G", "delta"), out))
    cols["stage"] = np.repeat(_STAGE_LABELS, counts)
    cols["stable"] = np.arange(out.shape[1]) <= tp_pos
    dpt = d_fix if pc else None
    rows = [dict(zip(_KEYS, map(float, r))) for r in summ]
    summary = {"f_max": float(f_max), "onset": _point(rows[0], pc, dpt),
               "f_min": _point(rows[1], pc, dpt), "turning_point": _point(rows[2], pc, dpt)}
    if branch_end == branch_end:  # not NaN: the quasi-static branch ends; detachment is dynamic
        info["delamination_ends_at_a"] = float(branch_end)
    return History(cols, summary, info, tuple(int(n) for n in counts))


_STAGE_OF = {1: "pinning", 2: "delamination"}
_DOMAIN = "state outside the model's domain (free membrane past vertical at the clamp, or no real solution)"
#: relative agreement of the failing locators of every row grid tried for a branch end to count as
#: proven: near a fold Newton's basin shrinks, so grids stop within ~1e-6 of it; a stall elsewhere
#: (a step too long for the predictor) lands where the grid's rows happen to fall (spreads of 1e-4-1e-3
#: in the issue-24 audit)
AGREE = 1e-5
#: three grids stalling within this (relative) of one another end the retries (not a proof: the
#: failure stays a ConvergenceError unless they agree to AGREE). Measured on the 3,000-scene issue-24
#: audit: of 172 failing scenes whose first three grids stalled this close, the 4 a later grid solved
#: were all no-slip delamination (a branch end; never cut short), the other 168 none
SETTLED = 1e-3


def retry_points(points):
    """The row counts a history is tried on, in order: ``points`` first, then other grids (a
    continuation that stalls or an extremum search that fails on one grid is retried on another
    before anything is reported), all within the table's bounds."""
    lo, hi = int(DIMENSIONLESS["points"].lower), int(DIMENSIONLESS["points"].upper)
    out = []
    for n in (points, points + 1, points + 7, 3 * points // 2 + 1, points // 2 + 3, points // 4 + 5):
        n = min(max(n, lo), hi)
        if n not in out:
            out.append(n)
    return tuple(out)


def _agree(failures, tol=None):
    """Whether every failure is a stall (not a step limit) of the same stage at one locator (to
    ``tol``, default AGREE)."""
    tol = AGREE if tol is None else tol
    st, err = failures[0][1], failures[0][2]
    if st != K.H_FOLLOW or int(err[1]) == 2:
        return False
    if not all(f[1] == st and int(f[2][0]) == int(err[0]) and int(f[2][1]) != 2 for f in failures):
        return False
    locs = [float(f[2][2]) for f in failures]
    return max(locs) - min(locs) <= tol * max(abs(x) for x in locs)


def _locator_name(stage, slip):
    if stage == "pinning":
        return "G" if slip == "no-slip" else "alpha"
    return "a"


def _case_one_end(err, v, c, pc, no_slip, a_m, u_mc):
    """A continuation stall on the Case I limit, confirmed by the limit solve (:mod:`.core.limit`):
    its ``CaseOneEnd``, or None. ``u_mc``: the failed run's making-contact grid (its end of loading
    is solved again as the kernel solved it)."""
    from .core.continuation import F_STALLED  # noqa: PLC0415 - compiled kernels on first use
    from .core.limit import case_one_end  # noqa: PLC0415
    if int(err[1]) != F_STALLED or int(err[0]) not in (1, 2):
        return None
    pin = int(err[0]) == 1
    code = (K.PIN_NS if no_slip else K.PIN_FR) if pin else (K.DEL_NS if no_slip else K.DEL_FR)
    d_fix, j0_end = _end_of_loading_again(v, c, pc, a_m, u_mc)
    if j0_end is None:
        return None
    return case_one_end(code, pc, float(err[4]), float(err[3]), float(err[2]), c, float(v["w"]), a_m, j0_end, d_fix)


def _end_of_loading_again(v, c, pc, a_m, u_mc) -> tuple[float, float | None]:
    """(d, J0 at the end of loading) solved again on the failed run's making-contact grid ``u_mc`` as the
    kernel solved it (d = 0 under displacement control); J0 None when that solve fails."""
    d_fix = float(v["d"]) if pc else 0.0
    p_cr = float(critical_pressure(d_fix)) if pc else 0.0
    _, out_mc, st = K._making_contact(pc, c, 0.0 if pc else float(v["p"]), d_fix, p_cr, a_m * u_mc,
                                      np.full(5, math.nan))
    return d_fix, (float(out_mc[6, -1]) if st == K.H_OK else None)


def _equator_end(err, v, c, pc, a_m, u_mc):
    """A frictionless pinning stall at the sphere's equator (a = rs), confirmed by a solve there
    (:func:`.core.limit.equator_end`): its ``EquatorEnd``, or None."""
    from .core.continuation import F_STALLED  # noqa: PLC0415 - compiled kernels on first use
    from .core.limit import equator_end  # noqa: PLC0415
    if int(err[1]) != F_STALLED or int(err[0]) != 1 or c <= 0:
        return None
    d_fix, j0_end = _end_of_loading_again(v, c, pc, a_m, u_mc)
    if j0_end is None:
        return None
    return equator_end(pc, float(err[4]), float(err[3]), float(err[2]), c, float(v["w"]), a_m, j0_end, d_fix)


def _raise(failures, v, info, c, pc, limit=None):
    """Word the failure the kernel reports on every row grid tried (``failures``: (points, status,
    err) each, see core.history): an InputError for a loading end beyond the branch, a DomainError
    where the model's end is proven (explicit states, a stall on the Case I limit that the limit
    solve ``limit`` confirms, or every grid failing at the same state of the same stage), else a
    ConvergenceError naming the grids tried."""
    slip = info["slip"]
    pts, status, err = failures[0]
    if limit is not None and not hasattr(limit, "sigma"):  # the sphere's equator (core.limit.EquatorEnd)
        raise DomainError(f"the pinning branch ({slip}) reaches the sphere's equator (a = rs = "
                          f"{v['rs']:.8g}) at alpha = {limit.loc:.8g}, before G reaches w (the onset of "
                          f"delamination), at p = {limit.kappa:.8g}: past it the contact edge would run "
                          "onto the far side of the sphere, outside the model",
                          f"the continuation stops at alpha = {float(failures[-1][2][2]):.8g} (a = "
                          f"{float(failures[-1][2][4]):.10g}) and a direct solve at a = rs finds it there",
                          "lower w, raise rs, or lower a_max",
                          {**info, "locator": limit.loc, "kappa": limit.kappa})
    if limit is not None:
        stage = _STAGE_OF[int(failures[-1][2][0])]
        name = _locator_name(stage, slip)
        target = ("before G reaches w (the onset of delamination)" if stage == "pinning"
                  else "before detachment")
        raise DomainError(f"the {stage} branch ({slip}) reaches the Case I limit at {name} = "
                          f"{limit.loc:.8g}, {target}: the membrane's tangent at the clamp turns "
                          f"vertical there (sin theta = {limit.sigma:+.0f}, at p = {limit.kappa:.8g}) "
                          "and past it would turn beyond vertical (Case II, outside the model)",
                          f"the continuation stops at {name} = {float(failures[-1][2][2]):.8g} and a "
                          "direct solve on the limit finds it there"
                          + (" (the branch, followed on from the stop in sqrt(1 - |sin theta|), "
                             "reaches it)" if limit.bridged else ""),
                          "lower w, or change the loading end",
                          {**info, "locator": limit.loc, "kappa": limit.kappa})
    if status == K.H_END_UNREACHABLE:  # only with a_max given to the kernel unsolved: kept for safety
        name = "p_max" if pc else "delta_max"
        raise InputError(name, v[name], f"reachable with a contact radius below {_a_cap(c):g}")
    if status == K.H_END_SOLVE:
        name = "p_max" if pc else "delta_max"
        raise ConvergenceError(f"contact radius for {name}", {name: v[name], "status": int(err[0])})
    if status == K.H_MC_PRESSURE:
        _unreachable_a_max(v, c)
    if status == K.H_MC_STATE:
        if pc:
            _unreachable_a_max(v, c)
        a_end = _mc_end(v, c)
        raise DomainError("the membrane would turn past vertical at the clamp while making contact "
                          "(Case I ends)", f"a_max must stay below {a_end:.6g} at p = {v['p']:g}, "
                          f"rs = {v['rs']:g} (where p - (p + 1/rs) a^2 = -1)",
                          "lower a_max, or raise p", info)
    tried = [f[0] for f in failures]
    stage = _STAGE_OF.get(int(err[0]), "?")
    same = all(f[1] == status and int(f[2][0]) == int(err[0]) for f in failures)
    if status == K.H_STATE and same and stage == "delamination" and not pc and slip == "frictionless":
        a_end = _explicit_end(v, c, float(failures[0][2][2]))
        raise DomainError("the frictionless delamination branch leaves the model (the free membrane "
                          "would turn past vertical at the clamp)",
                          f"its states leave Case I below a = {a_end:.6g}, before detachment",
                          "lower w or p, "
                          "or a_max", info)
    # a no-slip delamination branch that ends (alpha -> 0) is a history that stops there, not "no
    # solution": a stall there is the engine's failure to finish it, never a DomainError
    branch_may_end = stage == "delamination" and slip == "no-slip"
    if status == K.H_FOLLOW and len(failures) > 1 and not branch_may_end:
        locs = [float(f[2][2]) for f in failures]
        if _agree(failures):
            name = _locator_name(stage, slip)
            target = ("before G reaches w (the onset of delamination)" if stage == "pinning"
                      else "before detachment")
            raise DomainError(f"the {stage} branch ({slip}) ends at {name} = {locs[0]:.8g} {target}; "
                              f"every row grid tried ({', '.join(map(str, tried))} rows) stops there",
                              "the membrane leaves the model's domain there (the clamp tangent turning "
                              "past vertical, or no real state)", "lower w, or change the loading end",
                              {**info, "kappa": float(err[3])})
    if status == K.H_FOLLOW:
        why = ("too many continuation steps" if int(err[1]) == 2 else "continuation stalled")
        raise ConvergenceError(f"{stage} ({slip}): {why} on every row grid tried "
                               f"({', '.join(map(str, tried))} rows)",
                               {"locator": float(err[2]), "kappa": float(err[3]),
                                "locators": [float(f[2][2]) for f in failures], **info})
    if status == K.H_STATE:
        raise ConvergenceError(f"{stage}: a solved row lies outside the model on every row grid tried "
                               f"({', '.join(map(str, tried))} rows)",
                               {**info, "index": int(err[1]), "locator": float(err[2])})
    which = "turning point" if int(err[1]) == 0 else "f min"
    raise ConvergenceError(f"{which} ({stage}, {slip}): the extremum search failed on every row grid "
                           f"tried ({', '.join(map(str, tried))} rows)",
                           {**info, "locator": float(err[2]), "status": int(err[3])})


def _unreachable_a_max(v, c):
    """a_max beyond the pressure-control making-contact branch: InputError with the branch's end."""
    d_fix = float(v["d"])
    res = K.resolve_end(True, 0.0, d_fix, float(critical_pressure(d_fix)), c, math.inf, _a_cap(c))
    bound = (f"a number in [0.001, {res.a_end:.6g}], the largest contact radius with a Case I "
             f"membrane at d = {d_fix:g}" if math.isfinite(res.a_end) else
             "reachable under pressure control at this gap")
    raise InputError("a_max", v["a_max"], bound,
                     "The membrane cannot reach a larger contact radius (its tangent would turn past "
                     "vertical at the clamp): lower a_max.")


def _mc_end(v, c):
    """Displacement control: where making contact leaves Case I, p - (p + c) a^2 = -1 (B1, C2 = 0)."""
    p = float(v["p"])
    return math.sqrt((1.0 + p) / (p + c))


def _explicit_end(v, c, a_bad):
    """Frictionless delamination under displacement control is explicit in a: bisect between the
    failing row's radius and the onset for where its states stop being admissible."""
    s = _States(v, c, False, False)
    s._loaded()
    lo, hi = a_bad, float(s.onset[0])
    ok = lambda a: bool(s._observe(K.DEL_FR, 0.0, s.kappa, a)[7]) and np.isfinite(  # noqa: E731
        s._observe(K.DEL_FR, 0.0, s.kappa, a)[:6]).all()
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        lo, hi = (lo, mid) if ok(mid) else (mid, hi)
    return hi


def _point(state, pc, d_fix):
    p = state["p"]
    d = d_fix if pc else state["d"]
    delta = p / (1.0 + math.sqrt(1.0 - p * p)) - d if abs(p) <= 1 else None  # apex_deflection
    return {"f": state["f"], "delta": delta, "p": p, "a": state["a"]}




# ----------------------------------------------------------------------------------------------
# single states (tests, reference comparisons)


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
    v, c, pc, _ = _prepare(control, slip, p, d, w, rs, a_max, None, None, 2.0, 200)
    loc = alpha if stage == "pinning" else a
    locator = "alpha" if stage == "pinning" else "a"
    if loc is None or not np.isfinite(loc):
        raise InputError(locator, loc, f"a number (the locator of stage '{stage}')")
    s = _States(v, c, pc, slip == "no-slip")
    if stage == "making_contact":
        obs = s.making_contact(float(loc))
    elif stage == "pinning":
        obs = s.pinning(float(loc))
    else:
        obs = s.delamination(float(loc))
    if not (obs[7] and np.isfinite(obs[:6]).all()):
        raise ConvergenceError(f"{stage}: {_DOMAIN}", {"control": control, "slip": slip, locator: loc})
    out = dict(zip(_KEYS, map(float, obs[:6])))
    if pc:
        out["d"] = float(v["d"])
    out["delta"] = float(apex_deflection(out["p"])) - out["d"] if abs(out["p"]) <= 1 else math.nan
    return out


class _States:
    """States of one scene from the compiled kernels: the end of loading, the pinning path to the
    onset (coarse continuation from the start of pinning), states at a locator."""

    def __init__(self, v, c, pc, no_slip):
        self.c, self.w, self.pc, self.no_slip = c, float(v["w"]), pc, no_slip
        self.kappa = 0.0 if pc else float(v["p"])
        self.d_fix = float(v["d"]) if pc else 0.0
        self.a_m = float(v["a_max"])
        self.v = v

    def _observe(self, code, x, k, loc):
        """a, alpha, p, d, f, G, J0, ok of one state."""
        out, ok = K.evaluate_batch(code, np.array([x]), np.array([k]), np.array([loc]), self.c,
                                   self.w, self.a_m)
        return np.append(out[:, 0], ok[0])

    def _mc_kappa(self, a):
        if not self.pc:
            return self.kappa
        hi = (1.0 + self.c * a * a) / (1.0 - a * a) * (1 - 1e-12)
        k, st = K.mc_bracketed(a, self.c, self.d_fix, float(critical_pressure(self.d_fix)), hi)
        if st != K.OK:
            raise InputError("a_max", self.a_m, "reachable under pressure control at this gap",
                             "The membrane cannot reach this contact radius with a Case I shape "
                             "(its tangent would turn past vertical at the clamp).")
        return k

    def making_contact(self, a):
        return self._observe(K.MC, 0.0, self._mc_kappa(a), a)

    def _loaded(self):
        """(L_m, kappa_m) at the end of loading, and the pinning path (locators, x, kappa) to the onset."""
        end = self.making_contact(self.a_m)
        if not end[7]:
            raise ConvergenceError(f"end of loading: {_DOMAIN}", {"a_max": self.a_m})
        self.L_m, k_m = float(end[6]), float(end[2])
        code = K.PIN_NS if self.no_slip else K.PIN_FR
        self.end = self.w if self.no_slip else math.atan(math.sqrt(2.0 * self.w))
        res = self._follow(code, 0.0, self.end, 1.0 if self.no_slip else self.a_m, k_m, K.SCALE_LINEAR)
        self.path = res[4], res[5], res[6]
        self.onset = res[7]

    def _follow(self, code, l0, target, x0, k0, scale):
        res = K.follow(code, self.pc, l0, np.array([target]), x0, k0, self.c, self.w, self.a_m,
                       self.L_m, self.d_fix, scale, K.max_steps(1), False)
        if res[0] != K.F_OK:
            what = "too many continuation steps" if res[0] == K.F_STEPS else "continuation stalled"
            raise ConvergenceError(f"{'pinning' if l0 == 0.0 else 'delamination'}: {what}",
                                   {"locator": float(res[4][-1]), "kappa": float(res[6][-1]), **self.v})
        return res

    def _pinned(self, loc):
        """The pinned state at locator ``loc`` (G or alpha) from predictors on the path."""
        code = K.PIN_NS if self.no_slip else K.PIN_FR
        pl, px, pk = self.path
        kg = float(np.interp(loc, pl, pk)) if self.pc else self.kappa
        x, k, st = K.solve_one(code, self.pc, loc, kg, float(np.interp(loc, pl, px)), self.c,
                               self.w, self.a_m, self.L_m, self.d_fix)
        if st != K.OK:
            raise ConvergenceError("pinning: the state does not solve", {"locator": loc, **self.v})
        return self._observe(code, x, k, loc)

    def pinning(self, alpha):
        self._loaded()
        alpha_on = float(self.onset[1])
        if not 0.0 <= alpha <= alpha_on * (1 + 1e-12):
            raise InputError("alpha", alpha, f"in [0, {alpha_on:.10g}] (the onset of delamination)")
        alpha = min(alpha, alpha_on)
        if not self.no_slip or alpha == 0.0:
            return self._pinned(alpha)
        if self._pinned(self.w)[1] - alpha <= 0.0:  # the onset's angle (to rounding)
            return self._pinned(self.w)
        from scipy.optimize import brentq  # noqa: PLC0415 - only single states need it
        G = brentq(lambda g: float(self._pinned(g)[1]) - alpha, 0.0, self.w, xtol=1e-15,
                   rtol=4 * np.finfo(float).eps, maxiter=200)
        return self._pinned(G)

    def delamination(self, a):
        self._loaded()
        a_on, k_on = float(self.onset[0]), float(self.onset[2])
        if not 0.0 < a <= a_on * (1 + 1e-12):
            raise InputError("a", a, f"in (0, {a_on:.10g}] (delamination runs from the onset inward)")
        code = K.DEL_NS if self.no_slip else K.DEL_FR
        x_on = float(self.path[1][-1]) if self.no_slip else math.nan
        if a >= a_on:
            return self._observe(code, x_on, k_on, a_on)
        res = self._follow(code, a_on, a, x_on, k_on, K.SCALE_LOG)
        return self._observe(code, float(res[2][0]), float(res[3][0]), a)
