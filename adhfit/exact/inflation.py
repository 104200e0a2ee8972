"""Free inflation of the exact neo-Hookean membrane (no contact)."""
from __future__ import annotations

import math

import numpy as np
from scipy.optimize import brentq

from ..errors import ConvergenceError
from . import chebyshev as CH
from . import kernels as K
from . import newton as N
from .state import DEFAULT_N, Config, State, evaluate

__all__ = ["free_inflation", "apex_deflection", "free_curve"]

D0_NODES = 20  # apex stretches of free_curve (d0 to ~5e-12 when p changes sign, ~3e-14 otherwise; 16
# nodes left 8e-10 through p = 0 at lambda0 = 1.1, over the accepted 1e-10 of control.D0_CHECK)


def free_inflation(p: float, lambda0: float, n: int = DEFAULT_N, lc_guess: float | None = None,
                   memo: dict | None = None) -> State:
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
    memo : dict, optional
        Kept between calls of a continuation: the last slope of r(beta) in lc (secant iterations).

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

    st = None
    if lc_guess is not None:
        memo = {} if memo is None else memo
        lc, memo["slope"], y = N.free_newton(q, cfg.beta, n, lc_guess, memo.get("slope", math.nan))
        if not math.isnan(lc):
            lc = float(lc)
            st = State(lc, 0.0, 0.0, q, 0.0, float(y[1]), 0.0, 0.0, float(y[0]), float(y[2]), lc, lc, lc,
                       float(y[4]), float(y[5]))
    if st is None or not _case_one(st):
        # no guess, no quick convergence, or a root outside Case I: bracket from lambda0 upwards
        st = evaluate(cfg, q, _bracketed(resid, lambda0, p))
    if not _case_one(st):
        raise ConvergenceError("exact free inflation: no Case I state (theta > pi/2 at the clamp)",
                               {"p": p, "lambda0": lambda0})
    if p < 0.0:
        st.p, st.d, st.theta_end, st.v = p, -st.d, -st.theta_end, -st.v
    return st


def _case_one(st: State) -> bool:
    """Whether a free-inflation root (at |p| > 0) is a Case I membrane: 0 < theta_end < pi/2 and, the
    inflated meridian being convex (theta rising from the apex), 0 < d0 <= tan(theta_end). Beyond the
    pressures Case I reaches, the bracketing finds roots of r(beta) = 1 of shots that curl through
    the axis (lambda0 = 1.78, p = 1-1.47: lc 18-41, d0 -9927 to 1e10, theta_end -3.1 to 0.17)."""
    th = st.theta_end
    return 0.0 < th < 0.5 * math.pi and math.isfinite(st.d) and 0.0 < st.d <= math.tan(th)


def apex_deflection(p: float, lambda0: float, n: int = DEFAULT_N) -> float:
    """d0(p): the apex deflection of the freely inflated exact membrane, over b."""
    return free_inflation(p, lambda0, n).d


def _bracketed(resid, lambda0, p):
    lo = lambda0
    if not resid(lo) < 0.0:
        # under a high pressure the shot at lc = lambda0 can curl through the axis (a non-finite or
        # meaningless r(beta): at p = 0.676, lambda0 = 1.1 it gave +35 at n = 14, NaN at 128): the
        # lower end is then the first of a few stretches above lambda0 with r(beta) < 1
        for lc in lambda0 * (1.0 + 0.01 * np.arange(1, 6)):
            r = resid(lc)
            if math.isfinite(r) and r < 0.0:
                lo = lc
                break
        else:
            raise ConvergenceError("exact free inflation: no Case I state", {"p": p, "lambda0": lambda0})
    hi = lo * 1.05
    while not resid(hi) >= 0.0:
        lo, hi = hi, hi * 1.2
        if hi > 1e3 * lambda0:
            raise ConvergenceError("exact free inflation", {"p": p, "lambda0": lambda0})

    def finite(lc):  # the shot leaves the domain inside the bracket: no Case I state found
        r = resid(lc)
        if not math.isfinite(r):
            raise ConvergenceError("exact free inflation: no Case I state", {"p": p, "lambda0": lambda0})
        return r
    return brentq(finite, lo, hi, xtol=1e-15, rtol=1e-15)


def free_curve(p: np.ndarray, ends: list, lambda0: float, n: int = DEFAULT_N,
               nodes: int = D0_NODES, with_stretch: bool = False):
    """d0(p) at many pressures from free inflation at ``nodes`` apex stretches only.

    Parametrized by u = sign(p) sqrt(lc - lambda0) (lc the apex stretch), in which p and d0 are smooth
    from p = 0 through the pressure maximum of free inflation (d0(p) itself has a square-root branch
    point there, so a polynomial in p would converge slowly): p(u) and d0(u) are interpolated on
    Chebyshev points between the ends (``chebyshev``), and p(u) = p is inverted by Newton on the
    interpolant.

    Parameters
    ----------
    p : ndarray
        Pressures.
    ends : list of State
        Free inflation at max(p) and at min(p).
    lambda0, n
        Pre-stretch, integration steps.
    nodes : int
        Interpolation points.
    with_stretch : bool
        Also return the interpolated apex stretch at each p (a close start for a direct solve).

    Returns
    -------
    ndarray or None
        d0 at each p (with ``with_stretch``: the tuple (d0, lc)); None where a node fails or leaves
        Case I (the caller solves each p instead).
    """
    u_hi, u_lo = (math.copysign(math.sqrt(max(st.lc - lambda0, 0.0)), st.p) for st in ends)
    u = 0.5 * (u_lo + u_hi) + 0.5 * (u_hi - u_lo) * np.cos(np.pi * np.arange(nodes) / (nodes - 1))
    out = N.free_at_stretches(u, lambda0, 1.0 / lambda0, n, ends[0].p)
    if not (np.all(np.isfinite(out)) and np.all(out[2] < 0.5 * math.pi)):
        return None
    pn, dn = out[0], np.sign(u) * out[1]
    if not np.all(np.diff(pn) < 0.0):
        return None
    x0 = (np.interp(p, pn[::-1], u[::-1]) - 0.5 * (u_lo + u_hi)) / (0.5 * (u_hi - u_lo))
    d0, x = CH.invert(pn, dn, np.asarray(p, dtype=float), x0)
    if not np.all(np.isfinite(d0)):
        return None
    if not with_stretch:
        return d0
    return d0, lambda0 + (0.5 * (u_lo + u_hi) + 0.5 * (u_hi - u_lo) * x) ** 2
