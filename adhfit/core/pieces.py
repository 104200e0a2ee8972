"""An observable along a computed history as monotone pieces, for fits (docs/numerics.md B4).

A measured curve gives the control value x (δ/b or p) at every row; the model needs the force (or
the contact radius) there.  Along a history the observable is a function of x on each monotone
piece:

* making contact: y(x), x rising from contact to the end of loading;
* pinning and delamination: y(u) with u = sqrt(x - x_tp), x_tp the turning point of the control
  variable.  y has an infinite slope in x at the turning point but is smooth in u, and the onset of
  delamination (a kink) is a node of both pieces.

Each piece is a PCHIP interpolant (:mod:`.pchip`) through the history's own rows.  Everything here
is compiled: building and evaluating the pieces costs a few microseconds, against ~0.5 ms for the
same work with scipy objects.
"""
from __future__ import annotations

import math

import numpy as np

from .jit import jit
from .pchip import evaluate, slopes, value_at

__all__ = ["loading_nodes", "retraction_nodes", "loading_values", "retraction_values"]


@jit
def loading_nodes(x, y, n_mc):
    """Nodes (x, y, slopes) of the making-contact piece: rows 0 .. n_mc-1, x strictly rising
    (a row that does not advance x is left out)."""
    keep = np.ones(n_mc, np.bool_)
    last = x[0]
    for i in range(1, n_mc):
        if x[i] > last:
            last = x[i]
        else:
            keep[i] = False
    xl = np.ascontiguousarray(x[:n_mc][keep])
    yl = np.ascontiguousarray(y[:n_mc][keep])
    return xl, yl, slopes(xl, yl)


@jit
def _u_piece(x, y, rows, x_tp):
    """Nodes of y(u), u = sqrt(x - x_tp), over ``rows`` (history order, u falling): reversed so
    that u rises, rows that do not advance u left out."""
    n = rows.size
    u = np.empty(n)
    v = np.empty(n)
    m = 0
    for k in range(n - 1, -1, -1):
        r = rows[k]
        uk = math.sqrt(max(x[r] - x_tp, 0.0))
        if m == 0 or uk > u[m - 1]:
            u[m] = uk
            v[m] = y[r]
            m += 1
    return u[:m].copy(), v[:m].copy()


@jit
def retraction_nodes(x, y, n_mc, n_pin, n_dl, tp_pos):
    """Nodes of the retraction pieces (pinning from the end of loading, then delamination from the
    onset), stable rows only (up to the turning point, row ``tp_pos``).

    Returns
    -------
    u, v, d : ndarray
        The pieces' nodes (u rising within each piece), values and slopes, concatenated in order of
        rising u (delamination first).
    starts : ndarray of int64
        Piece k is ``starts[k]:starts[k+1]``; a piece with fewer than two nodes is dropped.
    x_tp, y_tp : float
        The turning point and the observable there.
    x_onset : float
        Control value at the onset of delamination (the last stable pinning row).
    """
    x_tp, y_tp = x[tp_pos], y[tp_pos]
    last_mc = n_mc - 1
    n_pin_st = max(min(n_pin, tp_pos - last_mc), 0)
    pin = np.empty(n_pin_st + 1, np.int64)
    pin[0] = last_mc
    for k in range(n_pin_st):
        pin[k + 1] = last_mc + 1 + k
    onset = pin[n_pin_st]
    first_dl = n_mc + n_pin
    n_dl_st = max(min(n_dl, tp_pos - first_dl + 1), 0)
    dl = np.empty(n_dl_st + 1, np.int64)
    dl[0] = onset
    for k in range(n_dl_st):
        dl[k + 1] = first_dl + k
    u_p, v_p = _u_piece(x, y, pin, x_tp)
    u_d, v_d = _u_piece(x, y, dl, x_tp) if n_dl_st > 0 else (np.empty(0), np.empty(0))
    if u_p.size < 2:
        u_p = u_p[:0]
    if u_d.size < 2:
        u_d = u_d[:0]
    if u_p.size and u_d.size and u_p[0] < u_d[0]:  # pieces in order of rising u
        u_p, v_p, u_d, v_d = u_d, v_d, u_p, v_p
    n1, n2 = u_d.size, u_p.size
    u = np.concatenate((u_d, u_p))
    v = np.concatenate((v_d, v_p))
    d = np.empty(n1 + n2)
    if n1:
        d[:n1] = slopes(u_d, v_d)
    if n2:
        d[n1:] = slopes(u_p, v_p)
    starts = np.zeros(1 + (n1 > 0) + (n2 > 0), np.int64)
    k = 1
    for size in (n1, n2):
        if size:
            starts[k] = starts[k - 1] + size
            k += 1
    return u, v, d, starts, x_tp, y_tp, x[onset]


@jit
def loading_values(xl, yl, dl, xq):
    """The making-contact piece at control values ``xq``: zero at or before contact (xl[0]),
    clamped to the end of loading beyond it."""
    xc = np.minimum(np.maximum(xq, xl[0]), xl[-1])
    out = evaluate(xl, yl, dl, xc)
    for i in range(xq.size):
        if xq[i] <= xl[0]:
            out[i] = 0.0
    return out


@jit
def retraction_values(u, v, d, starts, x_tp, y_tp, xq):
    """The retraction pieces at control values ``xq``: the turning point's value at and beyond it
    (a clamp that keeps the residuals continuous), the end of loading's value past the top."""
    out = np.full(xq.size, y_tp)
    n_pieces = starts.size - 1
    if n_pieces == 0:
        return out
    top = u[starts[n_pieces] - 1]
    for i in range(xq.size):
        ui = math.sqrt(max(xq[i] - x_tp, 0.0))
        if ui > top:
            ui = top
        for k in range(n_pieces - 1, -1, -1):
            a, b = starts[k], starts[k + 1]
            if u[a] <= ui <= u[b - 1]:
                out[i] = value_at(u[a:b], v[a:b], d[a:b], ui)
                break
    return out
