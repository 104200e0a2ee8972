"""Free inflation of the exact neo-Hookean membrane (no contact)."""
from __future__ import annotations

import math

from scipy.optimize import brentq

from ..errors import ConvergenceError
from . import kernels as K
from .state import DEFAULT_N, Config, State, evaluate

__all__ = ["free_inflation", "apex_deflection"]


def free_inflation(p: float, lambda0: float, n: int = DEFAULT_N, lc_guess: float | None = None) -> State:
    """The Case I free-inflation state at pressure p (lambda1 = lambda2 = lc at the apex).

    Parameters
    ----------
    p : float
        P b/(2 mu h).
    lambda0 : float
        Pre-stretch (> 1).
    n : int
        Integration steps.
    lc_guess : float, optional
        A nearby apex stretch (continuation): Newton from it instead of a bracketing search.

    Returns
    -------
    State
        ``d`` is the apex deflection d0 (over b), ``lc`` the apex stretch.

    Raises
    ------
    ConvergenceError
        No Case I state (the membrane would turn past vertical at the clamp).
    """
    cfg = Config(lambda0, 0.0, n)
    if p == 0.0:
        return evaluate(cfg, 0.0, lambda0)
    q = abs(p)

    def resid(lc):
        return float(K.from_apex(K.FREE, lc, cfg.beta, n, q, K.A, K.B, K.C)[0]) - 1.0

    lc = _newton(resid, lc_guess) if lc_guess is not None else None
    if lc is None:
        lc = _bracketed(resid, lambda0, p)
    st = evaluate(cfg, q, lc)
    if not (st.theta_end < 0.5 * math.pi and math.isfinite(st.d)):
        raise ConvergenceError("exact free inflation: no Case I state (theta > pi/2 at the clamp)",
                               {"p": p, "lambda0": lambda0})
    if p < 0.0:
        st.p, st.d, st.theta_end, st.v = p, -st.d, -st.theta_end, -st.v
    return st


def apex_deflection(p: float, lambda0: float, n: int = DEFAULT_N) -> float:
    """d0(p): the apex deflection of the freely inflated exact membrane, over b."""
    return free_inflation(p, lambda0, n).d


def _newton(resid, x):
    """Secant-Newton from a close guess; None if it does not converge quickly."""
    fx = resid(x)
    for _ in range(12):
        h = 1e-7 * x
        dfx = (resid(x + h) - fx) / h
        if not (math.isfinite(fx) and math.isfinite(dfx)) or dfx <= 0.0:
            return None
        x = x - fx / dfx
        fx = resid(x)
        if abs(fx) < 1e-14:
            return x
    return None


def _bracketed(resid, lambda0, p):
    lo, hi = lambda0, lambda0 * 1.05
    if not resid(lo) < 0.0:
        raise ConvergenceError("exact free inflation: no Case I state", {"p": p, "lambda0": lambda0})
    while not resid(hi) >= 0.0:
        lo, hi = hi, hi * 1.2
        if hi > 1e3 * lambda0:
            raise ConvergenceError("exact free inflation", {"p": p, "lambda0": lambda0})
    return brentq(resid, lo, hi, xtol=1e-15, rtol=1e-15)
