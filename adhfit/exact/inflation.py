"""Free inflation of the exact neo-Hookean membrane (no contact)."""
from __future__ import annotations

import math

import numpy as np
from scipy.optimize import brentq

from ..errors import ConvergenceError
from . import chebyshev as CH
from . import kernels as K
from . import newton as N
from . import scaled as S
from .state import DEFAULT_N, Config, State, evaluate

__all__ = ["free_inflation", "apex_deflection", "free_curve", "checked_curve"]

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
    if st is None or not (st.theta_end < 0.5 * math.pi and math.isfinite(st.d)):
        # no guess, no quick convergence, or a root outside Case I: bracket from lambda0 upwards
        st = evaluate(cfg, q, _bracketed(resid, lambda0, p))
    if not (st.theta_end < 0.5 * math.pi and math.isfinite(st.d)):
        raise ConvergenceError("exact free inflation: no Case I state (theta > pi/2 at the clamp)",
                               {"p": p, "lambda0": lambda0})
    if p < 0.0:
        st.p, st.d, st.theta_end, st.v = p, -st.d, -st.theta_end, -st.v
    return st


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
    interpolant. The ends are nodes; each other node is one shot and a few Runge-Kutta steps
    (``scaled.free_at_stretches``: the scaling symmetry of the membrane equations).

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
    crv = _Curve.build(ends, lambda0, n, nodes)
    got = None if crv is None else crv.at(np.asarray(p, dtype=float))
    if got is None:
        return None
    return got if with_stretch else got[0]


def checked_curve(p: np.ndarray, ends: list, lambda0: float, rows: np.ndarray, tol: float,
                  n: int = DEFAULT_N) -> np.ndarray | None:
    """``free_curve``'s d0 at the pressures p, checked at the rows ``rows``: free inflation at each such
    row's interpolated apex stretch (``scaled.free_at_points``: one shot and a Newton in the material
    coordinate, a state independent of the interpolant, at a pressure within ~1e-8 of the row's)
    against the interpolant at that state's own pressure. None when the curve fails or a check differs
    by more than ``tol``."""
    crv = _Curve.build(ends, lambda0, n, D0_NODES)
    got = None if crv is None else crv.at(np.asarray(p, dtype=float))
    if got is None:
        return None
    d0, lc = got
    q = np.abs(p[rows])
    chk = S.free_at_points(lc[rows], q, lambda0, n)
    if not (np.all(np.isfinite(chk)) and np.all(chk[2] < 0.5 * math.pi)):
        return None
    sgn = np.where(p[rows] < 0.0, -1.0, 1.0)
    at = crv.at(sgn * chk[0])
    if at is None or not np.all(np.abs(at[0] - sgn * chk[1]) <= tol):
        return None
    return d0


class _Curve:
    """The Chebyshev interpolant of (p, d0) in u = sign(p) sqrt(lc - lambda0) (see ``free_curve``)."""

    def __init__(self, pn, dn, u_lo, u_hi, lambda0):
        self.pn, self.dn, self.lambda0 = pn, dn, lambda0
        self.mid, self.half = 0.5 * (u_lo + u_hi), 0.5 * (u_hi - u_lo)
        self.u = self.mid + self.half * np.cos(np.pi * np.arange(pn.shape[0]) / (pn.shape[0] - 1))

    @classmethod
    def build(cls, ends, lambda0, n, nodes):
        """From free inflation at the ends (max p, min p) and ``nodes`` - 2 nodes between (None: a
        node failed, left Case I, or p(u) is not monotonic)."""
        u_hi, u_lo = (math.copysign(math.sqrt(max(st.lc - lambda0, 0.0)), st.p) for st in ends)
        crv = cls(np.zeros(nodes), np.zeros(nodes), u_lo, u_hi, lambda0)
        known = np.full((3, nodes), np.nan)
        for j, st in ((0, ends[0]), (nodes - 1, ends[1])):
            known[:, j] = st.p, abs(st.d), abs(st.theta_end)
        out = S.free_at_stretches(crv.u, lambda0, n, known)
        if not (np.all(np.isfinite(out)) and np.all(out[2] < 0.5 * math.pi)):
            return None
        crv.pn, crv.dn = out[0], np.sign(crv.u) * out[1]
        return crv if np.all(np.diff(crv.pn) < 0.0) else None

    def at(self, p):
        """(d0, lc) at the pressures p (None: Newton on the interpolant failed somewhere)."""
        x0 = (np.interp(p, self.pn[::-1], self.u[::-1]) - self.mid) / self.half
        d0, x = CH.invert(self.pn, self.dn, p, x0)
        if not np.all(np.isfinite(d0)):
            return None
        return d0, self.lambda0 + (self.mid + self.half * x) ** 2
