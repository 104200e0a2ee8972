"""Plain scipy baseline of the forward model: adaptive ``quad`` for every integral, ``brentq`` for roots.

This is the model as a competent engineer would code it straight from the paper (Yang, Srivastava &
Long, sections 2-3), point by point, *without* the closed-form elliptic integrals of docs/numerics.md B2.
It is the yardstick for ``benchmarks/bench_time.py`` and ``benchmarks/bench_accuracy.py`` and is never
imported by the ``adhfit`` package.

Everything is dimensionless (docs/contracts.md A1, B1): lengths over b, ``kappa = p = P b / (2 mu h)``,
``D = kappa C1``, ``C2 = C2bar / b**2``.  The non-contacting membrane (a <= r <= 1) obeys

    sin(theta) = (kappa r^2 + D) / sqrt(r^2 + C2)                                   (eq. 38)
    Q(r)       = (r^2 + C2) - (kappa r^2 + D)^2
    J0         = int dr / sqrt(Q)            = ln(beta / rho_a)          (eqs. 35, 37, 41, 42, 57)
    J1         = int (kappa r^2 + D) / sqrt(Q) dr,   d = J1 - a^2/(rs + sqrt(rs^2 - a^2))  (25, 48, 58)
    f          = -pi D                                                          (eqs. 26, 50, 59)

``J0`` is the lambda0-free material coordinate ``L = ln(beta/rho)`` of the contact edge, so no
observable depends on lambda0 (docs/numerics.md C).  Q is a concave quadratic in ``u = r^2``, so it is positive
on the whole interval iff it is positive at both ends; that is the admissibility test used here.

Only the no-slip branch theta_a > pi/2 (eq. 42, reached under pressure control at p well below -1)
has an integrable 1/sqrt endpoint singularity at the turning point ``eta`` (eq. 44, the smaller root);
it is integrated with quad's algebraic weight (``weight="alg"``).

Public functions: :func:`history` and :func:`state`.  Tolerances: ``quad_tol`` is both ``epsabs`` and
``epsrel`` of every quad call; ``root_tol`` is ``xtol`` (and ``rtol``, floored at scipy's minimum) of
every brentq call.
"""
from __future__ import annotations

import math
import warnings
from dataclasses import dataclass
from typing import Callable

import numpy as np
from scipy import integrate, optimize

STAGES = ("making_contact", "pinning", "delamination")
COLUMNS = ("a", "alpha", "p", "d", "delta", "f", "G")
_RTOL_MIN = 4.0 * np.finfo(float).eps
_QUAD_LIMIT = 200


class BaselineError(RuntimeError):
    """A baseline solve failed (no bracket, inadmissible state); carries its inputs."""


@dataclass(frozen=True)
class Tol:
    """Tolerances of one run.

    Attributes
    ----------
    quad : float
        ``epsabs`` and ``epsrel`` of every ``scipy.integrate.quad`` call.
    root : float
        ``xtol`` of every ``scipy.optimize.brentq`` call (``rtol`` = max(root, 4 eps)).
    """

    quad: float = 1e-10
    root: float = 1e-12


# --------------------------------------------------------------------------------------------------
# geometry and integrals
# --------------------------------------------------------------------------------------------------
def cap_drop(a: float, rs: float) -> float:
    """Height of the substrate cap over radius a, ``rs - sqrt(rs^2 - a^2)`` without cancellation."""
    if math.isinf(rs):
        return 0.0
    return a * a / (rs + math.sqrt(rs * rs - a * a))


def d0_free(p: float) -> float:
    """Free-inflation apex deflection over b, ``p / (1 + sqrt(1 - p^2))`` (eq. 15); NaN if |p| > 1."""
    if abs(p) > 1.0:
        return math.nan
    return p / (1.0 + math.sqrt(1.0 - p * p))


def _q(r: float, kappa: float, c2: float, dd: float) -> float:
    s = kappa * r * r + dd
    return r * r + c2 - s * s


def admissible(a: float, kappa: float, c2: float, dd: float) -> bool:
    """True when Q > 0 on (a, 1]: the free membrane's tangent never turns vertical (Case I)."""
    return a * a + c2 >= 0.0 and _q(1.0, kappa, c2, dd) > 0.0 and _q(a, kappa, c2, dd) >= 0.0


def _quad(fun: Callable[[float], float], lo: float, hi: float, tol: Tol, **kw) -> float:
    with warnings.catch_warnings():
        # a warning here only means quad could not certify tol; the accuracy benchmark measures it
        warnings.simplefilter("ignore", integrate.IntegrationWarning)
        val, _ = integrate.quad(fun, lo, hi, epsabs=tol.quad, epsrel=tol.quad, limit=_QUAD_LIMIT, **kw)
    return val


def _lower_root(kappa: float, c2: float, dd: float) -> tuple[float, float]:
    """Roots of Q in u = r^2 as (q, u_minus): Q(u) = (q - kappa^2 u)(u - u_minus) (eq. 44, stable form)."""
    b_ = 1.0 - 2.0 * kappa * dd
    c_ = c2 - dd * dd
    disc = math.sqrt(max(1.0 - 4.0 * kappa * dd + 4.0 * kappa * kappa * c2, 0.0))
    q = 0.5 * (b_ + disc) if b_ >= 0.0 else 2.0 * kappa * kappa * c_ / (disc - b_)
    return q, -c_ / q


def integrals(a: float, kappa: float, c2: float, dd: float, tol: Tol, turned: bool = False
              ) -> tuple[float, float]:
    """Return ``(J0, J1)`` over the free membrane with quad.

    Parameters
    ----------
    a, kappa, c2, dd : float
        Contact radius, pressure, C2 and D (dimensionless).
    tol : Tol
        Quadrature tolerance.
    turned : bool
        The theta_a > pi/2 branch (eqs. 42, 47): r runs from a down to eta, then up to 1.

    Returns
    -------
    J0, J1 : float
        ``J0 = L = ln(beta/rho_a)`` and ``J1 = -z(a)``.
    """
    if not turned:
        j0 = _quad(lambda r: 1.0 / math.sqrt(_q(r, kappa, c2, dd)), a, 1.0, tol)
        j1 = _quad(lambda r: (kappa * r * r + dd) / math.sqrt(_q(r, kappa, c2, dd)), a, 1.0, tol)
        return j0, j1
    q, u_minus = _lower_root(kappa, c2, dd)
    eta = math.sqrt(u_minus)

    def g0(r: float) -> float:   # 1/sqrt(Q) = (r - eta)^(-1/2) g0(r)
        return 1.0 / math.sqrt((r + eta) * (q - kappa * kappa * r * r))

    def g1(r: float) -> float:
        return (kappa * r * r + dd) * g0(r)

    alg = dict(weight="alg", wvar=(-0.5, 0.0))
    j0 = _quad(g0, eta, a, tol, **alg) + _quad(g0, eta, 1.0, tol, **alg)
    j1 = _quad(g1, eta, a, tol, **alg) + _quad(g1, eta, 1.0, tol, **alg)
    return j0, j1


# --------------------------------------------------------------------------------------------------
# constants of each stage (eqs. 19, 39, 55-56) and energy release rates (eqs. 52, 60)
# --------------------------------------------------------------------------------------------------
def making_constants(a: float, kappa: float, rs: float) -> tuple[float, float]:
    """``(C2, D)`` while making contact (eq. 19): C2 = 0, D = -(kappa + 1/rs) a^2."""
    return 0.0, -(kappa + 1.0 / rs) * a * a


def frictionless_constants(a: float, alpha: float, kappa: float, rs: float) -> tuple[float, float]:
    """``(C2, D)`` for frictionless contact at angle alpha (eqs. 55, 56)."""
    ta = math.tan(alpha)
    root = math.sqrt(1.0 - (a / rs) ** 2)
    return (a * ta) ** 2, a * root * ta - (kappa + 1.0 / rs) * a * a


def theta_edge(a: float, alpha: float, rs: float) -> float:
    """Tangent angle of the free membrane at the contact edge, ``alpha - asin(a/rs)`` (eq. 22)."""
    return alpha - math.asin(a / rs)


def noslip_d(a: float, alpha: float, c2: float, kappa: float, rs: float) -> float:
    """D for no-slip contact (eq. 39): sin(theta_a) sqrt(a^2 + C2) - kappa a^2."""
    return math.sin(theta_edge(a, alpha, rs)) * math.sqrt(a * a + c2) - kappa * a * a


def g_frictionless(alpha: float) -> float:
    """Energy release rate over mu h, frictionless (eq. 60)."""
    return 0.5 * math.tan(alpha) ** 2


def g_noslip(alpha: float, a: float, c2: float) -> float:
    """Energy release rate over mu h, no slip (eq. 52)."""
    t = math.sqrt(1.0 + c2 / (a * a))
    return t * (1.0 - math.cos(alpha)) + 0.5 * (t - 1.0) ** 2


def alpha_from_g(t: float, w: float) -> float:
    """Contact angle with G = w at stretch ratio t = sqrt(1 + C2/a^2) (eq. 62 solved for alpha).

    NaN when no angle in [0, pi] satisfies it.
    """
    c = 1.0 - (w - 0.5 * (t - 1.0) ** 2) / t
    if not -1.0 <= c <= 1.0:
        return math.nan
    return math.acos(c)


# --------------------------------------------------------------------------------------------------
# root finding: brentq with an outward bracket search
# --------------------------------------------------------------------------------------------------
def _finite(fun: Callable[[float], float], x: float) -> float:
    try:
        v = fun(x)
    except (ValueError, ZeroDivisionError, OverflowError):
        return math.nan
    return v if math.isfinite(v) else math.nan


def _admissible_start(fun: Callable[[float], float], x0: float, lo: float, hi: float, step: float,
                      what: str) -> float:
    """x0 if fun is finite there, else the nearest finite point on a doubling probe outward."""
    if not math.isnan(fun(x0)):
        return x0
    h = step
    for _ in range(40):
        for x in (x0 + h, x0 - h):
            if lo < x < hi and not math.isnan(fun(x)):
                return x
        h *= 2.0
    raise BaselineError(f"{what}: no admissible point found near x0={x0!r}")


def _check_root(fun: Callable[[float], float], x: float, tol: Tol, what: str) -> float:
    """Reject a "root" where the residual is not small: brentq also converges to a jump.

    Nested solves (pressure control) can make the outer residual jump when the inner solve switches
    between roots; brentq then returns the jump, silently.  The residuals here (J0 - L, gap - d) are
    O(1) quantities computed to about quad_tol.
    """
    r = fun(x)
    if not abs(r) <= 1e4 * max(tol.quad, tol.root, 1e-12):
        raise BaselineError(f"{what}: brentq stopped at x={x!r} with residual {r!r} (a jump, not a root)")
    return x


def solve(fun: Callable[[float], float], x0: float, lo: float, hi: float, step: float, tol: Tol,
          what: str) -> float:
    """Root of ``fun`` near ``x0`` in (lo, hi) with brentq; bracket found by doubling steps outward.

    ``fun`` may return NaN where the state is inadmissible; the search then bisects towards the
    admissibility limit, so roots right next to it are still bracketed.
    """
    memo: dict[float, float] = {}

    def fun_memo(x: float) -> float:
        # brentq re-evaluates the bracket ends; nested solves must give it the same numbers again
        if x not in memo:
            memo[x] = _finite(fun, x)
        return memo[x]

    x0 = _admissible_start(fun_memo, x0, lo, hi, step, what)
    f0 = fun_memo(x0)
    if f0 == 0.0:
        return x0
    sides = [[x0, f0, step, True], [x0, f0, -step, True]]
    for _ in range(60):
        for side in sides:
            x_in, f_in, h, alive = side
            if not alive:
                continue
            x_out = min(max(x_in + h, lo), hi)
            if x_out == x_in:
                side[3] = False
                continue
            f_out = fun_memo(x_out)
            if math.isnan(f_out):
                side[2] = 0.5 * h           # creep towards the admissibility limit
                side[3] = abs(h) > 1e-14 * max(1.0, abs(x_in))
                continue
            if f_out * f_in <= 0.0:
                a_, b_ = sorted((x_in, x_out))
                try:
                    x = optimize.brentq(fun_memo, a_, b_, xtol=tol.root, rtol=max(tol.root, _RTOL_MIN))
                except ValueError as e:     # an inadmissible (NaN) point inside the bracket
                    raise BaselineError(f"{what}: {e}") from e
                return _check_root(fun_memo, x, tol, what)
            side[0], side[1], side[2] = x_out, f_out, 2.0 * h
    raise BaselineError(f"{what}: no sign change found from x0={x0!r} in ({lo!r}, {hi!r})")


# --------------------------------------------------------------------------------------------------
# one state at fixed pressure kappa
# --------------------------------------------------------------------------------------------------
def _nan_if_bad(ok: bool, value: float) -> float:
    return value if ok else math.nan


def gap(a: float, kappa: float, c2: float, dd: float, rs: float, tol: Tol, turned: bool = False) -> float:
    """Gap d over b (eqs. 25, 48, 58); NaN when inadmissible."""
    if not admissible(a, kappa, c2, dd):
        return math.nan
    return integrals(a, kappa, c2, dd, tol, turned)[1] - cap_drop(a, rs)


def material_coordinate(a: float, kappa: float, c2: float, dd: float, tol: Tol, turned: bool = False
                        ) -> float:
    """L = ln(beta/rho_a) of the contact edge (eqs. 35, 41, 42, 57); NaN when inadmissible."""
    if not admissible(a, kappa, c2, dd):
        return math.nan
    return integrals(a, kappa, c2, dd, tol, turned)[0]


def making_l(a: float, kappa: float, rs: float, tol: Tol) -> float:
    """Material coordinate of the edge at the end of making contact (eq. 37)."""
    return material_coordinate(a, kappa, *making_constants(a, kappa, rs), tol)


def fl_pin_a(alpha: float, kappa: float, rs: float, big_l: float, a0: float, tol: Tol) -> float:
    """Frictionless pinning/delamination: contact radius with J0 = L at angle alpha (eq. 57)."""
    a_hi = min(1.0, rs) * (1.0 - 1e-12)

    def res(a: float) -> float:
        c2, dd = frictionless_constants(a, alpha, kappa, rs)
        return material_coordinate(a, kappa, c2, dd, tol) - big_l

    return solve(res, a0, 1e-12, a_hi, 0.02 * a0, tol, "frictionless pinning radius")


def _ns_turned(a: float, alpha: float, rs: float) -> bool:
    return theta_edge(a, alpha, rs) > 0.5 * math.pi


def ns_pin_c2(alpha: float, a: float, kappa: float, rs: float, big_l: float, c20: float, tol: Tol
              ) -> float:
    """No-slip pinning: C2 with J0 = L at fixed a and angle alpha (eqs. 39, 41/42)."""
    turned = _ns_turned(a, alpha, rs)

    def res(c2: float) -> float:
        dd = noslip_d(a, alpha, c2, kappa, rs)
        return material_coordinate(a, kappa, c2, dd, tol, turned) - big_l

    step = 0.02 * a * a + 0.02 * abs(c20)
    return solve(res, c20, -a * a * (1.0 - 1e-12), 1e6, step, tol, "no-slip pinning C2")


def ns_del_t(a: float, kappa: float, rs: float, w: float, big_l: float, t0: float, tol: Tol) -> float:
    """No-slip delamination: stretch ratio t = sqrt(1 + C2/a^2) with G = w and J0 = L (eqs. 61, 62).

    The angle follows from G = w in closed form (:func:`alpha_from_g`), so one brentq in t suffices.
    """
    def res(t: float) -> float:
        alpha = alpha_from_g(t, w)
        if math.isnan(alpha):
            return math.nan
        c2 = a * a * (t * t - 1.0)
        dd = noslip_d(a, alpha, c2, kappa, rs)
        return material_coordinate(a, kappa, c2, dd, tol, _ns_turned(a, alpha, rs)) - big_l

    step = min(0.01, 0.05 * math.sqrt(2.0 * w))   # the admissible t-interval is 2 sqrt(2w) wide
    return solve(res, t0, 1e-9, 1.0 + math.sqrt(2.0 * w), step, tol, "no-slip delamination t")


# --------------------------------------------------------------------------------------------------
# scenes and states
# --------------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Scene:
    """A dimensionless scene: ``p`` fixed under displacement control, ``d`` under pressure control."""

    control: str
    slip: str
    p: float | None
    d: float | None
    w: float
    rs: float
    a_max: float
    tol: Tol

    @property
    def alpha_d(self) -> float:
        """Frictionless delamination angle, atan(sqrt(2 w)) (eq. 63)."""
        return math.atan(math.sqrt(2.0 * self.w))


def _check(control: str, slip: str, p: float | None, d: float | None) -> None:
    if control not in ("displacement", "pressure"):
        raise ValueError(f"control must be 'displacement' or 'pressure', got {control!r}")
    if slip not in ("no-slip", "frictionless"):
        raise ValueError(f"slip must be 'no-slip' or 'frictionless', got {slip!r}")
    if (control == "displacement") != (p is not None) or (control == "pressure") != (d is not None):
        raise ValueError("displacement control takes p (not d); pressure control takes d (not p)")


def _solve_p(sc: Scene, gap_at: Callable[[float], float], p0: float, what: str) -> float:
    """Pressure with gap_at(p) = d (pressure control); inner failures count as inadmissible."""
    def res(p: float) -> float:
        try:
            return gap_at(p) - sc.d
        except BaselineError:
            return math.nan

    return solve(res, p0, -1e3, 1e3, 0.02, sc.tol, what)


def _row(sc: Scene, stage: str, a: float, alpha: float, p: float, d: float, c2: float, dd: float,
         g: float) -> dict:
    if not math.isfinite(d):
        raise BaselineError(f"{stage} at a={a!r}, alpha={alpha!r}, p={p!r}: outside the model's domain "
                            "(Q <= 0 on the free membrane: its tangent turns vertical)")
    return dict(stage=stage, a=a, alpha=alpha, p=p, d=d, delta=d0_free(p) - d, f=-math.pi * dd, G=g,
                c2=c2)


# --- making contact (eqs. 19, 25, 26) ---------------------------------------------------------
def making_state(sc: Scene, a: float, p0: float | None = None) -> dict:
    """State while making contact at radius a (displacement control: explicit; pressure: solve p)."""
    if sc.control == "displacement":
        p = sc.p
    elif a == 0.0:
        p = 2.0 * sc.d / (1.0 + sc.d ** 2)              # eq. 64
    else:
        p = _solve_p(sc, lambda k: gap(a, k, *making_constants(a, k, sc.rs), sc.rs, sc.tol),
                     2.0 * sc.d / (1.0 + sc.d ** 2) if p0 is None else p0, "making contact p")
    c2, dd = making_constants(a, p, sc.rs)
    d = gap(a, p, c2, dd, sc.rs, sc.tol) if sc.control == "displacement" else sc.d
    return _row(sc, "making_contact", a, 0.0, p, d, c2, dd, 0.0)


# --- frictionless pinning and delamination (eqs. 55-60, 63) -----------------------------------
def _fl_state(sc: Scene, stage: str, alpha: float, p: float, a: float) -> dict:
    c2, dd = frictionless_constants(a, alpha, p, sc.rs)
    d = gap(a, p, c2, dd, sc.rs, sc.tol) if sc.control == "displacement" else sc.d
    return _row(sc, stage, a, alpha, p, d, c2, dd, g_frictionless(alpha))


def fl_pinning_state(sc: Scene, alpha: float, p_m: float, big_l: float, a0: float,
                     p0: float | None = None) -> dict:
    """Frictionless pinning at angle alpha: solve a (eq. 57), and p under pressure control."""
    if sc.control == "displacement":
        return _fl_state(sc, "pinning", alpha, sc.p, fl_pin_a(alpha, sc.p, sc.rs, big_l, a0, sc.tol))
    cache: dict[float, float] = {}

    def gap_at(k: float) -> float:
        a = fl_pin_a(alpha, k, sc.rs, big_l, a0, sc.tol)
        cache[k] = a
        return gap(a, k, *frictionless_constants(a, alpha, k, sc.rs), sc.rs, sc.tol)

    p = _solve_p(sc, gap_at, p_m if p0 is None else p0, "frictionless pinning p")
    a = cache[p] if p in cache else fl_pin_a(alpha, p, sc.rs, big_l, a0, sc.tol)
    return _fl_state(sc, "pinning", alpha, p, a)


def fl_delamination_state(sc: Scene, a: float, p0: float | None = None) -> dict:
    """Frictionless delamination at radius a: explicit (displacement control) or solve p."""
    alpha = sc.alpha_d
    if sc.control == "displacement":
        p = sc.p
    else:
        p = _solve_p(sc, lambda k: gap(a, k, *frictionless_constants(a, alpha, k, sc.rs), sc.rs, sc.tol),
                     p0, "frictionless delamination p")
    return _fl_state(sc, "delamination", alpha, p, a)


# --- no-slip pinning and delamination (eqs. 39-52, 61, 62) --------------------------------------
def _ns_state(sc: Scene, stage: str, a: float, alpha: float, p: float, c2: float) -> dict:
    dd = noslip_d(a, alpha, c2, p, sc.rs)
    turned = _ns_turned(a, alpha, sc.rs)
    d = gap(a, p, c2, dd, sc.rs, sc.tol, turned) if sc.control == "displacement" else sc.d
    return _row(sc, stage, a, alpha, p, d, c2, dd, g_noslip(alpha, a, c2))


def ns_pinning_state(sc: Scene, alpha: float, p_m: float, big_l: float, c20: float = 0.0,
                     p0: float | None = None) -> dict:
    """No-slip pinning at angle alpha, a = a_max: solve C2 (eqs. 39, 41/42), and p under pressure control."""
    a = sc.a_max
    turned = _ns_turned(a, alpha, sc.rs)
    if sc.control == "displacement":
        return _ns_state(sc, "pinning", a, alpha, sc.p, ns_pin_c2(alpha, a, sc.p, sc.rs, big_l, c20, sc.tol))
    cache: dict[float, float] = {}

    def gap_at(k: float) -> float:   # inner solve always starts from the previous row: deterministic
        c2 = ns_pin_c2(alpha, a, k, sc.rs, big_l, c20, sc.tol)
        cache[k] = c2
        return gap(a, k, c2, noslip_d(a, alpha, c2, k, sc.rs), sc.rs, sc.tol, turned)

    p = _solve_p(sc, gap_at, p_m if p0 is None else p0, "no-slip pinning p")
    c2 = cache[p] if p in cache else ns_pin_c2(alpha, a, p, sc.rs, big_l, c20, sc.tol)
    return _ns_state(sc, "pinning", a, alpha, p, c2)


def ns_material_coordinate(sc: Scene, a: float, big_l_m: float) -> float:
    """L_d = L_m + ln(rho_am/rho_ad) of the no-slip contact edge at radius a (eq. 61)."""
    am, rs = sc.a_max, sc.rs
    s_m = 1.0 if math.isinf(rs) else 1.0 + math.sqrt(1.0 - (am / rs) ** 2)
    s_d = 1.0 if math.isinf(rs) else 1.0 + math.sqrt(1.0 - (a / rs) ** 2)
    return big_l_m + math.log(am / a) + math.log(s_d / s_m)


def _t_start(w: float) -> float:
    return 1.0 + 0.5 * math.sqrt(2.0 * w) if w > 2.0 else 1.0


def ns_delamination_state(sc: Scene, a: float, big_l_m: float, t0: float | None = None,
                          p0: float | None = None) -> dict:
    """No-slip delamination at radius a: solve t (and alpha from G = w), and p under pressure control."""
    big_l = ns_material_coordinate(sc, a, big_l_m)
    t_start = _t_start(sc.w) if t0 is None else t0
    if sc.control == "displacement":
        p = sc.p
        t = ns_del_t(a, p, sc.rs, sc.w, big_l, t_start, sc.tol)
    else:
        cache: dict = {}

        def gap_at(k: float) -> float:
            t_ = ns_del_t(a, k, sc.rs, sc.w, big_l, t_start, sc.tol)
            cache[k] = t_
            al = alpha_from_g(t_, sc.w)
            c2 = a * a * (t_ * t_ - 1.0)
            return gap(a, k, c2, noslip_d(a, al, c2, k, sc.rs), sc.rs, sc.tol, _ns_turned(a, al, sc.rs))

        p = _solve_p(sc, gap_at, p0, "no-slip delamination p")
        t = cache[p] if p in cache else ns_del_t(a, p, sc.rs, sc.w, big_l, t_start, sc.tol)
    alpha = alpha_from_g(t, sc.w)
    row = _ns_state(sc, "delamination", a, alpha, p, a * a * (t * t - 1.0))
    row["t"] = t
    return row


# --------------------------------------------------------------------------------------------------
# public API
# --------------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class LoadingEnd:
    """What pinning and delamination need from the end of loading: p_m and L_m (eq. 37)."""

    p_m: float
    big_l_m: float


def loading_end(sc: Scene) -> LoadingEnd:
    """Pressure and material coordinate of the contact edge at a = a_max (end of making contact)."""
    p_m = making_state(sc, sc.a_max)["p"]
    return LoadingEnd(p_m, making_l(sc.a_max, p_m, sc.rs, sc.tol))


_MARCH_STEP = 0.05      # rad: continuation step in alpha under pressure control


def march_pinning(sc: Scene, end: LoadingEnd, alpha: float, w_stop: float | None = None) -> dict:
    """Pinning state at ``alpha`` reached by continuation from alpha = 0 (pressure control needs it:
    the pressure moves far from p_m and a cold start loses the bracket).  With ``w_stop``, stop at
    the last state with G < w_stop instead.
    """
    n = max(1, math.ceil(alpha / _MARCH_STEP)) if sc.control == "pressure" else 1
    a_prev, c2_prev, p_prev = sc.a_max, 0.0, end.p_m
    prev = None
    for al in np.linspace(alpha / n, alpha, n):
        if sc.slip == "frictionless":
            r = fl_pinning_state(sc, float(al), end.p_m, end.big_l_m, a_prev, p_prev)
        else:
            r = ns_pinning_state(sc, float(al), end.p_m, end.big_l_m, c2_prev, p_prev)
        if w_stop is not None and r["G"] >= w_stop:
            return prev if prev is not None else r
        prev, a_prev, c2_prev, p_prev = r, r["a"], r["c2"], r["p"]
    return prev


def onset_state(sc: Scene, end: LoadingEnd) -> dict:
    """The state where G first reaches w: frictionless alpha = atan(sqrt(2w)); no slip a = a_max."""
    if sc.slip == "frictionless":
        return march_pinning(sc, end, sc.alpha_d)
    if sc.control == "displacement":
        return ns_delamination_state(sc, sc.a_max, end.big_l_m)
    last = march_pinning(sc, end, math.pi, w_stop=sc.w)
    t0 = math.sqrt(1.0 + last["c2"] / sc.a_max ** 2)
    return ns_delamination_state(sc, sc.a_max, end.big_l_m, t0=t0, p0=last["p"])


def march_delamination(sc: Scene, end: LoadingEnd, on: dict, a: float) -> dict:
    """Delamination state at radius ``a`` by continuation from the onset (pressure control)."""
    n = max(1, math.ceil(math.log(on["a"] / a) / math.log(1.25))) if sc.control == "pressure" else 1
    t_prev, p_prev = on.get("t"), on["p"]
    r = on
    for a_k in np.geomspace(on["a"], a, n + 1)[1:]:
        if sc.slip == "frictionless":
            r = fl_delamination_state(sc, float(a_k), p_prev)
        else:
            r = ns_delamination_state(sc, float(a_k), end.big_l_m, t_prev, p_prev)
            t_prev = r["t"]
        p_prev = r["p"]
    return r


def _scene(control, slip, p, d, w, rs, a_max, quad_tol, root_tol) -> Scene:
    _check(control, slip, p, d)
    return Scene(control, slip, None if p is None else float(p), None if d is None else float(d),
                 float(w), float(rs), float(a_max), Tol(float(quad_tol), float(root_tol)))


def _public(row: dict) -> dict:
    return {k: row[k] for k in ("stage",) + COLUMNS}


def state(control: str, slip: str, stage: str, *, p: float | None = None, d: float | None = None,
          w: float, rs: float, a_max: float, a: float | None = None, alpha: float | None = None,
          quad_tol: float = 1e-10, root_tol: float = 1e-12) -> dict:
    """One state of the history at a locator, solved from scratch (no continuation).

    Parameters
    ----------
    control, slip : str
        ``"displacement"``/``"pressure"`` and ``"no-slip"``/``"frictionless"``.
    stage : str
        ``"making_contact"`` or ``"delamination"`` (locator ``a``) or ``"pinning"`` (locator ``alpha``,
        radians).
    p, d, w, rs, a_max : float
        Dimensionless scene (docs/contracts.md A1); p under displacement control, d under pressure control.
    quad_tol, root_tol : float
        quad ``epsabs = epsrel`` and brentq ``xtol`` (``rtol`` floored at 4 eps).

    Returns
    -------
    dict
        ``stage, a, alpha, p, d, delta, f, G`` as floats (delta is NaN where |p| > 1).
    """
    sc = _scene(control, slip, p, d, w, rs, a_max, quad_tol, root_tol)
    if stage == "making_contact":
        return _public(making_state(sc, float(a)))
    end = loading_end(sc)
    if stage == "pinning":
        return _public(march_pinning(sc, end, float(alpha)))
    if stage == "delamination":
        return _public(march_delamination(sc, end, onset_state(sc, end), float(a)))
    raise ValueError(f"stage must be one of {STAGES}, got {stage!r}")


def default_locators(points: int, a_max: float, alpha_on: float, a_on: float) -> dict[str, np.ndarray]:
    """Row locators: a third of the rows per stage; delamination rows geometric towards 1e-3 a_max."""
    n_make = max(points // 3, 2)
    n_pin = max(points // 3, 2)
    n_del = max(points - n_make - n_pin, 2)
    return {"making_contact": np.linspace(0.0, a_max, n_make),
            "pinning": np.linspace(0.0, alpha_on, n_pin),
            "delamination": np.geomspace(a_on, 1e-3 * a_max, n_del)}


def history(control: str, slip: str, *, p: float | None = None, d: float | None = None, w: float,
            rs: float, a_max: float, points: int = 200, quad_tol: float = 1e-10, root_tol: float = 1e-12,
            locators: dict[str, np.ndarray] | None = None) -> dict[str, np.ndarray]:
    """Whole loading/unloading history, point by point with continuation from the previous row.

    Rows: making contact (a from 0 to a_max), pinning (alpha from 0 to the onset angle), delamination
    (a from the onset radius down to 1e-3 a_max).  ``locators`` overrides the row placement (e.g. to
    reproduce an engine frame row for row): a dict stage -> array of a (or alpha for pinning).

    Returns
    -------
    dict of numpy arrays
        ``stage`` (str) and ``a, alpha, p, d, delta, f, G`` (float).
    """
    sc = _scene(control, slip, p, d, w, rs, a_max, quad_tol, root_tol)
    end = loading_end(sc)
    on = onset_state(sc, end)
    loc = locators if locators is not None else default_locators(points, sc.a_max, on["alpha"], on["a"])
    rows = _making_rows(sc, loc["making_contact"]) + _pinning_rows(sc, end, loc["pinning"])
    rows += _delamination_rows(sc, end, on, loc["delamination"])
    out = {"stage": np.array([r["stage"] for r in rows])}
    out.update({k: np.array([r[k] for r in rows], dtype=float) for k in COLUMNS})
    return out


def _making_rows(sc: Scene, a_values: np.ndarray) -> list[dict]:
    rows, p_prev = [], None
    for a in a_values:
        rows.append(making_state(sc, float(a), p_prev))
        p_prev = rows[-1]["p"]
    return rows


def _pinning_rows(sc: Scene, end: LoadingEnd, alphas: np.ndarray) -> list[dict]:
    rows: list[dict] = []
    a_prev, c2_prev, p_prev = sc.a_max, 0.0, end.p_m
    for alpha in alphas:
        if sc.slip == "frictionless":
            r = fl_pinning_state(sc, float(alpha), end.p_m, end.big_l_m, a_prev, p_prev)
        else:
            r = ns_pinning_state(sc, float(alpha), end.p_m, end.big_l_m, c2_prev, p_prev)
            c2_prev = r["c2"]
        a_prev, p_prev = r["a"], r["p"]
        rows.append(r)
    return rows


def _delamination_rows(sc: Scene, end: LoadingEnd, on: dict, a_values: np.ndarray) -> list[dict]:
    rows: list[dict] = []
    t_prev, p_prev = on.get("t"), on["p"]
    for a in a_values:
        if sc.slip == "frictionless":
            r = fl_delamination_state(sc, float(a), p_prev)
        else:
            r = ns_delamination_state(sc, float(a), end.big_l_m, t_prev, p_prev)
            t_prev = r["t"]
        p_prev = r["p"]
        rows.append(r)
    return rows


# --------------------------------------------------------------------------------------------------
# self-check:  python benchmarks/baseline_quad.py
# --------------------------------------------------------------------------------------------------
def _self_check() -> list[tuple[str, float]]:
    """Limits the baseline must meet on the paper's base cases; returns (check, worst error) pairs."""
    cases = [("displacement", dict(p=0.6, rs=0.5)), ("displacement", dict(p=0.6, rs=math.inf)),
             ("pressure", dict(d=0.0, rs=0.5)), ("pressure", dict(d=0.2, rs=math.inf))]
    worst: dict[str, float] = {}

    def note(name: str, err: float) -> None:
        worst[name] = max(worst.get(name, 0.0), abs(err))

    for control, kw in cases:
        for slip in ("no-slip", "frictionless"):
            h = history(control, slip, w=0.2, a_max=0.25, points=60, **kw)
            st = h["stage"]
            mk, pin, dl = (np.flatnonzero(st == s) for s in STAGES)
            note("free inflation: delta = 0 at a = 0 (eq. 15)", h["delta"][0])
            for k in ("a", "p", "d", "f"):
                note("pinning at alpha=0 == making contact at a_max", h[k][pin[0]] - h[k][mk[-1]])
            for k in ("a", "alpha", "p", "d", "f", "G"):
                note("pinning end == delamination start", h[k][dl[0]] - h[k][pin[-1]])
            note("G = w throughout delamination", np.max(np.abs(h["G"][dl] - 0.2)))
            if slip == "frictionless":
                note("frictionless G = tan^2(alpha)/2 (eq. 60)",
                     np.max(np.abs(h["G"][pin] - 0.5 * np.tan(h["alpha"][pin]) ** 2)))
            note("f, delta -> 0 as a -> 0 (a = 1e-3 a_max)", max(abs(h["f"][-1]), abs(h["delta"][-1])))
    return sorted(worst.items())


if __name__ == "__main__":
    for name, err in _self_check():
        print(f"{err:10.2e}  {name}")
