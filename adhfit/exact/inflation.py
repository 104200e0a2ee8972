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

D0_NODES = 20  # apex stretches of free_curve (d0 to <~3e-11 on 50 pressure-control histories at lambda0 =
# 1.1-3, w up to 1, of which 8 refined to 39 nodes by checked_curve; 16 nodes: 23 refined, 18: 14)


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

    The nodes lie at the Chebyshev points of u = sign(p) sqrt(lc - lambda0) (lc the apex stretch)
    between the ends (which are nodes); each other node is one shot and a few Runge-Kutta steps
    (``scaled.free_at_stretches``: the scaling symmetry of the membrane equations). p is interpolated
    as a polynomial in d0 through them (smooth from p = 0 through the pressure maximum of free
    inflation, where d0(p) itself has a square-root branch point, so a polynomial in p would converge
    slowly; see ``_Curve`` for why not in u), and p(d0) = p is inverted by Newton (``chebyshev``).

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


def checked_curve(p: np.ndarray, ends: list, lambda0: float, rows: np.ndarray, tol: float, est: float,
                  n: int = DEFAULT_N) -> np.ndarray | None:
    """``free_curve``'s d0 at the pressures p, checked at the rows ``rows``: free inflation at each such
    row's interpolated apex stretch (``scaled.free_at_points``: one shot and a Newton in the material
    coordinate, a state independent of the interpolant, at a pressure within ~1e-8 of the row's)
    against the interpolant at that state's own pressure; and the interpolant's truncation estimate
    (its last Chebyshev coefficients over the least slope: above the error on 50 histories, by 1-30x)
    must not exceed ``est``. With ``D0_NODES`` nodes first, then twice the intervals
    (``_Curve.refine``: wide ranges, e.g. p = -0.64 .. 0.27 at lambda0 = 1.1). None when both fail."""
    crv = _Curve.build(ends, lambda0, n, D0_NODES)
    p = np.asarray(p, dtype=float)
    for refined in (False, True):
        got = crv.at(p, stretch=False) if crv is not None and crv.est <= est else None
        if got is not None and _passes(crv, p[rows], crv.stretch(got[0][rows]), tol, n):
            return got[0]
        crv = None if crv is None or refined else crv.refine(n)
    return None


def _passes(crv, p, lc, tol, n):
    """Whether free inflation at the apex stretches lc (near the pressures p) agrees with the curve."""
    chk = S.free_at_points(lc, np.abs(p), crv.lambda0, n)
    sgn = np.sign(p)
    got = crv.at(sgn * chk[0], stretch=False)  # (NaN where a check failed: no roots)
    return got is not None and bool(np.all(np.abs(got[0] - sgn * chk[1]) <= tol)
                                    and np.all(chk[2] < 0.5 * math.pi))


class _Curve:
    """d0(p) from free inflation at the Chebyshev points of u = sign(p) sqrt(lc - lambda0): p
    interpolated in t = d0 through the nodes' own d0 (barycentric form), resampled on the Lobatto points
    of t for ``chebyshev.invert`` (the same polynomial). In t, not u: the nodes are exact states of the
    discrete model, but its p at a given apex stretch carries a discretization part that does not
    vanish with p like p^2 (relative error ~1e-11/u^2 at n = 12): p(u) and d0(u) are rough at ~1e-11
    near u = 0, together, so d0(p) of a u-interpolant through p = 0 stopped at ~3e-11 for any number of
    nodes (1e-10 at lambda0 = 3), where p(d0) reaches ~1e-14."""

    def __init__(self, u_lo, u_hi, lambda0, nodes):
        self.lambda0 = lambda0
        self.mid, self.half = 0.5 * (u_lo + u_hi), 0.5 * (u_hi - u_lo)
        self.x = np.cos(np.pi * np.arange(nodes) / (nodes - 1))
        self.u = self.mid + self.half * self.x
        self.pn = self.dn = self.th = self.w = self.pc = self.tc = np.zeros(nodes)
        self.est = math.inf  # the truncation estimate of its d0 (``chebyshev.tail_bound``)

    @classmethod
    def build(cls, ends, lambda0, n, nodes):
        """From free inflation at the ends (max p, min p) and ``nodes`` - 2 nodes between (None: a
        node failed, left Case I, or p or d0 is not monotonic in u)."""
        u_hi, u_lo = (math.copysign(math.sqrt(max(st.lc - lambda0, 0.0)), st.p) for st in ends)
        crv = cls(u_lo, u_hi, lambda0, nodes)
        known = np.full((3, nodes), np.nan)
        for j, st in ((0, ends[0]), (nodes - 1, ends[1])):
            known[:, j] = st.p, abs(st.d), abs(st.theta_end)
        return crv._solve(known, np.full(nodes, np.nan), n)

    def refine(self, n):
        """The curve on twice the intervals: the Lobatto points of 2N - 1 nodes hold those of N, the
        new ones solved from p(u) of this curve's nodes there (one shot each)."""
        m = self.pn.shape[0]
        crv = _Curve(self.mid - self.half, self.mid + self.half, self.lambda0, 2 * m - 1)
        known = np.full((3, 2 * m - 1), np.nan)
        known[:, ::2] = self.pn, np.abs(self.dn), self.th
        pred = np.full(2 * m - 1, np.nan)
        cp = CH.coefficients(self.pn)
        for j in range(1, 2 * m - 1, 2):
            pred[j] = abs(CH.clenshaw(cp, crv.x[j]))
        return crv._solve(known, pred, n)

    def _solve(self, known, pred, n):
        out = S.free_at_stretches(self.u, self.lambda0, n, known, pred)
        self.pn, self.dn, self.th = out[0], np.sign(self.u) * out[1], out[2]
        self.w, self.tc, self.pc, self.est, ok = CH.curve(self.dn, self.pn, self.th)
        return self if ok else None

    def at(self, p, stretch=True):
        """(d0, lc) at the pressures p (lc None without ``stretch``; None: Newton on the interpolant
        failed somewhere)."""
        d0, ok = CH.roots(self.tc, self.pc, p)
        if not ok:
            return None
        return d0, (self.stretch(d0) if stretch else None)

    def stretch(self, d0):
        """The apex stretch at the apex deflections d0 (u interpolated in d0 through the nodes)."""
        return self.lambda0 + CH.bary_eval(self.dn, self.w, self.u, d0) ** 2
