"""A whole loading history in one compiled call (docs/contracts.md A2, B3): :func:`run`.

Making contact (a from 0 to a_max; the end of loading is solved here from delta_max or p_max when
those are given), contact pinning (from its start, G = 0 or alpha = 0, to the onset of delamination,
G = w) and delamination (a from the onset toward detachment), each by continuation through its rows
from the stage before, then the extrema of :mod:`.rows`. The kernel never raises: it returns a status
(``H_*``) and, on failure, the failing state in ``err`` for the Python layer to word the error.
"""
from __future__ import annotations

import math

import numpy as np

from .branch_end import END_ALPHA, end_stretch, solve_end
from .branches import (CLAMP_NEAR, DEL_FR, DEL_NS, MC, PIN_FR, PIN_NS, admissible, clamp_margin,
                       evaluate_batch, first_bad, is_implicit, state)
from .continuation import F_OK, F_STALLED, SCALE_LINEAR, SCALE_LOG, SCALE_SQRT, follow, max_steps
from .jit import jit
from .newton import OK, R_MC_RADIUS, bracketed, mc_pressure_rows
from .rows import S_ONSET, assemble, extrema
from .solve import solve_observe_batch

__all__ = ["H_OK", "H_END_UNREACHABLE", "H_END_SOLVE", "H_MC_PRESSURE", "H_MC_STATE", "H_FOLLOW",
           "H_STATE", "H_EXTREMUM", "run"]

#: statuses of :func:`run` and what ``err`` then holds
H_OK = 0
H_END_UNREACHABLE = 1  # loading end beyond the largest radius: err[0] = gap residual there
H_END_SOLVE = 2        # the radius of the loading end did not converge: err[0] = solver status
H_MC_PRESSURE = 3      # making contact, no pressure for the gap: err[0] = row, err[1] = a
H_MC_STATE = 4         # making contact outside the model: err[0] = row (last = end of loading), err[1] = a
H_FOLLOW = 5           # continuation failed: err = stage (1 pin, 2 del), follow status, locator, kappa, x
#                        (the last accepted state: locator, kappa and unknown x, NaN if explicit)
H_STATE = 6            # a row outside the model: err = stage, row, locator
H_EXTREMUM = 7         # an extremum search failed: err = stage, which (0 turning point, 1 f_min), locator, status


@jit
def _loading_end(c, kappa, target, lo, hi, err):
    """The radius where the making-contact gap reaches ``target`` at pressure ``kappa`` (bracketed
    Newton on [lo, hi], d falls with a): (a, status)."""
    st = state(MC, 0.0, kappa, hi, c, 0.0, 0.0, True)
    r_cap = st[2] - target if st[6] else math.nan
    if not math.isfinite(r_cap) or r_cap > 0:
        err[0] = r_cap
        return math.nan, H_END_UNREACHABLE
    a, s, _, _ = bracketed(R_MC_RADIUS, MC, kappa, 0.0, c, 0.0, 0.0, 0.0, target, 0.5 * (lo + hi),
                           lo, hi)
    if s != OK:
        err[0] = s
        return math.nan, H_END_SOLVE
    return a, H_OK


@jit
def _making_contact(pressure, c, kappa_dc, d_fix, p_cr, a_mc, err):
    """Pressures and observables of the making-contact rows: (kappa, obs, status)."""
    n = a_mc.size
    if pressure:
        hi = np.empty(n)
        for i in range(n):  # Case I: sin(theta(1)) = kappa (1 - a^2) - c a^2 < 1
            hi[i] = (1.0 + c * a_mc[i] * a_mc[i]) / (1.0 - a_mc[i] * a_mc[i]) * (1 - 1e-12)
        k_mc, st_mc = mc_pressure_rows(a_mc, c, d_fix, np.full(n, p_cr), hi)
    else:
        k_mc, st_mc = np.full(n, kappa_dc), np.zeros(n, dtype=np.int64)
    out, ok = evaluate_batch(MC, a_mc, k_mc, a_mc, c, 0.0, math.nan)
    for i in range(n):
        if st_mc[i] != OK:
            err[0], err[1] = i, a_mc[i]
            return k_mc, out, H_MC_PRESSURE
    i = first_bad(ok, out[0], out[1], out[2], out[3], out[4], out[5])
    if i >= 0:
        if not admissible(ok[n - 1], out[:, n - 1]):
            i = n - 1  # the end of loading is named first
        err[0], err[1] = i, a_mc[i]
        return k_mc, out, H_MC_STATE
    return k_mc, out, H_OK


@jit
def _follow_rows(stage, code, pressure, l0, locs, x0, k0, c, w, a_m, L_m, d_fix, scale, allow_end,
                 err):
    """:func:`.continuation.follow` through the rows of a stage, its failure into ``err``."""
    res = follow(code, pressure, l0, locs, x0, k0, c, w, a_m, L_m, d_fix, scale,
                 max_steps(locs.size), allow_end)
    st, n_out = res[0], res[1]
    if st != F_OK or (n_out != locs.size and not allow_end):
        path_l, path_x, path_k = res[4], res[5], res[6]
        err[0], err[1] = stage, st
        err[2], err[3] = path_l[path_l.size - 1], path_k[path_k.size - 1]
        err[4] = path_x[path_x.size - 1]
        return res, H_FOLLOW
    for i in range(n_out):  # every step follow accepts is admissible with a finite force
        if not admissible(True, res[8][:, i]):
            err[0], err[1], err[2] = stage, i, locs[i]
            return res, H_STATE
    return res, H_OK


@jit
def _to_branch_end(code, pressure, a_on, x_on, k_on, a_dl, path, kappa_dc, c, w, a_m, L_m, d_fix,
                   err):
    """The no-slip delamination branch ends at path[0][-1] > a_end: rows spread up to that end,
    solved from predictors interpolated on the path, else by continuation through them."""
    dl_l, dl_x, dl_k = path
    n = a_dl.size
    rl, rxp, rkp = dl_l[::-1].copy(), dl_x[::-1].copy(), dl_k[::-1].copy()
    kg = np.interp(a_dl, rl, rkp) if pressure else np.full(n, kappa_dc)
    xg = np.interp(a_dl, rl, rxp)
    xg[n - 1] = dl_x[dl_x.size - 1]
    xs, ks, status, out, ok, bad = solve_observe_batch(code, pressure, a_dl, kg, xg, True, c, w,
                                                       a_m, L_m, d_fix)
    good = True
    for i in range(n):
        good = good and status[i] == 0 and ok[i] and math.isfinite(out[4, i])
    if good:
        if bad >= 0:
            err[0], err[1], err[2] = 2, bad, a_dl[bad]
        return xs, out, H_OK if bad < 0 else H_STATE
    res, st = _follow_rows(2, code, pressure, a_on, a_dl, x_on, k_on, c, w, a_m, L_m, d_fix,
                           SCALE_LOG, False, err)
    return res[2], res[8], st


#: sub-points of each row interval at which an explicit branch's clamp margin is sampled
GAP_SAMPLES = 16


@jit
def _gap_between(code, locs, kappa, c, w, a_m):
    """A locator between two rows of an explicit branch where the state is outside Case I (the clamp
    tangent past vertical, 1 - |sin theta(1)| < 0), or NaN: the margin sampled at GAP_SAMPLES points
    a row interval, and each sampled local minimum refined by golden section. Rows alone miss such a
    gap (stress seed 24: frictionless delamination leaves Case I for a in (0.028, 0.0746) and comes
    back; 11 rows stepped over it and returned a history through it)."""
    n = locs.size
    m = (n - 1) * GAP_SAMPLES + 1
    xs, ms = np.empty(m), np.empty(m)
    for i in range(n - 1):
        for j in range(GAP_SAMPLES):
            q = i * GAP_SAMPLES + j
            xs[q] = locs[i] + (locs[i + 1] - locs[i]) * j / GAP_SAMPLES
    xs[m - 1] = locs[n - 1]
    for q in range(m):
        ms[q] = clamp_margin(code, xs[q], kappa, xs[q], c, w, a_m)
        if ms[q] < 0.0:
            return xs[q]
    g = 0.5 * (math.sqrt(5.0) - 1.0)
    for q in range(1, m - 1):
        if ms[q] <= ms[q - 1] and ms[q] <= ms[q + 1]:
            lo, hi = xs[q - 1], xs[q + 1]
            x1, x2 = hi - g * (hi - lo), lo + g * (hi - lo)
            f1 = clamp_margin(code, x1, kappa, x1, c, w, a_m)
            f2 = clamp_margin(code, x2, kappa, x2, c, w, a_m)
            for _ in range(60):
                if min(f1, f2) < 0.0:
                    return x1 if f1 < f2 else x2
                if f1 <= f2:
                    hi, x2, f2 = x2, x1, f1
                    x1 = hi - g * (hi - lo)
                    f1 = clamp_margin(code, x1, kappa, x1, c, w, a_m)
                else:
                    lo, x1, f1 = x1, x2, f2
                    x2 = lo + g * (hi - lo)
                    f2 = clamp_margin(code, x2, kappa, x2, c, w, a_m)
    return math.nan


@jit
def _delamination(pressure, no_slip, kappa_dc, c, w, a_m, L_m, d_fix, onset, on_x, a_end, u_dl,
                  err):
    """Delamination rows from the onset toward a_end: (locators, x, obs, branch end or NaN, status)."""
    code = DEL_NS if no_slip else DEL_FR
    a_on, k_on = onset[0], onset[2]
    a_dl = a_end + (a_on - a_end) * u_dl
    if not (pressure or is_implicit(code)):  # explicit under displacement control when frictionless
        out, ok = evaluate_batch(code, a_dl, np.full(a_dl.size, kappa_dc), a_dl, c, w, a_m)
        i = first_bad(ok, out[0], out[1], out[2], out[3], out[4], out[5])
        if i >= 0:
            err[0], err[1], err[2] = 2, i, a_dl[i]
            return a_dl, a_dl.copy(), out, math.nan, H_STATE
        a_gap = _gap_between(code, np.concatenate((np.array([a_on]), a_dl)), kappa_dc, c, w, a_m)
        if math.isfinite(a_gap):
            # every row is inside the model, but the branch leaves it between two of them
            err[0], err[1], err[2] = 2, -1, a_gap
            return a_dl, a_dl.copy(), out, math.nan, H_STATE
        return a_dl, a_dl.copy(), out, math.nan, H_OK
    x_on = on_x if no_slip else math.nan
    res, st = _follow_rows(2, code, pressure, a_on, a_dl, x_on, k_on, c, w, a_m, L_m, d_fix,
                           SCALE_LOG, no_slip, err)
    if st != H_OK or res[1] == a_dl.size:
        return a_dl, res[2], res[8], math.nan, st
    branch_end = res[4][res[4].size - 1]
    x_e, k_e = res[5][res[5].size - 1], res[6][res[6].size - 1]
    if clamp_margin(code, x_e, k_e, branch_end, c, w, a_m) <= CLAMP_NEAR:
        # not the branch's own end (alpha -> 0): it leaves the model at the Case I limit
        err[0], err[1], err[2], err[3], err[4] = 2, F_STALLED, branch_end, k_e, x_e
        return a_dl, res[2], res[8], math.nan, H_FOLLOW
    a_dl = branch_end + (a_on - branch_end) * u_dl
    xs, out, st = _to_branch_end(code, pressure, a_on, x_on, k_on, a_dl, (res[4], res[5], res[6]),
                                 kappa_dc, c, w, a_m, L_m, d_fix, err)
    if st == H_OK:
        branch_end = _exact_end(pressure, a_dl, xs, out, c, w, a_m, L_m, d_fix)
    return a_dl, xs, out, branch_end, st


@jit
def _exact_end(pressure, a_dl, xs, out, c, w, a_m, L_m, d_fix):
    """The last delamination row (where the continuation in t stopped, ~1e-7 in alpha short of the
    branch's own end) replaced by the end itself, alpha = 0 (:mod:`.branch_end`), when that solves
    just beyond it; returns the branch end's radius."""
    n = a_dl.size
    last = a_dl[n - 1]
    if n < 2:
        return last
    t_e = end_stretch(xs[n - 1], w)
    if not math.isfinite(t_e):
        return last
    obs = np.empty(7)
    a_e, k_e, good = solve_end(pressure, t_e, last, out[2, n - 1], c, w, a_m, L_m, d_fix, obs)
    # the continuation stopped next to the end (alpha small), and the end lies just beyond its last
    # row (a falls toward it), where the last two rows' angles extrapolate to alpha = 0 (a regular
    # function of a there): the end it was approaching, not another root of the material condition
    # (from the last row with at least twice the last angle: on a dense grid the last two are too
    # close for the extrapolation)
    al1 = out[1, n - 1]
    j = n - 2
    while j > 0 and out[1, j] < 2.0 * al1:
        j -= 1
    al2 = out[1, j]
    a_pred = last - al1 * (a_dl[j] - last) / (al2 - al1) if al2 > al1 else math.nan
    if (good and al1 < END_ALPHA and a_e <= last
            and abs(a_e - a_pred) <= 0.1 * (a_dl[j] - a_e) + 1e-14):
        a_dl[n - 1], xs[n - 1] = a_e, t_e
        out[:, n - 1] = obs
        return a_e
    return last


@jit
def _pinning(pressure, no_slip, c, w, a_m, L_m, kappa_m, d_fix, u_pin, err):
    """Pinning rows by continuation from its start (G = 0, t = 1 / alpha = 0, a = a_m) through every
    row; the last row is the onset (G = w / alpha = atan sqrt(2 w)): (locators, x, obs, status)."""
    end = w if no_slip else math.atan(math.sqrt(2.0 * w))
    lp = end * (u_pin * u_pin if no_slip else u_pin)
    res, st = _follow_rows(1, PIN_NS if no_slip else PIN_FR, pressure, 0.0, lp,
                           1.0 if no_slip else a_m, kappa_m, c, w, a_m, L_m, d_fix,
                           SCALE_SQRT if no_slip else SCALE_LINEAR, False, err)
    return lp, res[2], res[8], st


@jit
def _fail(status, err, a_max):
    return (status, err, a_max, np.empty((7, 0)), np.zeros(3, dtype=np.int64), -1,
            np.empty((3, 6)), math.nan, math.nan)


@jit
def run(pressure, no_slip, kappa_dc, d_fix, p_cr, c, w, a_max, end_kappa, end_target, end_lo,
        end_hi, u_mc, u_pin, u_dl, a_end_rel):
    """A whole history after validation.

    Parameters
    ----------
    pressure, no_slip : bool
    kappa_dc, d_fix, p_cr : float
        Displacement control: the fixed pressure; pressure control: the gap and the pressure at
        which contact starts (the free-inflation row).
    c, w : float
        Substrate curvature 1/rs and work of adhesion.
    a_max : float
        End of loading; NaN to solve it: the radius where the making-contact gap at pressure
        ``end_kappa`` reaches ``end_target``, in [end_lo, end_hi].
    u_mc, u_pin, u_dl : ndarray
        Row grids of the three stages (``adhfit.loading._grids``).
    a_end_rel : float
        Where the history stops on the way to detachment, over a_max.

    Returns
    -------
    status, err : int, ndarray (5,)
        ``H_OK`` or the failure (see the ``H_*`` codes) and its state.
    a_max : float
    cols : ndarray (7, n)
        ``a, alpha, p, d, f, G, delta`` in history order.
    counts : ndarray of int64 (3,)
        Rows of making contact (with the free-inflation row), pinning, delamination.
    tp_pos : int
        Row of the turning point (rows up to it are ``stable``).
    summary : ndarray (3, 6)
        ``a, alpha, p, d, f, G`` at the onset, f_min and the turning point (``rows.S_*``).
    f_max, branch_end : float
        Force at the end of loading; radius where the no-slip delamination branch ends (NaN when it
        reaches detachment).
    """
    err = np.full(5, math.nan)
    if not math.isfinite(a_max):
        a_max, st = _loading_end(c, end_kappa, end_target, end_lo, end_hi, err)
        if st != H_OK:
            return _fail(st, err, a_max)
    a_mc = a_max * u_mc
    k_mc, out_mc, st = _making_contact(pressure, c, kappa_dc, d_fix, p_cr, a_mc, err)
    if st != H_OK:
        return _fail(st, err, a_max)
    n_mc = a_mc.size
    L_m, kappa_m = out_mc[6, n_mc - 1], k_mc[n_mc - 1]
    lp, x_pin, out_pin, st = _pinning(pressure, no_slip, c, w, a_max, L_m, kappa_m, d_fix, u_pin, err)
    if st != H_OK:
        return _fail(st, err, a_max)
    onset = out_pin[:, lp.size - 1].copy()
    pull_off = math.sqrt(2.0 * w) / (2.0 * (abs(onset[2]) + c + 1.0))
    a_end = min(a_end_rel * a_max, 0.1 * pull_off)
    a_dl, x_dl, out_dl, branch_end, st = _delamination(
        pressure, no_slip, kappa_dc, c, w, a_max, L_m, d_fix, onset, x_pin[lp.size - 1], a_end,
        u_dl, err)
    if st != H_OK:
        return _fail(st, err, a_max)
    summary = np.empty((3, 6))
    summary[S_ONSET, :] = onset[:6]
    ext_stage, ext_loc = np.zeros(2, dtype=np.int64), np.empty(2)
    pin = (PIN_NS if no_slip else PIN_FR, lp, x_pin, True, out_pin)
    dl = (DEL_NS if no_slip else DEL_FR, a_dl, x_dl, no_slip, out_dl)
    end_obs = out_mc[:, n_mc - 1].copy()
    end_obs[5] = 0.0  # G at the end of loading (pinning's start)
    if extrema(pressure, pin, dl, kappa_dc, c, w, a_max, L_m, d_fix, onset[0], summary, ext_stage,
               ext_loc, err, end_obs):
        return _fail(H_EXTREMUM, err, a_max)
    cols, counts, tp_pos = assemble(pressure, kappa_dc, d_fix, p_cr, (a_mc, out_mc), (lp, out_pin),
                                    (a_dl, out_dl), summary, ext_stage, ext_loc)
    return H_OK, err, a_max, cols, counts, tp_pos, summary, out_mc[4, n_mc - 1], branch_end
