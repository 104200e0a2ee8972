"""Input checks and the control setting (fixed p or fixed d) of an exact-membrane history."""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import brentq

from ..errors import ConvergenceError, InputError
from . import scaled as S
from .inflation import checked_curve, free_inflation
from .solve import solve_state
from .state import Config, State

__all__ = ["Control", "prepare"]


@dataclass
class Control:
    """Validated inputs plus the free-inflation state the history starts from."""

    control: str
    slip: str
    p: float | None
    d: float | None
    w: float
    rs: float
    lambda0: float
    a_max: float
    points: int
    n: int
    free: State
    n_mc: int = 0
    n_pin: int = 0
    n_del: int = 0
    _seen: list = field(default_factory=list)  # (|p|, apex stretch) of the last d0(p): continuation
    _memo: dict = field(default_factory=dict)  # slope of the free-inflation secant iterations
    _d0: dict = field(default_factory=dict)  # d0 by pressure, as solved
    _beyond: float = math.inf  # the least |p| found without a Case I free inflation (none at any |p| above)
    end: tuple = ("a_max", None)  # the loading end as given

    @property
    def crv(self) -> float:
        return 0.0 if math.isinf(self.rs) else 1.0 / self.rs

    def delta(self, st: State) -> float:
        """delta = d0(p) - d with the exact free-inflation deflection (NaN without a Case I d0)."""
        if self.control == "displacement":
            return self.free.d - st.d
        if st.p not in self._d0 and abs(st.p) >= self._beyond:
            self._d0[st.p] = math.nan
        if st.p not in self._d0:  # one value per pressure (onset, f_min, turning point may coincide)
            try:
                fi = free_inflation(st.p, self.lambda0, self.n, self._guess(abs(st.p)), self._memo)
                self._seen = (self._seen + [(abs(st.p), fi.lc)])[-3:]
                self._d0[st.p] = fi.d
            except ConvergenceError:
                self._d0[st.p] = math.nan
                self._beyond = min(self._beyond, abs(st.p))
        return self._d0[st.p] - st.d

    def deltas(self, states: list) -> np.ndarray:
        """``delta`` of every state. Under pressure control d0(p) comes from ``free_curve`` (free
        inflation at a few stretches, interpolated), checked by its truncation estimate and against
        free-inflation states independent of it at five rows spread over the range of p
        (``checked_curve``), and replaced by one solve per row where a check fails (or the curve
        leaves Case I)."""
        d = np.array([st.d for st in states], dtype=float)
        if self.control == "displacement":
            return self.free.d - d
        p = np.array([st.p for st in states], dtype=float)
        d0 = self._d0_curve(p)
        if d0 is None:
            d0 = self._d0_below_limit(p)
        if d0 is None:
            d0 = self._d0_rows(p, np.ones(p.shape, dtype=bool), np.full(p.shape, np.nan))
        return d0 - d

    def _d0_rows(self, p: np.ndarray, which: np.ndarray, out: np.ndarray) -> np.ndarray:
        """One free-inflation solve per row of ``which``, in order of |p| (past the first |p| without a
        Case I state the rest are NaN unsolved: ``_beyond``); ``out`` filled in and returned."""
        for i in sorted(np.flatnonzero(which), key=lambda k: abs(p[k])):
            out[i] = self.delta(_AtP(float(p[i]), 0.0))
        return out

    def _d0_below_limit(self, p: np.ndarray) -> np.ndarray | None:
        """d0 when the rows' pressures reach past the largest |p| with a Case I free state (the loading
        pressed on beyond it, the membrane held by the substrate): that limit from the free-inflation
        branch (``case_one_limit``), the curve over the rows below it, NaN above; None when the rows
        stay below it (or it cannot be found), i.e. the curve failed for another reason."""
        q = np.abs(p)
        limit = case_one_limit(self.lambda0, self.n, self.free)
        if limit is None or not q.max() > limit:
            return None
        out = np.full(p.shape, np.nan)
        below = q <= limit
        if np.count_nonzero(below) >= MIN_CURVE_ROWS:
            d0 = self._d0_curve(p[below])
            if d0 is not None:
                out[below] = d0
                below = np.zeros(p.shape, dtype=bool)
        self._beyond = min(self._beyond, limit * (1.0 + LIMIT_TOL))
        return self._d0_rows(p, below | ((q > limit) & (q < limit * (1.0 + LIMIT_TOL))), out)

    def _d0_curve(self, p: np.ndarray) -> np.ndarray | None:
        """d0 at the pressures p from ``checked_curve`` if it passes the checks, else None."""
        lo, hi = int(np.argmin(p)), int(np.argmax(p))
        if not p[hi] - p[lo] > 1e-9:
            return None
        rows = np.argsort(p)[(CHECK_AT * (len(p) - 1)).astype(int)]

        def curve(ends):
            if ends is None:
                return None
            return checked_curve(p, ends, self.lambda0, rows, CHECK_MARGIN * D0_CHECK, D0_CHECK, self.n)
        d0 = curve(self._node_ends(p[lo], p[hi]))
        # else the ends solved at the extreme pressures (an end node past the pressure maximum, say)
        return d0 if d0 is not None else curve(self._solved_ends(p, lo, hi))

    def _node_ends(self, p_lo: float, p_hi: float) -> list | None:
        """Free states just beyond the rows' pressures (by ``END_COVER`` of their range at most:
        ``scaled.end_node``, 1-4 shots each), from the free state the history starts at and the flat
        membrane; (max p, min p), or None where that fails."""
        fr, lam, cover = self.free, self.lambda0, END_COVER * (p_hi - p_lo)
        if fr.p == 0.0:
            return None
        u_f = math.copysign(math.sqrt(max(fr.lc - lam, 0.0)), fr.p)
        lo = S.end_node(p_lo, -cover, lam, self.n, 0.0, 0.0, u_f, fr.p)
        if not math.isfinite(lo[1]):
            return None
        far = abs(lo[1] - fr.p) > 0.1 * (p_hi - p_lo)  # else from lo and the flat membrane
        hi = S.end_node(p_hi, cover, lam, self.n, u_f if far else 0.0, fr.p if far else 0.0, lo[0], lo[1])
        if not math.isfinite(hi[1]):
            return None
        ends = [_node_state(*hi, lam), _node_state(*lo, lam)]
        self._seen = (self._seen + [(abs(st.p), st.lc) for st in ends[::-1]])[-3:]
        return ends

    def _solved_ends(self, p: np.ndarray, lo: int, hi: int) -> list | None:
        """Free inflation at the rows' extreme pressures (max p, min p); None where a solve fails."""
        ends = []
        for i in (lo, hi):  # lo first: near the free state's pressure, then continued from both
            try:
                ends.append(free_inflation(p[i], self.lambda0, self.n, self._guess(abs(p[i])), self._memo))
            except ConvergenceError:
                return None
            self._seen = (self._seen + [(abs(p[i]), ends[-1].lc)])[-3:]
        return ends[::-1]

    def _guess(self, q: float) -> float | None:
        """Apex stretch of free inflation at |p| = q, extrapolated from the last (up to 3) solved."""
        pts = [pt for pt in self._seen if pt[0] != q] or self._seen
        if not pts:
            return None
        if len({pt[0] for pt in pts}) < len(pts) or len(pts) == 1:
            return pts[-1][1]
        out = 0.0
        for i, (qi, li) in enumerate(pts):
            w = 1.0
            for j, (qj, _) in enumerate(pts):
                if j != i:
                    w *= (q - qj) / (qi - qj)
            out += w * li
        return out if out > 1.0 else pts[-1][1]

    def inputs(self) -> dict:
        return {"control": self.control, "slip": self.slip, "p": self.p, "d": self.d, "w": self.w,
                "rs": self.rs, "lambda0": self.lambda0, "a_max": self.a_max, "points": self.points,
                "membrane": "exact"}


D0_CHECK = 1e-10  # largest accepted difference of the interpolated d0 from a direct solve
CHECK_AT = np.array([0.02, 0.25, 0.5, 0.75, 0.98])  # quantiles of p of the rows checked
CHECK_MARGIN = 0.25  # the checks accept a quarter of D0_CHECK: the rows checked see a part of the
# interpolant's error (1.1e-10 where 7 checks saw 2.5e-11 and 5 7.4e-11, 20 nodes at lambda0 = 1.1)


END_COVER = 0.01  # the interpolated range of p reaches past the rows' by at most this part of theirs


MIN_CURVE_ROWS = 12  # fewer rows below the Case I limit are solved one by one
LIMIT_TOL = 1e-6  # relative bracket of the Case I limit: rows within it are solved one by one
LIMIT_GROW = 1.15  # steps in the apex-stretch variable u while bracketing the Case I limit


def case_one_limit(lambda0: float, n: int, free: State) -> float | None:
    """The largest |p| at which free inflation has a Case I state (0 < theta_end < pi/2 on the branch
    rising from the flat membrane): along the branch in u = sqrt(lc - lambda0) (one scaled shot a
    state, ``scaled.free_at_stretch``) from the touching state ``free`` outwards until theta_end
    reaches pi/2 or p stops rising, then bisection in u to ``LIMIT_TOL``. None when ``free`` is flat or
    no state is found."""
    u = math.sqrt(max(free.lc - lambda0, 0.0))
    if not u > 0.0:
        return None
    good, p_good, bad = u, abs(free.p), None
    for _ in range(60):  # bracket: the first u whose state leaves Case I or lies past the pressure maximum
        nxt = good * LIMIT_GROW
        p, _, th = S.free_at_stretch(lambda0 + nxt * nxt, lambda0, n, p_good)
        if not (math.isfinite(p) and th < 0.5 * math.pi and p > p_good):
            bad = nxt
            break
        good, p_good = nxt, p
    if bad is None:
        return None
    while bad - good > LIMIT_TOL * good:
        mid = 0.5 * (good + bad)
        p, _, th = S.free_at_stretch(lambda0 + mid * mid, lambda0, n, p_good)
        if math.isfinite(p) and th < 0.5 * math.pi and p > p_good:
            good, p_good = mid, p
        else:
            bad = mid
    return p_good


def _node_state(u: float, p: float, d: float, theta: float, lambda0: float) -> State:
    """A free-inflation state from ``scaled.end_node`` (the observables ``free_curve`` reads)."""
    lc = lambda0 + u * u
    return State(lc, 0.0, 0.0, p, 0.0, d, 0.0, 0.0, 1.0, math.copysign(theta, p), lc, lc, lc, math.nan,
                 math.nan)


@dataclass
class _AtP:
    """A stand-in state (pressure, deflection) for ``Control.delta``."""

    p: float
    d: float


def _check(name, value, lo, hi, valid, *, lo_open=True, hi_open=True):
    """The bounds here repeat ``adhfit.params.DIMENSIONLESS`` (this layer may not import it);
    ``tests/test_domain_params.py`` holds them equal, value by value. ``adhfit.simulate`` validates
    with the table itself before calling the exact membrane."""
    ok = isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(value, bool) \
        and not math.isnan(value)
    if ok:
        ok = (value > lo if lo_open else value >= lo) and (value < hi if hi_open else value <= hi)
    if not ok:
        raise InputError(name, value, valid)


def prepare(control, slip, p, d, w, rs, lambda0, a_max, delta_max, p_max, points, n) -> Control:
    """Validate the inputs (InputError naming parameter, value and range) and inflate freely."""
    if control not in ("displacement", "pressure"):
        raise InputError("control", control, "'displacement' or 'pressure'")
    if slip not in ("no-slip", "frictionless"):
        raise InputError("slip", slip, "'no-slip' or 'frictionless'")
    _check("lambda0", lambda0, 1.0, 100.0, "a float in (1, 100]", hi_open=False)
    _check("w", w, 1e-6, 10.0, "a float in [1e-6, 10]", lo_open=False, hi_open=False)
    _check("rs", rs, 0.02, math.inf, "a float in [0.02, inf] (inf: flat substrate)", lo_open=False,
           hi_open=False)
    if not isinstance(points, (int, np.integer)) or isinstance(points, bool):
        raise InputError("points", points, "an integer in [10, 50000]")
    _check("points", points, 10, 50_000, "an integer in [10, 50000]", lo_open=False, hi_open=False)
    if control == "displacement":
        _check("p", p, -1.0, 1.0, "a float in (-1, 1) under displacement control")
        if p <= -(0.0 if math.isinf(rs) else 1.0 / rs):
            raise InputError("p", p, "a float > -1/rs (the membrane must be pressed onto the substrate)")
        free = _free_at_p(p, lambda0, n)
    else:
        _check("d", d, -1.0, 1.0, "a float in (-1, 1) under pressure control")
        if 2.0 * d / (1.0 + d * d) <= -(0.0 if math.isinf(rs) else 1.0 / rs):
            raise InputError("d", d, f"such that 2d/(1+d^2) > -1/rs = {-1.0 / rs:.6g}",
                             "Contact must start at the substrate apex.")
        free = _free_at_gap(d, lambda0, n)
    given = (("a_max", a_max), ("delta_max", delta_max), ("p_max", p_max))
    ends = [(k, v) for k, v in given if v is not None]
    if len(ends) != 1:
        raise InputError("a_max", a_max, "exactly one of a_max, delta_max, p_max")
    if delta_max is not None and control != "displacement":
        raise InputError("delta_max", delta_max, "given under displacement control only (use p_max)")
    if p_max is not None and control != "pressure":
        raise InputError("p_max", p_max, "given under pressure control only (use delta_max)")
    if a_max is not None:
        _check("a_max", a_max, 1e-3, 0.95, "a float in [1e-3, 0.95] (contact radius over b)",
               lo_open=False, hi_open=False)
        if not math.isinf(rs) and a_max >= 0.95 * rs:
            raise InputError("a_max", a_max, f"a float <= 0.95 rs = {0.95 * rs:.6g} (contact on the upper "
                             "hemisphere of the substrate)")
    elif delta_max is not None:
        _check("delta_max", delta_max, 0.0, 2.0, "a float in (0, 2) (displacement over b)")
    else:
        _check("p_max", p_max, -1.0, 5.0, "a number in (-1, 5)")
        _check("p_max", p_max, free.p, 5.0, f"a float in ({free.p:.6g}, 5): above the touching pressure")
    c = Control(control, slip, p, d, w, rs, lambda0, a_max, int(points), n, free)
    c.end = ends[0]
    c._seen = [(abs(free.p), free.lc)]  # d0(p) continuation starts from the free state
    c.n_mc = max(4, round(0.3 * points))
    c.n_pin = max(4, round(0.2 * points))
    c.n_del = max(5, points - c.n_mc - c.n_pin + 2)
    return c


def _free_at_p(p, lambda0, n) -> State:
    """Displacement control starts from free inflation at p (Newton from the large-stretch cap)."""
    try:
        lc0 = cap_stretch(abs(p) / (1.0 + math.sqrt(1.0 - p * p)), lambda0)  # eq. 15's d0 (its cap)
        return free_inflation(p, lambda0, n, lc0)
    except ConvergenceError as exc:
        raise InputError("p", p, f"a pressure with a Case I free inflation at lambda0 = {lambda0}",
                         "The exact membrane would turn past vertical at the clamp (Case II is not "
                         "modelled): lower |p| or raise lambda0.") from exc


def cap_stretch(d0: float, lambda0: float) -> float:
    """The mean meridional stretch lambda0 phi/sin(phi) of the spherical cap through the clamp with
    apex deflection d0 (half-angle phi = 2 atan|d0|): a start for the apex stretch of free inflation
    (the large-stretch solution is that cap, with p = 2 d0/(1 + d0^2))."""
    phi = 2.0 * math.atan(abs(d0))
    return lambda0 * phi / math.sin(phi) if phi > 0.0 else lambda0


def _free_at_gap(d, lambda0, n) -> State:
    """Pressure control starts where the freely inflated apex touches the substrate: d0(p) = d.
    Newton on (apex stretch, p) with the clamp and the gap as residuals (``_gap_newton``); the root
    search in p, each value a free-inflation solve (``_gap_bracketed``), where that fails."""
    if d == 0.0:
        return free_inflation(0.0, lambda0, n)
    st = _gap_newton(d, lambda0, n)
    return st if st is not None else _gap_bracketed(d, lambda0, n)


def _gap_newton(d, lambda0, n) -> State | None:
    """The free state with apex deflection d by Newton on (lc, p) (compiled, residuals to 1e-13), from
    the large-stretch spherical cap through the clamp and the apex (half-angle phi = 2 atan|d|, p =
    2 d/(1 + d^2); lc its mean meridional stretch lambda0 phi/sin(phi)). None when Newton fails, the
    state is not Case I or lies past the pressure maximum of free inflation (d falling with p along
    the branch: the root search in p finds the state before it)."""
    memo: dict = {}
    try:
        st = solve_state(Config(lambda0, 0.0, n), "continuous", {"rho_a": 0.0}, ("lc", "p"),
                         [cap_stretch(d, lambda0), 2.0 * d / (1.0 + d * d)], ("clamp", "d"), {"d": d},
                         tol=1e-13, memo=memo)
    except ConvergenceError:
        return None
    J = memo.get("J")  # observables' rows (r_end 0, d 1), columns (lc, p): d d/d p along r(beta) = 1
    if J is None or not (abs(st.theta_end) < 0.5 * math.pi and st.lc > 1.0 and st.p * d > 0.0):
        return None
    return st if J[1, 1] - J[1, 0] * J[0, 1] / J[0, 0] > 0.0 else None


def _gap_bracketed(d, lambda0, n) -> State:
    """``_free_at_gap`` by brentq on p, each value a free-inflation solve continued from the last."""
    sgn = 1.0 if d > 0 else -1.0
    memo: dict = {}

    def resid(q):  # continuation in lc from the last evaluation (secant iterations, bracket fallback)
        st = free_inflation(sgn * q, lambda0, n, memo.get("lc"), memo)
        memo["lc"] = st.lc
        return sgn * st.d - abs(d)

    hi = 0.5
    while True:
        try:
            if resid(hi) > 0.0:
                break
        except ConvergenceError as exc:
            raise InputError("d", d, "a gap reachable by free inflation in Case I") from exc
        hi = 0.5 * (hi + 1.0) if hi < 0.99 else hi * 1.5
        if hi > 20:
            raise InputError("d", d, "a gap reachable by free inflation in Case I")
    q = brentq(resid, 0.0, hi, xtol=1e-15, rtol=1e-15)
    return free_inflation(sgn * q, lambda0, n, memo.get("lc"), memo)  # from the last root iterate
