"""Newton on the shooting unknowns of one exact-membrane state.

A problem names its unknowns among ``lc, rho_a, alpha, l1p, p`` and as many residuals among
``clamp`` (r(beta) = 1, i.e. b = lambda0 beta), ``a`` (contact radius = target), ``d`` (gap =
target) and ``G`` (G = w). The Jacobian is taken by forward differences of the shot (the shot is a
fixed-step integration, smooth in its inputs to rounding).
"""
from __future__ import annotations

import math

import numpy as np

from ..errors import ConvergenceError
from .state import Config, State, evaluate

__all__ = ["shoot", "solve_state"]

_KEYS = ("p", "lc", "rho_a", "alpha", "l1p")


def shoot(cfg: Config, edge: str, values: dict) -> State:
    """Evaluate the state with the given values of ``p, lc, rho_a, alpha, l1p``."""
    return evaluate(cfg, values["p"], values["lc"], values.get("rho_a", 0.0),
                    values.get("alpha", 0.0), edge, values.get("l1p"))


def _residual(st: State, names, targets) -> np.ndarray:
    out = np.empty(len(names))
    for i, nm in enumerate(names):
        if nm == "clamp":
            out[i] = st.r_end - 1.0
        elif nm == "a":
            out[i] = st.a - targets["a"]
        elif nm == "d":
            out[i] = st.d - targets["d"]
        elif nm == "G":
            out[i] = st.G - targets["w"]
        else:
            raise ValueError(nm)
    return out


def _at(cfg, edge, fixed, unknowns, x):
    vals = dict(fixed)
    vals.update(zip(unknowns, (float(v) for v in x)))
    return shoot(cfg, edge, vals)


def solve_state(cfg: Config, edge: str, fixed: dict, unknowns: tuple, x0, residuals: tuple,
                targets: dict, *, tol: float = 1e-11, max_iter: int = 40, memo: dict | None = None) -> State:
    """Solve ``residuals`` = 0 for ``unknowns``.

    Newton with a forward-difference Jacobian; with ``memo`` (a dict kept between calls of one
    continuation) the last Jacobian is reused and updated by Broyden's rule, and recomputed only when a
    step fails to halve the residual.

    Raises
    ------
    ConvergenceError
        No convergence, or the iterate left the domain (non-finite shot).
    """
    x = np.asarray(x0, dtype=float).copy()
    info = {**fixed, **targets, "lambda0": cfg.lambda0}
    memo = {} if memo is None else memo
    st = _safe(cfg, edge, fixed, unknowns, x)
    if st is None:
        raise ConvergenceError("exact membrane: shooting from the start guess", info)
    res = _residual(st, residuals, targets)
    J = memo.get("J")
    fresh = False
    for _ in range(max_iter):
        nrm = float(np.max(np.abs(res)))
        if nrm < tol:
            memo["J"] = J
            return st
        if J is None or J.shape != (len(res), len(x)):
            J, fresh = _jacobian(cfg, edge, fixed, unknowns, x, res, residuals, targets, info), True
        try:
            dx = np.linalg.solve(J, -res)
        except np.linalg.LinAlgError:
            dx = None
        sn = None if dx is None else _safe(cfg, edge, fixed, unknowns, x + dx)
        rn = None if sn is None else _residual(sn, residuals, targets)
        if rn is not None and np.max(np.abs(rn)) < 0.5 * nrm:
            J = J + np.outer((rn - res) - J @ dx, dx) / float(dx @ dx)
            x, st, res, fresh = x + dx, sn, rn, False
            continue
        if not fresh:
            J = None
            continue
        x, st, res = _line_search(cfg, edge, fixed, unknowns, x, dx, nrm, residuals, targets, info)
        J = None
    memo["J"] = None
    if float(np.max(np.abs(res))) < 1e3 * tol:
        return st
    raise ConvergenceError("exact membrane: Newton iterations", info)


def _jacobian(cfg, edge, fixed, unknowns, x, res, residuals, targets, info):
    J = np.empty((len(res), len(x)))
    for j in range(len(x)):
        h = 1e-7 * max(1e-3, abs(x[j]))
        xp = x.copy()
        xp[j] += h
        sp = _safe(cfg, edge, fixed, unknowns, xp)
        if sp is None:
            xp[j] -= 2 * h
            h = -h
            sp = _safe(cfg, edge, fixed, unknowns, xp)
            if sp is None:
                raise ConvergenceError("exact membrane: Jacobian outside the domain", info)
        J[:, j] = (_residual(sp, residuals, targets) - res) / h
    return J


def _line_search(cfg, edge, fixed, unknowns, x, dx, nrm, residuals, targets, info):
    if dx is None:
        raise ConvergenceError("exact membrane: singular Jacobian", info)
    lam = 1.0
    while lam > 1e-4:
        xn = x + lam * dx
        sn = _safe(cfg, edge, fixed, unknowns, xn)
        if sn is not None:
            rn = _residual(sn, residuals, targets)
            if np.max(np.abs(rn)) < (1 - 1e-4 * lam) * nrm or nrm < 1e-9:
                return xn, sn, rn
        lam *= 0.5
    raise ConvergenceError("exact membrane: Newton line search", info)


def _safe(cfg, edge, fixed, unknowns, x):
    vals = dict(fixed)
    vals.update(zip(unknowns, (float(v) for v in x)))
    if vals["lc"] <= 1.0 or vals.get("rho_a", 0.0) < 0.0 or vals.get("rho_a", 0.0) >= cfg.beta:
        return None
    if "l1p" in vals and vals["l1p"] is not None and vals["l1p"] <= 0.0:
        return None
    if edge == "frictionless" and not 0.0 <= vals.get("alpha", 0.0) < 0.5 * math.pi:
        return None
    try:
        st = shoot(cfg, edge, vals)
    except (ValueError, ZeroDivisionError, OverflowError):
        return None
    if not all(math.isfinite(v) for v in (st.r_end, st.d, st.f, st.G, st.theta_end)):
        return None
    return st
