"""The state of one row: the unknown and, under pressure control, the pressure from the fixed gap.

Displacement control fixes kappa: an implicit row solves the material condition alone
(``newton.inner_one``). Pressure control adds the gap condition d = d_fix: a joint (x, kappa) Newton
from a predictor (:func:`_joint_one`), else a Newton on kappa whose iterates re-solve x
(:func:`pressure_one`). :func:`derivative_row` carries d(state)/d(locator) along a branch by complex
steps. Never raises: statuses as in :mod:`.newton`.
"""
from __future__ import annotations

import math

import numpy as np

from .branches import admissible, bracket, is_implicit, material_residual, material_target, observe, state
from .jit import jit
from .newton import (ACCEPT, CHORD_RATE, FAIL_OUTER, JOINT_MAXITER, MAXITER, OK, STEP, damped_step,
                     gap_from, inner_one, stop)

__all__ = ["FD_STEP", "pressure_one", "solve_one", "solve_batch", "solve_observe_batch",
           "derivative_row"]

#: outer iterations of :func:`pressure_one`'s nested solve for a caller that can shorten its step
FALLBACK_ITER = 12
#: relative step of the forward differences of the joint Newton's Jacobian, sqrt(machine epsilon)
FD_STEP = 1.4901161193847656e-08


@jit
def propagate(code, x, kappa, kc, lc, c, w, a_m, L_m):
    """One complex Newton step from the real root carries dx/d(kappa, loc)."""
    r_x = material_residual(code, complex(x, STEP), complex(kappa, 0.0), complex(lc.real, 0.0),
                    c, w, a_m, L_m).imag / STEP
    return x - material_residual(code, complex(x, 0.0), kc, lc, c, w, a_m, L_m) / r_x


@jit
def _jacobian(code, x, kappa, loc, c, w, a_m, s0, fd):
    """d(J0, d)/d(x, kappa) at a real state ``s0`` (its ``state``): (Rx, Gx, Rk, Gk).

    Forward differences with steps FD_STEP (1 + |x|) and FD_STEP (1 + |kappa|): two real
    evaluations, good to ~1e-8 relative, which only sets how fast the joint Newton converges (its
    residuals are exact). Two complex steps (exact) where a perturbed state is outside the model,
    or when ``fd`` is False.
    """
    if fd:
        hx, hk = FD_STEP * (1.0 + abs(x)), FD_STEP * (1.0 + abs(kappa))
        sx = state(code, x + hx, kappa, loc, c, w, a_m, True)
        sk = state(code, x, kappa + hk, loc, c, w, a_m, True)
        if sx[6] and sk[6]:
            return ((sx[5] - s0[5]) / hx, (sx[2] - s0[2]) / hx, (sk[5] - s0[5]) / hk,
                    (sk[2] - s0[2]) / hk)
    lc = complex(loc, 0.0)
    s1 = state(code, complex(x, STEP), complex(kappa, 0.0), lc, c, w, a_m, True)
    s2 = state(code, complex(x, 0.0), complex(kappa, STEP), lc, c, w, a_m, True)
    return s1[5].imag / STEP, s1[2].imag / STEP, s2[5].imag / STEP, s2[2].imag / STEP


@jit
def _solved(code, x, kappa, loc, c, w, a_m, L_m, d_fix, R, G):
    """Whether a state a pressure-control solve calls converged is a root: its residuals ``R``
    (material) and ``G`` (gap), from the iterate before the last step, within ACCEPT, or else
    those of the state itself (one more evaluation). At the Case I limit a vanishing step is no
    root (``newton.ACCEPT``)."""
    if abs(R) <= ACCEPT and abs(G) <= ACCEPT:
        return True
    st = state(code, x, kappa, loc, c, w, a_m, True)
    if not st[6]:
        return False
    tgt = material_target(code, complex(loc, 0.0), c, a_m, L_m).real if is_implicit(code) else 0.0
    r = st[5] - tgt if is_implicit(code) else 0.0
    return abs(r) <= ACCEPT and abs(st[2] - d_fix) <= ACCEPT


@jit
def _joint_one(code, loc, c, w, a_m, L_m, d_fix, kappa, x, fd):
    """Joint Newton on (material condition, gap) for one row: (x, kappa, converged).

    Newton on the pair (material condition, gap) in (x, kappa) from a predictor. The first
    iteration takes the 2x2 Jacobian (:func:`_jacobian`, by differences if ``fd``); later ones reuse it (chord steps, one real
    evaluation each) while each step is below CHORD_RATE times the one before, and take a fresh
    Jacobian otherwise. It stops when the error left, estimated from the observed rate of
    convergence, is below XTOL (:func:`stop`; the Newton rule only with the exact Jacobian).
    No safeguard: a non-finite or inadmissible iterate, a singular Jacobian, no convergence in
    JOINT_MAXITER or a root outside x's bracket is a failure.
    """
    tgt = material_target(code, complex(loc, 0.0), c, a_m, L_m).real
    Rx = Gx = Rk = Gk = det = 0.0
    fresh = True
    prev = math.inf
    for _ in range(JOINT_MAXITER):
        s0 = state(code, x, kappa, loc, c, w, a_m, True)
        if not s0[6]:
            return math.nan, math.nan, False
        R, G = s0[5] - tgt, s0[2] - d_fix
        if fresh:
            Rx, Gx, Rk, Gk = _jacobian(code, x, kappa, loc, c, w, a_m, s0, fd)
            det = Rx * Gk - Rk * Gx
        if not (math.isfinite(R) and math.isfinite(G) and math.isfinite(det)) or det == 0:
            return math.nan, math.nan, False
        exact = R == 0 and G == 0
        dx = -(R * Gk - Rk * G) / det
        dk = -(Rx * G - R * Gx) / det
        size = max(abs(dx) / (1.0 + abs(x)), abs(dk) / (1.0 + abs(kappa)))
        if not exact:
            x, kappa = x + dx, kappa + dk
        if exact or stop(fresh and not fd, size, prev):
            lo, hi = bracket(code, loc, c, w, a_m)
            return x, kappa, (min(lo, hi) <= x <= max(lo, hi)
                              and _solved(code, x, kappa, loc, c, w, a_m, L_m, d_fix, R, G))
        fresh = not (size <= CHORD_RATE * prev)
        prev = size
    return math.nan, math.nan, False


@jit
def pressure_one(code, loc, c, w, a_m, L_m, d_fix, kappa, x0, has_x0, short=False):
    """Pressure control, one row: (x, kappa, status).

    An implicit row with a finite predictor x0 is first solved by :func:`_joint_one` (Jacobian by
    differences, then exact), an explicit
    row by :func:`gap_from`. Otherwise (or when that fails): unbracketed Newton on kappa for the
    gap; each iterate re-solves the unknown (from the last finite inner solution) and carries its
    derivative through that solve by :func:`propagate`; an iterate without inner solution gives
    NaN and the Newton step backs off toward the last good kappa.
    """
    implicit = is_implicit(code)
    if implicit and has_x0 and math.isfinite(x0) and math.isfinite(kappa):
        # differences first; next to a fold (det -> 0) their ~1e-8 error can stall the iteration,
        # and the exact Jacobian is tried before the nested solve
        for fd in (True, False):
            xj, kj, good = _joint_one(code, loc, c, w, a_m, L_m, d_fix, kappa, x0, fd)
            if good:
                return xj, kj, OK
    if not implicit and math.isfinite(kappa):
        kj, good = gap_from(code, loc, c, w, a_m, d_fix, kappa, -math.inf, math.inf)
        if good:
            return 0.0, kj, OK
    memo, has_memo = x0, has_x0 and math.isfinite(x0)
    last_good = kappa
    lc = complex(loc, 0.0)
    converged = False
    xi = math.nan
    # from a continuation's predictor the joint Newton converges in a few steps where a state is
    # near; a caller that can shorten its step (:func:`.continuation.follow`) gives the nested
    # solve FALLBACK_ITER iterations, not MAXITER (failed steps cost up to 60 x 120 evaluations)
    for _ in range(FALLBACK_ITER if short else MAXITER):
        memo_was, had_memo = memo, has_memo
        if implicit:
            xi, _st = inner_one(code, kappa, loc, c, w, a_m, L_m, memo, has_memo)
            if math.isfinite(xi):
                memo, has_memo = xi, True
        kc = complex(kappa, STEP)
        xc = propagate(code, xi, kappa, kc, lc, c, w, a_m, L_m) if implicit else 0j
        sg = state(code, xc, kc, lc, c, w, a_m, True)
        g = sg[2] - d_fix if sg[6] else complex(math.nan, math.nan)
        kn, gn, converged = damped_step(kappa, last_good, g.real, g.imag / STEP)
        if converged:
            kappa, last_good = kn, gn
            break
        if kn == kappa and gn == last_good and memo == memo_was and has_memo == had_memo:
            # the next iteration would repeat this one (no inner solution, NaN gap: halfway back
            # to itself) to the last: it fails now, with the same answer
            break
        kappa, last_good = kn, gn
    if not converged:
        return math.nan, kappa, FAIL_OUTER
    x, st = (inner_one(code, kappa, loc, c, w, a_m, L_m, memo, has_memo) if implicit
             else (0.0, OK))
    if st == OK and not _solved(code, x, kappa, loc, c, w, a_m, L_m, d_fix, math.inf, math.inf):
        return math.nan, kappa, FAIL_OUTER
    return x, kappa, st


@jit
def solve_one(code, pressure, loc, k, xg, c, w, a_m, L_m, d_fix, short=False):
    """One state at ``loc``: (x, kappa, status); kappa fixed at ``k`` or solved from the gap from ``k``
    (``short``: see :func:`pressure_one`).

    The one-row case of :func:`solve_batch`, without its arrays.
    """
    implicit = is_implicit(code)
    if pressure:
        return pressure_one(code, loc, c, w, a_m, L_m, d_fix, k, xg, implicit, short)
    if implicit:
        x, st = inner_one(code, k, loc, c, w, a_m, L_m, xg, True)
        return x, k, st
    return 0.0, k, OK


@jit
def _inner_rows(code, kappa, loc, c, w, a_m, L_m, x0, has_x0, xs, status):
    """The unknown over all rows, into ``xs`` and ``status`` (NaN and a code on failure).

    Rows are independent (:func:`inner_one` each).
    """
    for i in range(loc.size):
        xs[i], status[i] = inner_one(code, kappa[i], loc[i], c, w, a_m, L_m, x0[i], has_x0)


@jit
def _solve_pressure(code, loc, c, w, a_m, L_m, d_fix, kappa, x0, has_x0, xs, status):
    """Pressure control, row by row (:func:`pressure_one`).

    ``kappa`` holds the start values and is overwritten.
    """
    for i in range(loc.size):
        xs[i], kappa[i], status[i] = pressure_one(code, loc[i], c, w, a_m, L_m, d_fix, kappa[i],
                                                   x0[i], has_x0)


@jit
def solve_batch(code, pressure, loc, kappa, x0, has_x0, c, w, a_m, L_m, d_fix):
    """The states of the rows.

    Parameters
    ----------
    code : int
        Branch code.
    pressure : bool
        Pressure control (``kappa`` holds the start values, ``d_fix`` the gap) or displacement
        control (``kappa`` holds the fixed pressures).
    loc, kappa, x0 : ndarray of float64
        Locators, pressures (or start pressures) and start values of the unknown (used when
        ``has_x0`` and all finite).

    Returns
    -------
    x, kappa : ndarray of float64
    status : ndarray of int64
        ``OK`` or the ``FAIL_*`` code of each row.
    """
    n = loc.size
    xs = np.zeros(n)
    ks = kappa.copy()
    status = np.zeros(n, dtype=np.int64)
    if pressure:
        _solve_pressure(code, loc, c, w, a_m, L_m, d_fix, ks, x0, has_x0, xs, status)
    elif is_implicit(code):
        _inner_rows(code, kappa, loc, c, w, a_m, L_m, x0, has_x0, xs, status)
    return xs, ks, status


@jit
def solve_observe_batch(code, pressure, loc, kappa, x0, has_x0, c, w, a_m, L_m, d_fix):
    """solve_batch followed by the observables of the solved states (one call).

    Returns
    -------
    x, kappa, status : as solve_batch
    out, ok : as evaluate_batch (meaningless where status is not OK)
    bad : int
        First row outside the model or with a non-finite a, alpha, p, d, f, G (``branches.first_bad``);
        -1 if none.
    """
    xs, ks, status = solve_batch(code, pressure, loc, kappa, x0, has_x0, c, w, a_m, L_m, d_fix)
    n = loc.size
    out = np.empty((7, n))
    ok = np.zeros(n, dtype=np.bool_)
    implicit = is_implicit(code)
    bad = -1
    for i in range(n):
        if status[i] != 0:
            out[:, i] = math.nan
            bad = i if bad < 0 else bad
            continue
        ok[i] = observe(code, xs[i] if implicit else loc[i], ks[i], loc[i], c, w, a_m, out[:, i])
        if bad < 0 and not admissible(ok[i], out[:, i]):
            bad = i
    return xs, ks, status, out, ok, bad


@jit
def derivative_row(code, pressure, loc, x, kappa, c, w, a_m, L_m):
    """The complex state whose imaginary parts over STEP are d(observable)/d(locator)."""
    implicit = is_implicit(code)
    lr, lc = complex(loc, 0.0), complex(loc, STEP)
    kr = complex(kappa, 0.0)
    if not pressure:
        xc = propagate(code, x, kappa, kr, lc, c, w, a_m, L_m) if implicit else 0j
        return xc, kr
    if not implicit:
        gk = state(code, 0j, complex(kappa, STEP), lr, c, w, a_m, True)[2].imag / STEP
        gl = state(code, 0j, kr, lc, c, w, a_m, True)[2].imag / STEP
        return 0j, complex(kappa, -(STEP * gl / gk))
    t_r = material_target(code, lr, c, a_m, L_m)
    t_l = material_target(code, lc, c, a_m, L_m)
    s = state(code, complex(x, STEP), kr, lr, c, w, a_m, True)
    Rx, Gx = (s[5] - t_r).imag / STEP, s[2].imag / STEP
    s = state(code, complex(x, 0.0), complex(kappa, STEP), lr, c, w, a_m, True)
    Rk, Gk = (s[5] - t_r).imag / STEP, s[2].imag / STEP
    s = state(code, complex(x, 0.0), kr, lc, c, w, a_m, True)
    Rl, Gl = (s[5] - t_l).imag / STEP, s[2].imag / STEP
    det = Rx * Gk - Rk * Gx
    dx = -(Rl * Gk - Rk * Gl) / det
    dk = -(Rx * Gl - Rl * Gx) / det
    return complex(x, STEP * dx), complex(kappa, STEP * dk)
