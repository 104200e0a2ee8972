"""A history's summary extrema and its rows in history order (the last steps of ``history.run``).

The turning point of the control variable and the force minimum are refined between the neighbours
of their best row on its own branch (:func:`.extremum.extremum`) and inserted as rows; the columns
are stacked free inflation, making contact, pinning, delamination.
"""
from __future__ import annotations

import math

import numpy as np

from .branch_end import end_extremum
from .branches import DEL_NS, PIN_NS, admissible, observe
from .extremum import BRENT_MAXITER, BRENT_RTOL, BRENT_XTOL, E_OK, ROOT_TOL, extremum
from .jit import jit
from .solve import solve_one

__all__ = ["S_ONSET", "S_FMIN", "S_TP", "extrema", "assemble", "apex"]

#: rows of the summary array: onset, f_min, turning point
S_ONSET, S_FMIN, S_TP = 0, 1, 2


@jit
def apex(p):
    """Apex deflection of the free cap d0 = p / (1 + sqrt(1 - p^2)) (eq. 15), NaN where |p| > 1."""
    if abs(p) > 1.0:
        return math.nan
    return p / (1.0 + math.sqrt(1.0 - p * p))


@jit
def _search(code, pressure, locs, xs, implicit, out, i, lo, hi, kappa_dc, c, w, a_m, L_m, d_fix,
            key, sign, k):
    """The extremum between ``lo`` and ``hi`` around rows k..i of one stage: (locator, obs, status)."""
    n = locs.size
    j0, j1 = max(min(k, i) - 2, 0), min(i + 3, n)
    order = np.argsort(locs[j0:j1])
    rl = locs[j0:j1][order]
    rx = (xs[j0:j1] if implicit else np.full(j1 - j0, math.nan))[order]
    rk = out[2, j0:j1][order]
    if lo != hi:
        lo, hi = min(lo, hi), max(lo, hi)
    else:
        lo, hi = locs[i], locs[i]
    # the best row's own slope too: with the bracket's ends it tells on which side the extremum is
    # the no-slip delamination branch's last row is its own end (a fold in a): its slope is not
    # trusted, the end is approached from inside
    open_lo = code == DEL_NS and lo != hi and lo == locs[n - 1]
    st, loc, obs, ok = extremum(code, pressure, lo, hi, locs[i], rl, rx, rk, 0.0 if pressure else kappa_dc,
                                c, w, a_m, L_m, d_fix, key, sign, BRENT_XTOL, BRENT_RTOL,
                                BRENT_MAXITER, open_lo)
    if st == E_OK and not admissible(ok, obs):
        st = -1
    return loc, obs, st


@jit
def _best_row(out_pin, out_dl, key, sign):
    """(index in pinning + delamination, value) of the largest sign * key over both stages."""
    j, best = 0, -math.inf
    for i in range(out_pin.shape[1]):
        if sign * out_pin[key, i] > best:
            j, best = i, sign * out_pin[key, i]
    for i in range(out_dl.shape[1]):
        if sign * out_dl[key, i] > best:
            j, best = out_pin.shape[1] + i, sign * out_dl[key, i]
    return j, best


#: a row counts as past the first turning point when the control variable has come back up by more
#: than this (relative) from the row before it: rows are solved to ~1e-13, a fold moves them by O(h^2)
TURN_TOL = 1e-10


@jit
def _first_turn(out_pin, out_dl, key, sign, end):
    """(index in pinning + delamination, value) of the first row after which sign * key falls: the
    first turning point of the control variable on the way out (docs/contracts.md "turning point").
    ``end`` is sign * key at the end of loading: when the first row already lies below it, the branch
    turns at once and the first row is returned (the search between the end of loading and it then
    finds the end of loading itself)."""
    n_pin, n_dl = out_pin.shape[1], out_dl.shape[1]
    n = n_pin + n_dl
    # the fall is measured from the greatest value so far, not from the row before: on a dense grid
    # a slow fall moves each row by less than TURN_TOL (seed 7: rows 1001 fell by 6e-10 in all,
    # < 1e-10 a row, past a minimum of delta 1e-5 in alpha from the branch end)
    peak, j_peak = end, -1
    for j in range(n):
        v = sign * (out_pin[key, j] if j < n_pin else out_dl[key, j - n_pin])
        if v < peak - TURN_TOL * (1.0 + abs(peak)):
            return (j_peak, peak) if j_peak >= 0 else (0, v)
        if v > peak:
            peak, j_peak = v, j
    if j_peak < 0:
        return n - 1, sign * (out_pin[key, n - 1] if n - 1 < n_pin else out_dl[key, n - 1 - n_pin])
    return j_peak, peak


@jit
def _walk_in(code, pressure, locs, xs, implicit, out, kappa, c, w, a_m, L_m, d_fix, end_x, end_k, eps, obs):
    """The state at locator ``eps`` (below the first pinning row's) on the rows' own branch, into
    ``obs``: whether it solved and is admissible.

    Two branches can leave the end of loading (frictionless: one retracting, one pressing on); a
    predictor interpolated from rows a spacing away can land on the other one (seed 11, 10 rows:
    a = 1.0021 a_max on the pressing branch while the rows retract). The locator is therefore halved
    from the first row down to ``eps``, each state predicted between the end of loading and the last
    state solved, so that every start lies within O(h^2) of the rows' branch.
    """
    lc_prev, x_prev, k_prev = locs[0], xs[0] if implicit else 0.0, out[2, 0]
    lc = lc_prev
    x, k = x_prev, k_prev
    while lc > eps:
        lc = max(0.5 * lc, eps)
        t = lc / lc_prev
        xg = end_x + (x_prev - end_x) * t if implicit else 0.0
        kg = end_k + (k_prev - end_k) * t if pressure else kappa
        x, k, st = solve_one(code, pressure, lc, kg, xg, c, w, a_m, L_m, d_fix)
        if st != 0:
            return False
        lc_prev, x_prev, k_prev = lc, x, k
    ok = observe(code, x, k, lc, c, w, a_m, obs)
    return admissible(ok, obs)


@jit
def _rises_at_once(pressure, pin, kappa_dc, c, w, a_m, L_m, d_fix, key, sign, end_obs):
    """Whether the control variable rises as pinning starts: the state at a locator 1e-4 of the first
    pinning row's, on the rows' branch (:func:`_walk_in`), has sign * key below the end of loading's
    (the turning point is then the end of loading itself, whatever the row grid)."""
    code, locs, xs, implicit, out = pin
    eps = 1e-4 * locs[0]
    obs = np.empty(7)
    end_x = (1.0 if code == PIN_NS else a_m) if implicit else 0.0
    if not _walk_in(code, pressure, locs, xs, implicit, out, 0.0 if pressure else kappa_dc, c, w, a_m,
                    L_m, d_fix, end_x, end_obs[2], eps, obs):
        return False
    v0 = sign * end_obs[key]
    return sign * obs[key] < v0 - TURN_TOL * (1.0 + abs(v0))


@jit
def _past_onset(pressure, pin, dl, kappa_dc, c, w, a_m, L_m, d_fix, a_on, key, sign):
    """The extremum of delamination between the onset and its first row: (locator, obs, status);
    the onset's own state is one of the predictor rows."""
    code, locs, xs, implicit, out = dl
    m = min(3, locs.size)
    rl, rx, rk = np.empty(m + 1), np.full(m + 1, math.nan), np.empty(m + 1)
    pin_out, pin_x = pin[4], pin[2]
    n_pin = pin_out.shape[1]
    # ascending locators: delamination runs from the onset inward (a falling)
    for q in range(m):
        rl[q], rk[q] = locs[m - 1 - q], out[2, m - 1 - q]
        if implicit:
            rx[q] = xs[m - 1 - q]
    rl[m], rk[m] = a_on, pin_out[2, n_pin - 1]
    if implicit and code == DEL_NS:  # the edge stretch ratio t carries over from pinning
        rx[m] = pin_x[n_pin - 1]
    elif implicit:
        rx[m] = rx[m - 1]
    st, loc, obs, ok = extremum(code, pressure, min(a_on, locs[0]), max(a_on, locs[0]), math.nan, rl, rx, rk,
                                0.0 if pressure else kappa_dc, c, w, a_m, L_m, d_fix, key, sign,
                                BRENT_XTOL, BRENT_RTOL, BRENT_MAXITER)
    if st == E_OK and not admissible(ok, obs):
        st = -1
    return loc, obs, st


@jit
def extrema(pressure, pin, dl, kappa_dc, c, w, a_m, L_m, d_fix, a_on, summary, ext_stage, ext_loc,
            err, end_obs):
    """Turning point (e = 0) and force minimum (e = 1) into ``summary``, ``ext_stage`` (1 pinning,
    2 delamination) and ``ext_loc``; returns the status of the failed search (0 if none), with
    (stage, which, locator, status) in ``err``. ``pin``, ``dl``: (code, locators, x, implicit, obs);
    ``end_obs``: the observables at the end of loading (a, alpha, p, d, f, G, ...). The turning
    point is the first one on the way out (:func:`_first_turn`), f_min the least force of all rows."""
    tp_lo, tp_hi, tp_st = 0.0, 0.0, -1
    for e in range(2):
        key, sign = ((2, -1.0) if pressure else (3, 1.0)) if e == 0 else (4, -1.0)
        if e == 0 and _rises_at_once(pressure, pin, kappa_dc, c, w, a_m, L_m, d_fix, key, sign, end_obs):
            tp_lo, tp_hi, tp_st = 0.0, 0.0, 1
            ext_stage[0], ext_loc[0] = 1, 0.0
            summary[S_TP, :] = end_obs[:6]
            continue
        if e == 0:
            j, best = _first_turn(pin[4], dl[4], key, sign, sign * end_obs[key])
        else:
            j, best = _best_row(pin[4], dl[4], key, sign)
        stage = 1 if j < pin[1].size else 2
        code, locs, xs, implicit, out = pin if stage == 1 else dl
        i = j if stage == 1 else j - pin[1].size
        k = i
        if e == 0:
            # a flat turn: the rows before it within TURN_TOL of it are all candidates (on a dense
            # grid the turn shows only rows after the extremum), so the bracket starts before them
            tol = TURN_TOL * (1.0 + abs(best))
            while k > 0 and sign * out[key, k - 1] >= sign * out[key, i] - tol:
                k -= 1
        lo = locs[k - 1] if k > 0 else (0.0 if stage == 1 else a_on)
        hi = locs[i + 1] if i + 1 < locs.size else locs[i]
        if e == 0:  # the turning point's bracket: f_min's state may replace it only inside it
            tp_lo, tp_hi, tp_st = min(lo, hi), max(lo, hi), stage
        loc, obs, st = _search(code, pressure, locs, xs, implicit, out, i, lo, hi, kappa_dc, c, w,
                               a_m, L_m, d_fix, key, sign, k)
        if st != E_OK:
            err[0], err[1], err[2], err[3] = stage, e, loc, st
            return 1
        # next to the no-slip delamination end the search's root may be below the row by the states'
        # rounding (seed 7 kept a row 1.6e-8 in a from the root so); the branch end itself (the last
        # delamination row) is kept over anything not better outright
        tol = ROOT_TOL * (1.0 + abs(best)) if code == DEL_NS and i != locs.size - 1 else 0.0
        if sign * obs[key] < best - tol:
            # the row itself is better: the search could not re-solve an end of its bracket (the
            # end of a no-slip delamination branch, a fold); the extremum is that row
            loc, obs = locs[i], out[:, i].copy()
        n_l = locs.size
        if stage == 2 and code == DEL_NS and n_l >= 2 and i >= n_l - 2 and out[1, n_l - 1] == 0.0:
            # the bracket reaches the branch's own end, solved at alpha = 0 (.branch_end): between it
            # and the row before, states in t do not resolve (t - t_end ~ alpha^2), so the extremum
            # there is searched in alpha
            ends = (out[1, n_l - 2], xs[n_l - 1], locs[n_l - 1], out[2, n_l - 1], locs[n_l - 2],
                    out[2, n_l - 2])
            obs_e = np.empty(7)
            v_e, a_e, k_e, t_e = end_extremum(pressure, ends, c, w, a_m, L_m, d_fix, key, sign, obs_e)
            # kept only when better beyond the states' rounding: at the bracket's other end it meets
            # the search's own root, which locates a flat extremum better than values can
            if v_e > sign * obs[key] + ROOT_TOL * (1.0 + abs(v_e)):
                loc, obs = a_e, obs_e
        if stage == 1 and i == locs.size - 1 and dl[1].size > 0:
            # the best row is the onset, where the branch has a kink: the extremum may lie on
            # either side of it, between the onset and the first delamination row as well
            loc2, obs2, st2 = _past_onset(pressure, pin, dl, kappa_dc, c, w, a_m, L_m, d_fix, a_on, key,
                                          sign)
            if st2 == E_OK and sign * obs2[key] > sign * obs[key]:
                stage, loc, obs = 2, loc2, obs2
                if e == 0:
                    tp_lo, tp_hi, tp_st = min(a_on, dl[1][0]), max(a_on, dl[1][0]), 2
        if e == 0 and sign * end_obs[key] > sign * obs[key]:
            # the control variable rises at once on the way out: the turning point is the end of
            # loading itself (pinning's locator 0), and no row after it is stable
            stage, loc, obs = 1, 0.0, end_obs.copy()
        ext_stage[e], ext_loc[e] = stage, loc
        summary[S_TP if e == 0 else S_FMIN, :] = obs[:6]
    # each is also held against the other's state: next to a fold the other search may be better
    tp, fm = summary[S_TP, :].copy(), summary[S_FMIN, :].copy()
    tp_stage, tp_loc, fm_stage, fm_loc = ext_stage[0], ext_loc[0], ext_stage[1], ext_loc[1]
    k_tp, s_tp = (2, -1.0) if pressure else (3, 1.0)
    if s_tp * fm[k_tp] > s_tp * tp[k_tp] and fm_stage == tp_st and tp_lo <= fm_loc <= tp_hi:
        summary[S_TP, :], ext_stage[0], ext_loc[0] = fm, fm_stage, fm_loc
    if -tp[4] > -fm[4]:
        summary[S_FMIN, :], ext_stage[1], ext_loc[1] = tp, tp_stage, tp_loc
    return 0


@jit
def _insert_at(locs, counts, rank, lc):
    """(row, found): the first row of stage ``rank`` at or beyond locator ``lc``, and whether that
    row is ``lc`` itself (then nothing is inserted)."""
    s0 = counts[0] + (counts[1] if rank == 2 else 0)
    m = counts[rank]
    k = m
    for q in range(m):
        lq = locs[s0 + q]
        if (lq <= lc + 1e-15) if rank == 2 else (lq >= lc - 1e-15):
            k = q
            break
    return s0 + k, k < m and abs(locs[s0 + k] - lc) <= 1e-14


@jit
def assemble(pressure, kappa_dc, d_fix, p_cr, mc, pin, dl, summary, ext_stage, ext_loc):
    """The rows in history order: (cols (7, n) a, alpha, p, d, f, G, delta; counts; tp_pos).

    ``mc``, ``pin``, ``dl``: (locators, obs). The extrema are inserted as rows unless a row already
    sits at their locator; ``tp_pos`` is the turning point's row.
    """
    n_mc, n_pin, n_dl = mc[0].size, pin[0].size, dl[0].size
    n0 = 1 + n_mc + n_pin + n_dl
    base = np.zeros((6, n0 + 2))
    base[2, 0] = p_cr if pressure else kappa_dc
    base[3, 0] = d_fix if pressure else apex(kappa_dc)
    locs = np.concatenate((np.zeros(1), mc[0], pin[0], dl[0]))
    base[:, 1:1 + n_mc] = mc[1][:6]
    base[:, 1 + n_mc:1 + n_mc + n_pin] = pin[1][:6]
    base[:, 1 + n_mc + n_pin:n0] = dl[1][:6]
    counts = np.array([1 + n_mc, n_pin, n_dl], dtype=np.int64)
    take = np.arange(n0)
    n_extra, tp_pos = 0, -1
    for e in (1, 0):  # f_min, then the turning point
        j, found = _insert_at(locs, counts, ext_stage[e], ext_loc[e])
        if not found:
            base[:, n0 + n_extra] = summary[S_TP if e == 0 else S_FMIN, :]
            take = np.concatenate((take[:j], np.array([n0 + n_extra]), take[j:]))
            locs = np.concatenate((locs[:j], np.array([ext_loc[e]]), locs[j:]))
            counts[ext_stage[e]] += 1
            n_extra += 1
            if tp_pos >= 0 and j <= tp_pos:
                tp_pos += 1
        if e == 0:
            tp_pos = j
    cols = np.empty((7, take.size))
    for r in range(take.size):
        for k in range(6):
            cols[k, r] = base[k, take[r]] + 0.0  # + 0.0 turns -0.0 into 0.0
        if pressure:
            cols[3, r] = d_fix
        cols[6, r] = apex(cols[2, r]) - cols[3, r]
    return cols, counts, tp_pos
