"""Free inflation of the exact neo-Hookean membrane (no contact)."""
from __future__ import annotations

import math

from scipy.optimize import brentq

from ..errors import ConvergenceError
from . import kernels as K
from .state import Config, State, evaluate

__all__ = ["free_inflation", "apex_deflection"]


def free_inflation(p: float, lambda0: float, n: int = 64) -> State:
    """The Case I free-inflation state at pressure p (lambda1 = lambda2 = lc at the apex).

    Parameters
    ----------
    p : float
        P b/(2 mu h).
    lambda0 : float
        Pre-stretch (> 1).
    n : int
        Integration steps.

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

    lo, hi = lambda0, lambda0 * 1.05
    while resid(hi) < 0.0:
        lo, hi = hi, hi * 1.2
        if hi > 1e3 * lambda0:
            raise ConvergenceError("exact free inflation", {"p": p, "lambda0": lambda0})
    lc = brentq(resid, lo, hi, xtol=1e-15, rtol=1e-15)
    st = evaluate(cfg, q, lc)
    if not (st.theta_end < 0.5 * math.pi and math.isfinite(st.d)):
        raise ConvergenceError("exact free inflation: no Case I state (theta > pi/2 at the clamp)",
                               {"p": p, "lambda0": lambda0})
    if p < 0.0:
        st.p, st.d, st.theta_end, st.v = p, -st.d, -st.theta_end, -st.v
    return st


def apex_deflection(p: float, lambda0: float, n: int = 64) -> float:
    """d0(p): the apex deflection of the freely inflated exact membrane, over b."""
    return free_inflation(p, lambda0, n).d
