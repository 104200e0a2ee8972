"""Newton on the shooting unknowns of one exact-membrane state.

A problem names its unknowns among ``lc, rho_a, alpha, l1p, p`` and as many residuals among
``clamp`` (r(beta) = 1, i.e. b = lambda0 beta), ``a`` (contact radius = target), ``d`` (gap =
target) and ``G`` (G = w). The Jacobian is taken by forward differences of the shot (the shot is a
fixed-step integration, smooth in its inputs to rounding). The loop itself is compiled
(``newton.py``); this module translates names to codes and results to a ``State``.
"""
from __future__ import annotations

import numpy as np

from ..errors import ConvergenceError
from . import kernels as K
from . import march as M
from . import newton as N
from .state import Config, State, evaluate

__all__ = ["shoot", "solve_state", "solve_path", "solve_bracket"]

_KEYS = ("p", "lc", "rho_a", "alpha", "l1p")
_RES = {"clamp": N.CLAMP, "a": N.A_RES, "d": N.D_RES, "G": N.G_RES}
_EDGES = {"continuous": K.CONTINUOUS, "frictionless": K.FRICTIONLESS, "given": K.GIVEN}
_WHY = {N.BAD_START: "shooting from the start guess", N.BAD_JAC: "Jacobian outside the domain",
        N.SINGULAR: "singular Jacobian", N.NO_LINE: "Newton line search", N.NO_CONV: "Newton iterations"}


def shoot(cfg: Config, edge: str, values: dict) -> State:
    """Evaluate the state with the given values of ``p, lc, rho_a, alpha, l1p``."""
    return evaluate(cfg, values["p"], values["lc"], values.get("rho_a", 0.0),
                    values.get("alpha", 0.0), edge, values.get("l1p"))


def solve_state(cfg: Config, edge: str, fixed: dict, unknowns: tuple, x0, residuals: tuple,
                targets: dict, *, tol: float = 1e-11, max_iter: int = 40, memo: dict | None = None) -> State:
    """Solve ``residuals`` = 0 for ``unknowns``.

    Newton with a forward-difference Jacobian; with ``memo`` (a dict kept between calls of one
    continuation) the last Jacobian (``memo["J"]``: of the N_OUT observables, rows as
    ``kernels.N_OUT``, columns as ``unknowns``) is reused and updated by Broyden's rule, and recomputed
    only when a step fails to halve the residual.

    Raises
    ------
    ConvergenceError
        No convergence, or the iterate left the domain (non-finite shot).
    """
    memo = {} if memo is None else memo
    vals, unk, res, tg, J = _arrays(fixed, unknowns, residuals, targets, memo)
    k = len(unknowns)
    out = N.newton_packed(_EDGES[edge], cfg.crv, cfg.beta, cfg.n, vals, unk, res, tg,
                          np.asarray(x0, dtype=float), J, tol, max_iter)
    status = int(out[0])
    J = out[2 + k + K.N_OUT:].reshape(K.N_OUT, k)
    memo["J"] = None if np.isnan(J[0, 0]) else J
    memo["shots"] = memo.get("shots", 0) + int(out[1])
    if status != N.OK:
        raise ConvergenceError("exact membrane: " + _WHY[status],
                               {**fixed, **targets, "lambda0": cfg.lambda0})
    return _state(vals, unk, out[2:2 + k + K.N_OUT])


def solve_path(cfg: Config, edge: str, fixed: dict, unknowns: tuple, residuals: tuple, targets: dict,
               param: str, values, vs: list, xs: list, x0, *, tol: float = 1e-10, max_iter: int = 40,
               memo: dict, scale: float = 0.0) -> list:
    """``solve_state`` at each of ``values`` of the parameter ``param`` (a key of ``fixed`` or of
    ``targets``) in one compiled call, continuing from the solved (``vs``, ``xs``) (Lagrange predictor,
    Jacobian carried along; ``scale``: see ``march.abscissa``). Returns the states solved before the
    first failure (or a state turning past vertical at the clamp)."""
    vals, unk, res, tg, J = _arrays(fixed, unknowns, residuals, targets, memo)
    in_tg = param in targets
    pidx = ("a", "d", "w").index(param) if in_tg else _KEYS.index(param)
    k = len(unknowns)
    hist = np.asarray(xs, dtype=float).reshape(len(vs), k)
    done, rows, J, shots = M.march_rows(_EDGES[edge], cfg.crv, cfg.beta, cfg.n, vals, unk, res, tg, in_tg,
                                        pidx, np.asarray(values, dtype=float), np.asarray(vs, dtype=float),
                                        hist, np.asarray(x0, dtype=float), J, tol, max_iter, float(scale))
    memo["J"] = None if np.isnan(J[0, 0]) else J
    memo["shots"] = memo.get("shots", 0) + int(shots)
    return _states(vals.tolist(), unk.tolist(), rows[:done].tolist(), None if in_tg else pidx,
                   np.asarray(values, dtype=float)[:done].tolist())


def solve_bracket(cfg: Config, edge: str, fixed: dict, unknowns: tuple, residuals: tuple, targets: dict,
                  param: str, x_m, g_m: float, w: float, top: float, *, memo: dict, tol: float = 1e-10,
                  max_iter: int = 40) -> tuple:
    """Step the parameter ``param`` (a key of ``fixed``) from 0 (unknowns ``x_m``, G = ``g_m``) until
    G >= w, in one compiled call (``march.bracket_rows``). Returns (last state below w or None for
    the start, its parameter, first state at or above w or None if the branch ends first, its
    parameter)."""
    vals, unk, res, tg, J = _arrays(fixed, unknowns, residuals, targets, memo)
    pidx = _KEYS.index(param)
    found, a0, r0, a1, r1, J, shots = M.bracket_rows(
        _EDGES[edge], cfg.crv, cfg.beta, cfg.n, vals, unk, res, tg, pidx, np.asarray(x_m, dtype=float),
        float(g_m), float(w), float(top), J, tol, max_iter)
    memo["J"] = None if np.isnan(J[0, 0]) else J
    memo["shots"] = memo.get("shots", 0) + int(shots)
    prev = None
    if a0 > 0.0:
        vals[pidx] = a0
        prev = _state(vals.copy(), unk, r0)
    st = None
    if found:
        vals[pidx] = a1
        st = _state(vals.copy(), unk, r1)
    return prev, float(a0), st, float(a1)


def _arrays(fixed, unknowns, residuals, targets, memo):
    """The compiled solvers' inputs: values, unknown and residual codes, targets, start Jacobian."""
    vals = [fixed.get(k) for k in _KEYS]
    vals = np.array([0.0 if v is None else float(v) for v in vals])
    codes = memo.get("codes")
    if codes is None or codes[0] != (unknowns, residuals):
        codes = ((unknowns, residuals), np.array([_KEYS.index(k) for k in unknowns], dtype=np.int64),
                 np.array([_RES[r] for r in residuals], dtype=np.int64))
        memo["codes"] = codes
    _, unk, res = codes
    tg = np.array([targets.get("a", 0.0), targets.get("d", 0.0), targets.get("w", 0.0)])
    J = memo.get("J")  # of the N_OUT observables (``newton.newton_cached``)
    if J is None or J.shape != (K.N_OUT, len(unknowns)):
        J = np.full((K.N_OUT, len(unknowns)), np.nan)
    return vals, unk, res, tg, J


def _states(vals: list, unk: list, rows: list, pidx, values: list) -> list:
    """``_state`` of many rows, on Python lists (a row costs ~1 us here, ~5 us through numpy)."""
    k = len(unk)
    out = []
    for i, row in enumerate(rows):
        if pidx is not None:
            vals[pidx] = values[i]
        for j in range(k):
            vals[unk[j]] = row[j]
        r_end, d, th, a, f, G, l1m, l1p_, l2, u, v = row[k:k + K.N_OUT]
        p, lc, rho_a, alpha = vals[0], vals[1], vals[2], vals[3]
        out.append(State(lc, max(rho_a, 0.0), alpha, p, a, d, f, G, r_end, th, l1m, l1p_, l2, u, v))
    return out


def _state(vals, unk, row) -> State:
    """A State from the unknowns and observables of a solved row (``vals`` gets the unknowns)."""
    k = unk.shape[0]
    vals[unk] = row[:k]
    r_end, d, th, a, f, G, l1m, l1p_, l2, u, v = row[k:k + K.N_OUT].tolist()
    p, lc, rho_a, alpha = vals[:4].tolist()
    return State(lc, max(rho_a, 0.0), alpha, p, a, d, f, G, r_end, th, l1m, l1p_, l2, u, v)
