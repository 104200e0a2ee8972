"""Compiled (numba) kernels of the forward-model engine: same semantics as the numpy path, per row.

This module is a scalar translation of :mod:`.integrals`, :mod:`.membrane`, the five branch unpack
functions and the solves of :mod:`.branches` / :mod:`.solve`, plus batch entry points that loop over
rows and return arrays. Its only reason to exist is speed: one numpy call costs ~150-300 us of
overhead and ``scipy.special.elliprf`` ~0.5 us per element; here one row costs about a microsecond.
Importing it imports numba (~0.5 s), so only :mod:`.backend` imports it, lazily.

Conventions
-----------
* Scalar kernels are generic: numba compiles them for float64 (plain evaluations) and complex128
  (complex-step derivatives, DESIGN.md B1-B2 and :mod:`.solve`); on the real path a square root of a
  negative number is NaN, exactly as in numpy.
* Branch codes (``MC, PIN_NS, PIN_FR, DEL_NS, DEL_FR``) replace the :class:`~.branches.Branch`
  objects; the context is passed as the four floats ``c, w, a_m, L_m``.
* Solves never raise: every row gets a status (``OK`` or one of the ``FAIL_*`` codes) and the Python
  layer raises :class:`~adhfit.errors.ConvergenceError` with the row's inputs.

Everything is dimensionless (DESIGN.md A1).
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

__all__ = ["MC", "PIN_NS", "PIN_FR", "DEL_NS", "DEL_FR", "OK", "FAIL_BRACKET", "FAIL_INNER",
           "FAIL_OUTER", "carlson_rf", "carlson_rd", "evaluate_batch", "solve_batch",
           "derivative_batch", "first_bad", "solve_observe_batch", "follow_kernel", "extremum_kernel",
           "F_OK", "F_STALLED", "F_STEPS", "E_OK", "E_SEARCH", "E_SOLVE", "E_NOCONV", "KEY_CODES"]

MC, PIN_NS, PIN_FR, DEL_NS, DEL_FR = 0, 1, 2, 3, 4
OK, FAIL_BRACKET, FAIL_INNER, FAIL_OUTER = 0, 1, 2, 3

#: complex step, as in :data:`.solve.STEP`
STEP = 1e-30
XTOL = 4e-15
MAXITER = 60
#: iterations of the joint (x, kappa) Newton before the nested solve takes over (as in branches)
JOINT_MAXITER = 12
#: a chord step (the last Jacobian reused) is kept up while each step is below this fraction of the
#: step before it; otherwise the next iteration takes a fresh Jacobian
CHORD_RATE = 0.01
#: relative step of the forward differences of the joint Newton's Jacobian, sqrt(machine epsilon)
FD_STEP = 1.4901161193847656e-08
#: relative truncation error aimed at in the Carlson series (both are 7th-degree, DLMF 19.36.1-2)
_RERR = 1e-16
_RF_FACTOR = 1.0 / (3.0 * _RERR) ** 0.125
_RD_FACTOR = 1.0 / (0.25 * _RERR) ** 0.125

# error_model="numpy": division by zero gives inf/NaN as in numpy instead of raising
_jit = njit(cache=True, nogil=True, error_model="numpy")


# ----------------------------------------------------------------------------------------------
# Carlson symmetric integrals (Carlson 1995, DLMF 19.36), real or complex


@_jit
def _ph_good(z):
    """Argument in the cut plane (not on the negative real axis, not NaN), as scipy checks it."""
    zr, zi = z.real, z.imag
    if zr != zr or zi != zi:
        return False
    if zi == 0.0:
        return zr >= 0.0
    return abs(zr) < math.inf


@_jit
def carlson_rf(x, y, z):
    """R_F(x, y, z) by duplication (DLMF 19.36.1, 7th-degree series); NaN outside the cut plane."""
    if not (_ph_good(x) and _ph_good(y) and _ph_good(z)):
        return (x + y + z) * math.nan
    if (x == 0.0) + (y == 0.0) + (z == 0.0) >= 2:
        return (x + y + z) * math.inf
    A0 = (x + y + z) / 3.0
    dx, dy = A0 - x, A0 - y
    Q = max(abs(dx), abs(dy), abs(A0 - z)) * _RF_FACTOR
    xm, ym, zm, Am = x, y, z, A0
    f = 1.0
    for _ in range(100):
        if abs(Am) > Q * f:
            break
        sx, sy, sz = np.sqrt(xm), np.sqrt(ym), np.sqrt(zm)
        lam = sx * (sy + sz) + sy * sz
        xm, ym, zm, Am = 0.25 * (xm + lam), 0.25 * (ym + lam), 0.25 * (zm + lam), 0.25 * (Am + lam)
        f *= 0.25
    X = f * dx / Am
    Y = f * dy / Am
    Z = -(X + Y)
    E2 = X * Y - Z * Z
    E3 = X * Y * Z
    s = (1.0 - E2 / 10.0 + E3 / 14.0 + E2 * E2 / 24.0 - 3.0 * E2 * E3 / 44.0
         - 5.0 * E2 * E2 * E2 / 208.0 + 3.0 * E3 * E3 / 104.0 + E2 * E2 * E3 / 16.0)
    return s / np.sqrt(Am)


@_jit
def carlson_rd(x, y, z):
    """R_D(x, y, z) by duplication (DLMF 19.36.2, 7th-degree series); NaN outside the cut plane."""
    if not (_ph_good(x) and _ph_good(y) and _ph_good(z)):
        return (x + y + z) * math.nan
    if z == 0.0 or (x == 0.0 and y == 0.0):
        return (x + y + z) * math.inf
    A0 = (x + y + 3.0 * z) / 5.0
    dx, dy = A0 - x, A0 - y
    Q = max(abs(dx), abs(dy), abs(A0 - z)) * _RD_FACTOR
    xm, ym, zm, Am = x, y, z, A0
    f = 1.0
    acc = 0.0 * A0
    for _ in range(100):
        if abs(Am) > Q * f:
            break
        sx, sy, sz = np.sqrt(xm), np.sqrt(ym), np.sqrt(zm)
        lam = sx * (sy + sz) + sy * sz
        acc += f / (sz * (zm + lam))
        xm, ym, zm, Am = 0.25 * (xm + lam), 0.25 * (ym + lam), 0.25 * (zm + lam), 0.25 * (Am + lam)
        f *= 0.25
    X = f * dx / Am
    Y = f * dy / Am
    Z = -(X + Y) / 3.0
    XY, Z2 = X * Y, Z * Z
    E2 = XY - 6.0 * Z2
    E3 = (3.0 * XY - 8.0 * Z2) * Z
    E4 = 3.0 * (XY - Z2) * Z2
    E5 = XY * Z2 * Z
    s = (1.0 - 3.0 * E2 / 14.0 + E3 / 6.0 + 9.0 * E2 * E2 / 88.0 - 3.0 * E4 / 22.0
         - 9.0 * E2 * E3 / 52.0 + 3.0 * E5 / 26.0 - E2 * E2 * E2 / 16.0 + 3.0 * E3 * E3 / 40.0
         + 3.0 * E2 * E4 / 20.0 + 45.0 * E2 * E2 * E3 / 272.0 - 9.0 * (E3 * E4 + E2 * E5) / 68.0)
    return f * s / (Am * np.sqrt(Am)) + 3.0 * acc


# ----------------------------------------------------------------------------------------------
# free membrane (integrals.py, membrane.py)


@_jit
def _roots(kappa, D, C2):
    """q and u_minus of Q(u) = (q - kappa^2 u)(u - u_minus) (integrals.quadratic_roots)."""
    B = 1.0 - 2.0 * kappa * D
    C = C2 - D * D
    sq = np.sqrt(1.0 - 4.0 * kappa * D + 4.0 * kappa * kappa * C2)
    if B.real >= 0.0:
        q = 0.5 * (B + sq)
    else:
        q = 2.0 * kappa * kappa * C / (sq - B)
    return q, -C / q


@_jit
def _pair(C, x1, x2, x3, y1, y2, y3, span, need_j1):
    """J0 and the u-moment from the factor values at the two limits (integrals._carlson_pair)."""
    X1, X2, X3 = np.sqrt(x1), np.sqrt(x2), np.sqrt(x3)
    Y1, Y2, Y3 = np.sqrt(y1), np.sqrt(y2), np.sqrt(y3)
    U12 = (X1 * X2 * Y3 + Y1 * Y2 * X3) / span
    U13 = (X1 * X3 * Y2 + Y1 * Y3 * X2) / span
    U23 = (X2 * X3 * Y1 + Y2 * Y3 * X1) / span
    s12, s13, s23 = U12 * U12, U13 * U13, U23 * U23
    j0 = carlson_rf(s12, s13, s23)
    if not need_j1:
        return j0, 0.0 * j0
    return j0, C / 3.0 * carlson_rd(s13, s23, s12) + X3 * Y3 / U12


@_jit
def _integrals(kappa, D, C2, a, q_edge, through, need_j1):
    """J0, J1 from the edge to the clamp (integrals.free_membrane_integrals), one state."""
    q, um = _roots(kappa, D, C2)
    k2 = kappa * kappa
    C = C2 - D * D
    ea = a * a
    L1e = q - k2 * ea
    L2e = ea - um
    if abs(L1e) < abs(L2e):
        L1e = q_edge / L2e
    else:
        L2e = q_edge / L1e
    one = 1.0 + 0.0 * ea
    if not through:
        j0, ju = _pair(C, q - k2, 1.0 - um, one, L1e, L2e, ea, 1.0 - ea, need_j1)
    else:
        zero = 0.0 * ea
        j0a, jua = _pair(C, L1e, L2e, ea, q - k2 * um, zero, um, L2e, need_j1)
        j0b, jub = _pair(C, q - k2, 1.0 - um, one, q - k2 * um, zero, um, 1.0 - um, need_j1)
        j0, ju = j0a + j0b, jua + jub
    return j0, kappa * ju + D * j0, q, um


@_jit
def _substrate_cos(a, c):
    return np.sqrt(1.0 - (a * c) ** 2)


@_jit
def _free_membrane(kappa, D, C2, a, c, cos_ta, need_j1):
    """J0, d and admissibility of one state (membrane.free_membrane, integrals.admissible)."""
    q_edge = (a * a + C2) * cos_ta * cos_ta
    through = cos_ta.real < 0.0
    j0, j1, q, um = _integrals(kappa, D, C2, a, q_edge, through, need_j1)
    ok = (q - kappa * kappa).real >= 0.0 and q_edge.real >= 0.0
    if through:
        ok = ok and um.real >= 0.0
    sag = a * a * c / (1.0 + _substrate_cos(a, c))
    return j0, j1 - sag, ok


# ----------------------------------------------------------------------------------------------
# branches (branches.py, making_contact.py, pinning.py, delamination.py)


@_jit
def _noslip_constants(kappa, a, c, alpha, t):
    s, ac = _substrate_cos(a, c), a * c
    sin_ta = s * np.sin(alpha) - ac * np.cos(alpha)
    return sin_ta * a * t - kappa * a * a, a * a * (t * t - 1.0)


@_jit
def _frictionless_constants(kappa, a, c, alpha):
    ta = np.tan(alpha)
    return a * _substrate_cos(a, c) * ta - (kappa + c) * a * a, (a * ta) ** 2


@_jit
def _unpack(code, x, kappa, loc, c, w, a_m):
    """(a, alpha, D, C2, G) of one state on branch ``code`` (the branches._mc ... _del_fr)."""
    # all three share one dtype (the batch functions see to it), so every branch returns one type
    zero = 0.0 * loc
    if code == MC:
        D = -(kappa + c) * loc * loc
        return loc + zero, zero, D + zero, zero, zero
    if code == PIN_NS:
        # located by G (0 -> w): alpha from eq. (52) solved for alpha, as in delamination
        a = a_m + zero
        alpha = np.arccos(1.0 - (loc - 0.5 * (x - 1.0) ** 2) / x)
        D, C2 = _noslip_constants(kappa, a, c, alpha, x)
        return a, alpha + zero, D + zero, C2 + zero, loc + zero
    if code == PIN_FR:
        D, C2 = _frictionless_constants(kappa, x, c, loc)
        ta = np.tan(loc)
        return x + zero, loc + zero, D + zero, C2 + zero, 0.5 * ta * ta + zero
    if code == DEL_NS:
        alpha = np.arccos(1.0 - (w - 0.5 * (x - 1.0) ** 2) / x)
        D, C2 = _noslip_constants(kappa, loc, c, alpha, x)
        return loc + zero, alpha + zero, D + zero, C2 + zero, w + zero
    alpha = math.atan(math.sqrt(2.0 * w))
    D, C2 = _frictionless_constants(kappa, loc, c, alpha)
    return loc + zero, alpha + zero, D + zero, C2 + zero, w + zero


@_jit
def _state(code, x, kappa, loc, c, w, a_m, need_j1):
    """branches.evaluate for one state: (a, alpha, d, f, G, J0, ok); p is kappa."""
    a, alpha, D, C2, G = _unpack(code, x, kappa, loc, c, w, a_m)
    s, ac = _substrate_cos(a, c), a * c
    cos_ta = s * np.cos(alpha) + ac * np.sin(alpha)
    j0, d, ok = _free_membrane(kappa, D, C2, a, c, cos_ta, need_j1)
    return a, alpha, d, -np.pi * D, G, j0, ok


@_jit
def _target(code, loc, c, a_m, L_m):
    """The J0 an implicit branch's state must have (eq. 57 / eq. 61)."""
    if code == DEL_NS:
        return (L_m + np.log(a_m / loc)
                + np.log((1.0 + _substrate_cos(loc, c)) / (1.0 + _substrate_cos(a_m, c))))
    return L_m + 0.0 * loc


@_jit
def _residual(code, x, kappa, loc, c, w, a_m, L_m):
    """Material condition J0 - target (branches._residual); J1 is not needed."""
    st = _state(code, x, kappa, loc, c, w, a_m, False)
    if not st[6]:  # outside the model: NaN even under complex evaluation, where sqrt stays finite
        return complex(math.nan, math.nan)
    return st[5] - _target(code, loc, c, a_m, L_m)


@_jit
def _bracket(code, loc, c, w, a_m):
    """(lo, hi) of the unknown (pinning.noslip_stretch_bracket, branches._a_limit, ...)."""
    if code == PIN_FR:
        lim = min(1.0, 1.0 / c) if c > 0 else 1.0
        return 1e-9 * a_m, (1.0 - 1e-9) * lim
    # t where eq. (62) has a real angle, for G = loc (no-slip pinning) or G = w (delamination)
    s = math.sqrt(2.0 * (loc if code == PIN_NS else w))
    return max(1.0 - s, s - 1.0, 0.0) + 1e-12, 1.0 + s - 1e-12


@_jit
def _implicit(code):
    return code == PIN_NS or code == PIN_FR or code == DEL_NS


# ----------------------------------------------------------------------------------------------
# solves (solve.newton, branches.solve_unknown / solve_state / derivative), one row at a time


#: residuals of :func:`_bracketed`: the material condition in x, the making-contact gap in kappa
R_MATERIAL, R_MC_GAP = 0, 1


@_jit
def _resid(kind, code, z, kappa, loc, c, w, a_m, L_m, d_fix):
    """Residual at complex z: the material condition in x at fixed kappa (``R_MATERIAL``), or the
    gap of the making-contact state at radius ``loc`` with pressure z (``R_MC_GAP``)."""
    if kind == R_MC_GAP:
        return _mc_gap(z, loc, c, d_fix)
    return _residual(code, z, complex(kappa, 0.0), complex(loc, 0.0), c, w, a_m, L_m)


@_jit
def _bracketed(kind, code, kappa, loc, c, w, a_m, L_m, d_fix, x0, lo, hi):
    """solve.newton with a bracket for one row: (x, status, r_lo, r_hi).

    Same rules: complex-step derivative, the bracket's residuals must differ in sign (checked), a
    Newton step that leaves the bracket (or a NaN step) is replaced by bisection, an exact zero
    residual is kept, converged when the step or the bracket is below xtol (1 + |x|).
    """
    rlo = _resid(kind, code, complex(lo, STEP), kappa, loc, c, w, a_m, L_m, d_fix).real
    rhi = _resid(kind, code, complex(hi, STEP), kappa, loc, c, w, a_m, L_m, d_fix).real
    # NaN at hi counts as the other side (the domain ends inside the bracket)
    if not math.isfinite(rlo) or np.sign(rlo) * np.sign(rhi) > 0:
        return math.nan, FAIL_BRACKET, rlo, rhi
    neg_at_lo = rlo < 0
    x = x0
    if x < min(lo, hi):
        x = min(lo, hi)
    if x > max(lo, hi):
        x = max(lo, hi)
    for _ in range(MAXITER):
        z = _resid(kind, code, complex(x, STEP), kappa, loc, c, w, a_m, L_m, d_fix)
        r, dr = z.real, z.imag / STEP
        finite = math.isfinite(r) and math.isfinite(dr)
        below = finite and ((r < 0) if neg_at_lo else (r > 0))
        if below:
            lo = x
        elif finite:
            hi = x
        xn = x + (-r / dr) if (finite and dr != 0) else math.nan
        inside = math.isfinite(xn) and min(lo, hi) <= xn <= max(lo, hi)
        exact = finite and r == 0
        if exact:
            xn = x
        elif not inside:
            xn = 0.5 * (lo + hi)
        tol = XTOL * (1.0 + abs(x))
        done = exact or (inside and abs(xn - x) <= tol) or abs(hi - lo) <= tol
        x = xn
        if done:
            if not finite:  # the bracket closed on a point outside the domain: no root
                return math.nan, FAIL_INNER, rlo, rhi
            return x, OK, rlo, rhi
    return math.nan, FAIL_INNER, rlo, rhi


@_jit
def _newton_bracketed(code, kappa, loc, c, w, a_m, L_m, x0, lo, hi):
    """The unknown x of one row by :func:`_bracketed`: (x, status, r_lo, r_hi)."""
    return _bracketed(R_MATERIAL, code, kappa, loc, c, w, a_m, L_m, 0.0, x0, lo, hi)


@_jit
def _damped_step(x, last_good, r, dr):
    """One step of solve.newton without a bracket: (next x, last good x, converged).

    A Newton step from a finite residual and derivative; otherwise halfway back toward the last
    good iterate. Converged on an exact zero or a step below XTOL (1 + |x|).
    """
    if math.isfinite(r) and math.isfinite(dr) and dr != 0:
        step = -r / dr
        return x + step, x, r == 0 or abs(step) <= XTOL * (1.0 + abs(x))
    return 0.5 * (x + last_good), last_good, False


@_jit
def _newton_free(code, kappa, loc, c, w, a_m, L_m, x0):
    """solve.newton without a bracket for one row: (x, status); NaN when it does not converge.

    A step that lands on NaN is halved back toward the last good iterate.
    """
    kc, lc = complex(kappa, 0.0), complex(loc, 0.0)
    x = last_good = x0
    for _ in range(MAXITER):
        z = _residual(code, complex(x, STEP), kc, lc, c, w, a_m, L_m)
        x, last_good, done = _damped_step(x, last_good, z.real, z.imag / STEP)
        if done:
            return x, OK
    return math.nan, FAIL_INNER


@_jit
def _inner_one(code, kappa, loc, c, w, a_m, L_m, x0, has_x0):
    """branches.solve_unknown for one row: (x, status).

    From a finite start value the row is first solved by unbracketed Newton (the root near a
    continuation predictor); if that fails or leaves the bracket, the row is solved again, bracketed,
    from the middle of its bracket.
    """
    lo, hi = _bracket(code, loc, c, w, a_m)
    if has_x0 and math.isfinite(x0):
        x, st = _newton_free(code, kappa, loc, c, w, a_m, L_m, x0)
        if math.isfinite(x) and min(lo, hi) <= x <= max(lo, hi):
            return x, OK
    x, st, _, _ = _newton_bracketed(code, kappa, loc, c, w, a_m, L_m, 0.5 * (lo + hi), lo, hi)
    return x, st


@_jit
def _inner_rows(code, kappa, loc, c, w, a_m, L_m, x0, has_x0, xs, status):
    """branches.solve_unknown over all rows, into ``xs`` and ``status`` (NaN and a code on failure).

    Rows are independent (:func:`_inner_one` each).
    """
    for i in range(loc.size):
        xs[i], status[i] = _inner_one(code, kappa[i], loc[i], c, w, a_m, L_m, x0[i], has_x0)


@_jit
def _propagate(code, x, kappa, kc, lc, c, w, a_m, L_m):
    """branches._propagate: one complex Newton step from the real root carries dx/d(kappa, loc)."""
    r_x = _residual(code, complex(x, STEP), complex(kappa, 0.0), complex(lc.real, 0.0),
                    c, w, a_m, L_m).imag / STEP
    return x - _residual(code, complex(x, 0.0), kc, lc, c, w, a_m, L_m) / r_x


@_jit
def _stop(fresh, size, prev):
    """Converged after a step of relative ``size`` (``prev``: the step before it, inf if none).

    The error left is estimated from the observed convergence: a Newton step (fresh Jacobian)
    leaves ~M size^2 with M ~ size / prev^2, a chord step ~(size / prev) size; it must be below
    XTOL. A first step has no estimate and must itself be below XTOL. (A fixed threshold on the
    step is not safe: next to a fold of the branch M is large.)
    """
    if not math.isfinite(prev):
        return size <= XTOL
    r = min(1.0, size / prev)
    return size * (r * r if fresh else r) <= XTOL


@_jit
def _jacobian(code, x, kappa, loc, c, w, a_m, s0, fd):
    """d(J0, d)/d(x, kappa) at a real state ``s0`` (its ``_state``): (Rx, Gx, Rk, Gk).

    Forward differences with steps FD_STEP (1 + |x|) and FD_STEP (1 + |kappa|): two real
    evaluations, good to ~1e-8 relative, which only sets how fast the joint Newton converges (its
    residuals are exact). Two complex steps (exact) where a perturbed state is outside the model,
    or when ``fd`` is False.
    """
    if fd:
        hx, hk = FD_STEP * (1.0 + abs(x)), FD_STEP * (1.0 + abs(kappa))
        sx = _state(code, x + hx, kappa, loc, c, w, a_m, True)
        sk = _state(code, x, kappa + hk, loc, c, w, a_m, True)
        if sx[6] and sk[6]:
            return ((sx[5] - s0[5]) / hx, (sx[2] - s0[2]) / hx, (sk[5] - s0[5]) / hk,
                    (sk[2] - s0[2]) / hk)
    lc = complex(loc, 0.0)
    s1 = _state(code, complex(x, STEP), complex(kappa, 0.0), lc, c, w, a_m, True)
    s2 = _state(code, complex(x, 0.0), complex(kappa, STEP), lc, c, w, a_m, True)
    return s1[5].imag / STEP, s1[2].imag / STEP, s2[5].imag / STEP, s2[2].imag / STEP


@_jit
def _joint_one(code, loc, c, w, a_m, L_m, d_fix, kappa, x, fd):
    """branches._joint_newton for one row: (x, kappa, converged).

    Newton on the pair (material condition, gap) in (x, kappa) from a predictor. The first
    iteration takes the 2x2 Jacobian (:func:`_jacobian`, by differences if ``fd``); later ones reuse it (chord steps, one real
    evaluation each) while each step is below CHORD_RATE times the one before, and take a fresh
    Jacobian otherwise. It stops when the error left, estimated from the observed rate of
    convergence, is below XTOL (:func:`_stop`; the Newton rule only with the exact Jacobian).
    No safeguard: a non-finite or inadmissible iterate, a singular Jacobian, no convergence in
    JOINT_MAXITER or a root outside x's bracket is a failure.
    """
    tgt = _target(code, complex(loc, 0.0), c, a_m, L_m).real
    Rx = Gx = Rk = Gk = det = 0.0
    fresh = True
    prev = math.inf
    for _ in range(JOINT_MAXITER):
        s0 = _state(code, x, kappa, loc, c, w, a_m, True)
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
        if exact or _stop(fresh and not fd, size, prev):
            lo, hi = _bracket(code, loc, c, w, a_m)
            return x, kappa, min(lo, hi) <= x <= max(lo, hi)
        fresh = not (size <= CHORD_RATE * prev)
        prev = size
    return math.nan, math.nan, False


@_jit
def _gap_from(code, loc, c, w, a_m, d_fix, kappa, lo, hi):
    """Pressure control on an explicit branch (making contact, frictionless delamination): kappa for
    the gap from a predictor, Newton with chord steps as in :func:`_joint_one`; (kappa, converged).

    Converged also requires the root inside [lo, hi] (pass -inf, inf for no bracket)."""
    lc = complex(loc, 0.0)
    dr = 0.0
    fresh = True
    prev = math.inf
    for _ in range(JOINT_MAXITER):
        if fresh:
            st = _state(code, 0j, complex(kappa, STEP), lc, c, w, a_m, True)
            r, dr = st[2].real - d_fix, st[2].imag / STEP
        else:
            st = _state(code, 0.0, kappa, loc, c, w, a_m, True)
            r = st[2].real - d_fix
        if not (st[6] and math.isfinite(r) and math.isfinite(dr)) or dr == 0:
            return math.nan, False
        step = -r / dr
        size = abs(step) / (1.0 + abs(kappa))
        kappa += step
        if r == 0 or _stop(fresh, size, prev):
            return kappa, lo <= kappa <= hi
        fresh = not (size <= CHORD_RATE * prev)
        prev = size
    return math.nan, False


@_jit
def _pressure_one(code, loc, c, w, a_m, L_m, d_fix, kappa, x0, has_x0):
    """branches.solve_state under pressure control for one row: (x, kappa, status).

    An implicit row with a finite predictor x0 is first solved by :func:`_joint_one` (Jacobian by
    differences, then exact), an explicit
    row by :func:`_gap_from`. Otherwise (or when that fails): unbracketed Newton on kappa for the
    gap; each iterate re-solves the unknown (from the last finite inner solution) and carries its
    derivative through that solve by :func:`_propagate`; an iterate without inner solution gives
    NaN and the Newton step backs off toward the last good kappa.
    """
    implicit = _implicit(code)
    if implicit and has_x0 and math.isfinite(x0) and math.isfinite(kappa):
        # differences first; next to a fold (det -> 0) their ~1e-8 error can stall the iteration,
        # and the exact Jacobian is tried before the nested solve
        for fd in (True, False):
            xj, kj, good = _joint_one(code, loc, c, w, a_m, L_m, d_fix, kappa, x0, fd)
            if good:
                return xj, kj, OK
    if not implicit and math.isfinite(kappa):
        kj, good = _gap_from(code, loc, c, w, a_m, d_fix, kappa, -math.inf, math.inf)
        if good:
            return 0.0, kj, OK
    memo, has_memo = x0, has_x0 and math.isfinite(x0)
    last_good = kappa
    lc = complex(loc, 0.0)
    converged = False
    xi = math.nan
    for _ in range(MAXITER):
        if implicit:
            xi, _st = _inner_one(code, kappa, loc, c, w, a_m, L_m, memo, has_memo)
            if math.isfinite(xi):
                memo, has_memo = xi, True
        kc = complex(kappa, STEP)
        xc = _propagate(code, xi, kappa, kc, lc, c, w, a_m, L_m) if implicit else 0j
        sg = _state(code, xc, kc, lc, c, w, a_m, True)
        g = sg[2] - d_fix if sg[6] else complex(math.nan, math.nan)
        kappa, last_good, converged = _damped_step(kappa, last_good, g.real, g.imag / STEP)
        if converged:
            break
    if not converged:
        return math.nan, kappa, FAIL_OUTER
    if not implicit:
        return 0.0, kappa, OK
    x, st = _inner_one(code, kappa, loc, c, w, a_m, L_m, memo, has_memo)
    return x, kappa, st


@_jit
def _solve_pressure(code, loc, c, w, a_m, L_m, d_fix, kappa, x0, has_x0, xs, status):
    """branches.solve_state under pressure control, row by row (:func:`_pressure_one`).

    ``kappa`` holds the start values and is overwritten.
    """
    for i in range(loc.size):
        xs[i], kappa[i], status[i] = _pressure_one(code, loc[i], c, w, a_m, L_m, d_fix, kappa[i],
                                                   x0[i], has_x0)


@_jit
def solve_batch(code, pressure, loc, kappa, x0, has_x0, c, w, a_m, L_m, d_fix):
    """branches.solve_state over the rows.

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
    elif _implicit(code):
        _inner_rows(code, kappa, loc, c, w, a_m, L_m, x0, has_x0, xs, status)
    return xs, ks, status


@_jit
def evaluate_batch(code, x, kappa, loc, c, w, a_m):
    """branches.evaluate row by row; x, kappa, loc share one dtype (float64 or complex128).

    Returns
    -------
    out : ndarray, shape (7, n), dtype of the inputs
        Rows ``a, alpha, p, d, f, G, J0``.
    ok : ndarray of bool
    """
    n = loc.size
    out = np.empty((7, n), dtype=loc.dtype)
    ok = np.empty(n, dtype=np.bool_)
    for i in range(n):
        st = _state(code, x[i], kappa[i], loc[i], c, w, a_m, True)
        a, alpha, d, f, G, j0, good = st
        out[0, i], out[1, i], out[2, i], out[3, i] = a, alpha, kappa[i] + 0.0 * f, d
        out[4, i], out[5, i], out[6, i] = f, G, j0
        ok[i] = good
    return out, ok


@_jit
def _derivative_row(code, pressure, loc, x, kappa, c, w, a_m, L_m):
    """The complex state whose imaginary parts over STEP are d(observable)/d(locator)."""
    implicit = _implicit(code)
    lr, lc = complex(loc, 0.0), complex(loc, STEP)
    kr = complex(kappa, 0.0)
    if not pressure:
        xc = _propagate(code, x, kappa, kr, lc, c, w, a_m, L_m) if implicit else 0j
        return xc, kr
    if not implicit:
        gk = _state(code, 0j, complex(kappa, STEP), lr, c, w, a_m, True)[2].imag / STEP
        gl = _state(code, 0j, kr, lc, c, w, a_m, True)[2].imag / STEP
        return 0j, complex(kappa, -(STEP * gl / gk))
    t_r = _target(code, lr, c, a_m, L_m)
    t_l = _target(code, lc, c, a_m, L_m)
    s = _state(code, complex(x, STEP), kr, lr, c, w, a_m, True)
    Rx, Gx = (s[5] - t_r).imag / STEP, s[2].imag / STEP
    s = _state(code, complex(x, 0.0), complex(kappa, STEP), lr, c, w, a_m, True)
    Rk, Gk = (s[5] - t_r).imag / STEP, s[2].imag / STEP
    s = _state(code, complex(x, 0.0), kr, lc, c, w, a_m, True)
    Rl, Gl = (s[5] - t_l).imag / STEP, s[2].imag / STEP
    det = Rx * Gk - Rk * Gx
    dx = -(Rl * Gk - Rk * Gl) / det
    dk = -(Rx * Gl - Rl * Gx) / det
    return complex(x, STEP * dx), complex(kappa, STEP * dk)


@_jit
def derivative_batch(code, pressure, loc, x, kappa, c, w, a_m, L_m):
    """branches.derivative row by row: shape (7, n), rows d(a, alpha, p, d, f, G, J0)/d(locator)."""
    n = loc.size
    out = np.empty((7, n))
    for i in range(n):
        xc, kc = _derivative_row(code, pressure, loc[i], x[i], kappa[i], c, w, a_m, L_m)
        lc = complex(loc[i], STEP)
        a, alpha, d, f, G, j0, _ = _state(code, xc, kc, lc, c, w, a_m, True)
        out[0, i], out[1, i], out[2, i] = a.imag / STEP, alpha.imag / STEP, kc.imag / STEP
        out[3, i], out[4, i], out[5, i], out[6, i] = (d.imag / STEP, f.imag / STEP, G.imag / STEP,
                                                      j0.imag / STEP)
    return out


@_jit
def first_bad(ok, a, alpha, p, d, f, G):
    """Index of the first state outside the model or with a non-finite observable; -1 if none."""
    for i in range(ok.size):
        if not (ok[i] and math.isfinite(a[i]) and math.isfinite(alpha[i]) and math.isfinite(p[i])
                and math.isfinite(d[i]) and math.isfinite(f[i]) and math.isfinite(G[i])):
            return i
    return -1


# ----------------------------------------------------------------------------------------------
# continuation and extremum refinement (continuation.py) in one call each. They live in this file
# because numba's cache is keyed on the defining file only: kernels in another module would keep
# stale copies of the functions here after they change.

F_OK, F_STALLED, F_STEPS = 0, 1, 2
#: continuation.GAP_CLOSE
GAP_CLOSE = 1e-12
E_OK, E_SOLVE, E_SEARCH, E_NOCONV = 0, 1, 2, 3
#: rows of an observation vector (as in compiled.evaluate_batch)
KEY_CODES = {"a": 0, "alpha": 1, "p": 2, "d": 3, "f": 4, "G": 5, "J0": 6}


@_jit
def _solve_one(code, pressure, loc, k, xg, c, w, a_m, L_m, d_fix):
    """One state at ``loc``: (x, kappa, status); kappa fixed at ``k`` or solved from the gap from ``k``.

    The one-row case of :func:`solve_batch`, without its arrays.
    """
    implicit = _implicit(code)
    if pressure:
        return _pressure_one(code, loc, c, w, a_m, L_m, d_fix, k, xg, implicit)
    if implicit:
        x, st = _inner_one(code, k, loc, c, w, a_m, L_m, xg, True)
        return x, k, st
    return 0.0, k, OK


@_jit
def _observe(code, x, k, loc, c, w, a_m, out):
    """Observables a, alpha, p, d, f, G, J0 of one real state into ``out``; returns ``ok``."""
    a, alpha, d, f, G, j0, ok = _state(code, x, k, loc, c, w, a_m, True)
    out[0], out[1], out[2], out[3], out[4], out[5], out[6] = a, alpha, k, d, f, G, j0
    return ok


@_jit
def _admissible(ok, out):
    """ok and a, alpha, p, d, f, G finite (continuation.extremum's test)."""
    if not ok:
        return False
    for j in range(6):
        if not math.isfinite(out[j]):
            return False
    return True


#: step variables of follow_kernel: the locator, its logarithm, its square root
SCALE_LINEAR, SCALE_LOG, SCALE_SQRT = 0, 1, 2


@_jit
def _to_step(scale, loc):
    if scale == SCALE_LOG:
        return math.log(loc)
    if scale == SCALE_SQRT:
        return math.sqrt(loc)
    return loc


@_jit
def _from_step(scale, s):
    if scale == SCALE_LOG:
        return math.exp(s)
    if scale == SCALE_SQRT:
        return s * s
    return s


@_jit
def _predict(ss, xs, ks, m, s):
    """continuation._predict: x, kappa at s extrapolated from the last accepted states (quadratic
    through three, linear through two, else the last one)."""
    if m > 2 and ss[m - 3] != ss[m - 2] and ss[m - 2] != ss[m - 1] and ss[m - 3] != ss[m - 1]:
        s0, s1, s2 = ss[m - 3], ss[m - 2], ss[m - 1]
        l0 = (s - s1) * (s - s2) / ((s0 - s1) * (s0 - s2))
        l1 = (s - s0) * (s - s2) / ((s1 - s0) * (s1 - s2))
        l2 = (s - s0) * (s - s1) / ((s2 - s0) * (s2 - s1))
        return (l0 * xs[m - 3] + l1 * xs[m - 2] + l2 * xs[m - 1],
                l0 * ks[m - 3] + l1 * ks[m - 2] + l2 * ks[m - 1])
    if m > 1 and ss[m - 1] != ss[m - 2]:
        r = (s - ss[m - 1]) / (ss[m - 1] - ss[m - 2])
        return xs[m - 1] + r * (xs[m - 1] - xs[m - 2]), ks[m - 1] + r * (ks[m - 1] - ks[m - 2])
    return xs[m - 1], ks[m - 1]


@_jit
def follow_kernel(code, pressure, l0, targets, x0, k0, c, w, a_m, L_m, d_fix, scale, max_steps,
                  allow_end):
    """continuation.follow in one call.

    ``scale`` is the step variable: ``SCALE_LINEAR`` (the locator), ``SCALE_LOG`` (``log=True``) or
    ``SCALE_SQRT`` (``sqrt=True``).

    Returns
    -------
    status : int
        ``F_OK``, ``F_STALLED`` (the step fell below 1e-10 of the span) or ``F_STEPS``.
    n_out : int
        Targets reached (their x, kappa are ``out_x[:n_out]``, ``out_k[:n_out]``).
    out_x, out_k : ndarray
    path_l, path_x, path_k : ndarray
        Every accepted step (locators, x, kappa); x NaN on explicit branches.
    last : ndarray, shape (7,)
        Observables a, alpha, p, d, f, G, J0 of the last accepted step (NaN if none).
    out_obs : ndarray, shape (7, n_targets)
        The same at the targets reached (``out_obs[:, :n_out]``).
    """
    implicit = _implicit(code)
    n_t = targets.size
    cap = max_steps + 2
    ss, xs, ks = np.empty(cap), np.empty(cap), np.empty(cap)
    out_x, out_k = np.empty(n_t), np.empty(n_t)
    out_obs = np.empty((7, n_t))
    ss[0] = _to_step(scale, l0)
    xs[0] = x0 if implicit else math.nan
    ks[0] = k0
    m = 1
    last = _to_step(scale, targets[n_t - 1])
    span = abs(last - ss[0])
    if span == 0.0:
        span = 1.0
    h = span / 16.0
    i, steps, n_out, status = 0, 0, 0, F_OK
    obs = np.empty(7)
    last_obs = np.full(7, math.nan)
    while i < n_t:
        steps += 1
        if steps > max_steps:
            status = F_STEPS
            break
        goal = _to_step(scale, targets[i])
        gap = goal - ss[m - 1]
        # a gap within rounding of the goal is closed in one step (a step below the spacing of
        # floats would not move)
        near = abs(gap) <= h or abs(gap) <= GAP_CLOSE * (1.0 + abs(goal))
        s_new = goal if near else ss[m - 1] + math.copysign(h, gap)
        xg, kg = _predict(ss, xs, ks, m, s_new)
        loc = _from_step(scale, s_new)
        x, k, st = _solve_one(code, pressure, loc, kg if pressure else k0, xg, c, w, a_m, L_m, d_fix)
        good = st == 0
        if good:
            good = _observe(code, x, k, loc, c, w, a_m, obs) and math.isfinite(obs[4])
        if not good:
            h *= 0.5
            if h < 1e-10 * span:
                if not (allow_end and m > 1):
                    status = F_STALLED
                break
            continue
        ss[m], xs[m], ks[m] = s_new, (x if implicit else math.nan), k
        last_obs[:] = obs
        m += 1
        if s_new == goal:
            out_x[n_out], out_k[n_out] = xs[m - 1], ks[m - 1]
            out_obs[:, n_out] = obs
            n_out += 1
            i += 1
        h = min(1.6 * h, span / 8.0)
    path_l = np.empty(m)
    for j in range(m):
        path_l[j] = _from_step(scale, ss[j])
    return status, n_out, out_x, out_k, path_l, xs[:m].copy(), ks[:m].copy(), last_obs, out_obs


@_jit
def _solve_at(code, pressure, loc, rl, rx, rk, kappa, c, w, a_m, L_m, d_fix):
    """continuation.extremum's solve: predictors interpolated from the rows."""
    kg = np.interp(loc, rl, rk) if pressure else kappa
    xg = np.interp(loc, rl, rx)
    return _solve_one(code, pressure, loc, kg, xg, c, w, a_m, L_m, d_fix)


@_jit
def _slope_of(code, pressure, loc, x, k, c, w, a_m, L_m, key):
    """d(observable ``key``)/d(locator) at a solved state (compiled.derivative_batch, one row)."""
    xc, kc = _derivative_row(code, pressure, loc, x, k, c, w, a_m, L_m)
    if key == 2:
        return kc.imag / STEP
    a, alpha, d, f, G, j0, _ = _state(code, xc, kc, complex(loc, STEP), c, w, a_m, True)
    if key == 0:
        return a.imag / STEP
    if key == 1:
        return alpha.imag / STEP
    if key == 3:
        return d.imag / STEP
    if key == 4:
        return f.imag / STEP
    if key == 5:
        return G.imag / STEP
    return j0.imag / STEP


@_jit
def _slope_at(code, pressure, loc, rl, rx, rk, kappa, c, w, a_m, L_m, d_fix, key):
    x, k, st = _solve_at(code, pressure, loc, rl, rx, rk, kappa, c, w, a_m, L_m, d_fix)
    if st != 0:
        return math.nan, st
    return _slope_of(code, pressure, loc, x, k, c, w, a_m, L_m, key), 0


@_jit
def _value(code, pressure, loc, rl, rx, rk, kappa, c, w, a_m, L_m, d_fix, key, sign, obs):
    """sign * key at the solved state, -inf where it does not solve or is not admissible."""
    x, k, st = _solve_at(code, pressure, loc, rl, rx, rk, kappa, c, w, a_m, L_m, d_fix)
    if st != 0:
        return -math.inf
    ok = _observe(code, x, k, loc, c, w, a_m, obs)
    return sign * obs[key] if _admissible(ok, obs) else -math.inf


@_jit
def _brent(code, pressure, xa, xb, fa, fb, rl, rx, rk, kappa, c, w, a_m, L_m, d_fix, key,
           xtol, rtol, maxiter):
    """scipy.optimize.brentq (scipy/optimize/Zeros/brentq.c) on the slope: (root, status)."""
    xpre, xcur, fpre, fcur = xa, xb, fa, fb
    xblk, fblk, spre, scur = 0.0, 0.0, 0.0, 0.0
    if fpre == 0:
        return xpre, E_OK
    if fcur == 0:
        return xcur, E_OK
    for _ in range(maxiter):
        if fpre != 0 and fcur != 0 and (math.copysign(1.0, fpre) != math.copysign(1.0, fcur)):
            xblk, fblk = xpre, fpre
            spre = scur = xcur - xpre
        if abs(fblk) < abs(fcur):
            xpre, xcur, xblk = xcur, xblk, xcur
            fpre, fcur, fblk = fcur, fblk, fcur
        delta = (xtol + rtol * abs(xcur)) / 2
        sbis = (xblk - xcur) / 2
        if fcur == 0 or abs(sbis) < delta:
            return xcur, E_OK
        if abs(spre) > delta and abs(fcur) < abs(fpre):
            if xpre == xblk:
                stry = -fcur * (xcur - xpre) / (fcur - fpre)   # interpolate
            else:                                              # extrapolate
                dpre = (fpre - fcur) / (xpre - xcur)
                dblk = (fblk - fcur) / (xblk - xcur)
                stry = -fcur * (fblk * dblk - fpre * dpre) / (dblk * dpre * (fblk - fpre))
            if 2 * abs(stry) < min(abs(spre), 3 * abs(sbis) - delta):
                spre, scur = scur, stry                        # good short step
            else:
                spre, scur = sbis, sbis                        # bisect
        else:
            spre, scur = sbis, sbis
        xpre, fpre = xcur, fcur
        if abs(scur) > delta:
            xcur += scur
        else:
            xcur += delta if sbis > 0 else -delta
        fcur, st = _slope_at(code, pressure, xcur, rl, rx, rk, kappa, c, w, a_m, L_m, d_fix, key)
        if st != 0:
            return xcur, E_SEARCH
    return xcur, E_NOCONV


@_jit
def _probe(code, pressure, loc, rl, rx, rk, kappa, c, w, a_m, L_m, d_fix, key, sign, obs):
    """:func:`_value` and :func:`_slope_at` at ``loc`` from one solve: (value, slope); the
    observables go to ``obs``."""
    x, k, st = _solve_at(code, pressure, loc, rl, rx, rk, kappa, c, w, a_m, L_m, d_fix)
    if st != 0:
        return -math.inf, math.nan
    ok = _observe(code, x, k, loc, c, w, a_m, obs)
    v = sign * obs[key] if _admissible(ok, obs) else -math.inf
    return v, _slope_of(code, pressure, loc, x, k, c, w, a_m, L_m, key)


@_jit
def extremum_kernel(code, pressure, lo, hi, rl, rx, rk, kappa, c, w, a_m, L_m, d_fix, key, sign,
                    xtol, rtol, maxiter):
    """continuation.extremum in one call.

    Returns
    -------
    status : int
        ``E_OK``; ``E_SOLVE`` (the state at the chosen locator does not solve), ``E_SEARCH`` (a solve
        inside the root search failed) or ``E_NOCONV`` (the search did not converge).
    loc : float
    obs : ndarray, shape (7,)
        a, alpha, p, d, f, G, J0 at ``loc``.
    ok : bool
    """
    obs = np.empty(7)
    best = lo
    if lo != hi:
        # each candidate is solved once; the best one's observables are kept
        best_obs = np.empty(7)
        v_best, s_lo = _probe(code, pressure, lo, rl, rx, rk, kappa, c, w, a_m, L_m, d_fix, key,
                              sign, best_obs)
        v, s_hi = _probe(code, pressure, hi, rl, rx, rk, kappa, c, w, a_m, L_m, d_fix, key, sign,
                         obs)
        if v > v_best:
            best, v_best = hi, v
            best_obs[:] = obs
        if math.isfinite(s_lo) and math.isfinite(s_hi) and s_lo * s_hi < 0:
            root, st = _brent(code, pressure, lo, hi, s_lo, s_hi, rl, rx, rk, kappa, c, w, a_m, L_m,
                              d_fix, key, xtol, rtol, maxiter)
            if st != E_OK:
                return st, root, obs, False
            v = _value(code, pressure, root, rl, rx, rk, kappa, c, w, a_m, L_m, d_fix, key, sign,
                       obs)
            if v > v_best:
                best, v_best = root, v
                best_obs[:] = obs
        if v_best > -math.inf:  # admissible, so ok
            return E_OK, best, best_obs, True
    x, k, st = _solve_at(code, pressure, best, rl, rx, rk, kappa, c, w, a_m, L_m, d_fix)
    if st != 0:
        return E_SOLVE, best, obs, False
    ok = _observe(code, x, k, best, c, w, a_m, obs)
    return E_OK, best, obs, ok


@_jit
def solve_observe_batch(code, pressure, loc, kappa, x0, has_x0, c, w, a_m, L_m, d_fix):
    """compiled.solve_batch followed by compiled.evaluate_batch at the solved states (one call).

    Returns
    -------
    x, kappa, status : as solve_batch
    out, ok : as evaluate_batch (meaningless where status is not OK)
    bad : int
        First row outside the model or with a non-finite a, alpha, p, d, f, G (compiled.first_bad);
        -1 if none.
    """
    xs, ks, status = solve_batch(code, pressure, loc, kappa, x0, has_x0, c, w, a_m, L_m, d_fix)
    n = loc.size
    out = np.empty((7, n))
    ok = np.zeros(n, dtype=np.bool_)
    implicit = _implicit(code)
    bad = -1
    for i in range(n):
        if status[i] != 0:
            out[:, i] = math.nan
            bad = i if bad < 0 else bad
            continue
        ok[i] = _observe(code, xs[i] if implicit else loc[i], ks[i], loc[i], c, w, a_m, out[:, i])
        if bad < 0 and not _admissible(ok[i], out[:, i]):
            bad = i
    return xs, ks, status, out, ok, bad


@_jit
def _mc_gap(kc, a, c, d_fix):
    """Gap residual of the making-contact state at complex pressure kc (NaN outside the model)."""
    st = _state(MC, 0j, kc, complex(a, 0.0), c, 0.0, 0.0, True)
    return st[2] - d_fix if st[6] else complex(math.nan, math.nan)


@_jit
def _mc_bracketed(a, c, d_fix, l, h):
    """branches.mc_pressure for one row, by :func:`_bracketed` from the middle of [l, h].

    Returns (kappa, status): ``OK``, ``FAIL_BRACKET`` or ``FAIL_INNER``.
    """
    k, st, _, _ = _bracketed(R_MC_GAP, MC, 0.0, a, c, 0.0, 0.0, 0.0, d_fix, 0.5 * (l + h), l, h)
    return k, st


@_jit
def _mc_from(a, c, d_fix, l, h, k0):
    """One making-contact pressure from a predictor k0 (:func:`_gap_from`), accepted when it
    converges inside [l, h], where the root is unique (d grows with kappa); otherwise
    :func:`_mc_bracketed`."""
    k, good = _gap_from(MC, a, c, 0.0, 0.0, d_fix, k0, min(l, h), max(l, h))
    if good:
        return k, OK
    return _mc_bracketed(a, c, d_fix, l, h)


@_jit
def mc_pressure_batch(a, c, d_fix, lo, hi):
    """branches.mc_pressure row by row (:func:`_mc_bracketed`).

    Returns
    -------
    kappa : ndarray
    status : ndarray of int64
        ``OK``, ``FAIL_BRACKET`` or ``FAIL_INNER`` per row.
    """
    n = a.size
    ks = np.empty(n)
    status = np.zeros(n, dtype=np.int64)
    for i in range(n):
        ks[i], status[i] = _mc_bracketed(a[i], c, d_fix, lo[i], hi[i])
    return ks, status


@_jit
def _extrapolate(s, v, i, fallback):
    """Predictor of v at s[i] from rows i-3..i-1 (quadratic, Lagrange); ``fallback`` for i < 3."""
    if i < 3:
        return fallback
    s0, s1, s2, z = s[i - 3], s[i - 2], s[i - 1], s[i]
    if s0 == s1 or s1 == s2 or s0 == s2:
        return fallback
    return (v[i - 3] * (z - s1) * (z - s2) / ((s0 - s1) * (s0 - s2))
            + v[i - 2] * (z - s0) * (z - s2) / ((s1 - s0) * (s1 - s2))
            + v[i - 1] * (z - s0) * (z - s1) / ((s2 - s0) * (s2 - s1)))


@_jit
def _mc_pressure_rows(a, c, d_fix, lo, hi):
    """mc_pressure_batch along a history's rows (ascending a): each row from a predictor
    extrapolated from the rows before it (:func:`_mc_from`); the first rows bracketed."""
    n = a.size
    ks = np.empty(n)
    status = np.zeros(n, dtype=np.int64)
    for i in range(n):
        k0 = _extrapolate(a, ks, i, ks[i - 1] if i > 0 else math.nan)
        if math.isfinite(k0):
            ks[i], status[i] = _mc_from(a[i], c, d_fix, lo[i], hi[i], k0)
        else:
            ks[i], status[i] = _mc_bracketed(a[i], c, d_fix, lo[i], hi[i])
    return ks, status


# ----------------------------------------------------------------------------------------------
# a whole history in one call (loading.history's orchestration, for speed)
#
# loading.py is the readable reference of these steps (and what runs under the numpy backend);
# this kernel repeats them in the same order with the same solver calls, so it gives the same rows.
# It never raises and reports no details: on any failure it returns H_FAIL and the Python layer
# re-runs the reference orchestration, which raises the error with its full message.

H_OK, H_FAIL = 0, 1
#: rows of the summary array returned by history_kernel: onset, f_min, turning point
S_ONSET, S_FMIN, S_TP = 0, 1, 2


@_jit
def _all_good(status, ok, out):
    """Every row solved, admissible and with a finite force (loading._solve_rows' acceptance)."""
    for i in range(ok.size):
        if status[i] != 0 or not ok[i] or not math.isfinite(out[4, i]):
            return False
    return True


@_jit
def _rows_k(code, pressure, locs, kappa_dc, kg, xg, has_xg, c, w, a_m, L_m, d_fix, l0, x0, k0,
            log):
    """loading._solve_rows with a start state: vectorised solve, else follow the branch through the rows.

    Returns (x, kappa, out, good): ``good`` False when the rows have a state outside the model.
    """
    n = locs.size
    kin = kg.copy() if pressure else np.full(n, kappa_dc)
    xs, ks, status, out, ok, bad = solve_observe_batch(code, pressure, locs, kin, xg, has_xg, c, w,
                                                       a_m, L_m, d_fix)
    if _all_good(status, ok, out):
        return xs, ks, out, bad < 0
    st, n_out, ox, okp, _, _, _, _, _ = follow_kernel(code, pressure, l0, locs, x0, k0, c, w, a_m,
                                                   L_m, d_fix, SCALE_LOG if log else SCALE_LINEAR,
                                                   2000, False)
    if st != F_OK or n_out != n:
        return xs, ks, out, False
    xe = ox if _implicit(code) else locs
    out, ok = evaluate_batch(code, xe, okp, locs, c, w, a_m)
    return ox, okp, out, first_bad(ok, out[0], out[1], out[2], out[3], out[4], out[5]) < 0


@_jit
def _extremum_k(code, pressure, locs, xs, implicit, out, i, lo, hi, kappa_dc, c, w, a_m, L_m,
                d_fix, key, sign, xtol, rtol, maxiter):
    """One call of loading._extrema's search on its stage: (locator, observables, good)."""
    n = locs.size
    j0, j1 = max(i - 2, 0), min(i + 3, n)
    order = np.argsort(locs[j0:j1])
    rl = locs[j0:j1][order]
    rx = (xs[j0:j1] if implicit else np.full(j1 - j0, math.nan))[order]
    rk = out[2, j0:j1][order]
    if lo != hi:
        lo, hi = min(lo, hi), max(lo, hi)
    else:
        lo, hi = locs[i], locs[i]
    st, loc, obs, ok = extremum_kernel(code, pressure, lo, hi, rl, rx, rk,
                                       0.0 if pressure else kappa_dc, c, w, a_m, L_m, d_fix, key,
                                       sign, xtol, rtol, maxiter)
    return loc, obs, st == E_OK and _admissible(ok, obs)


@_jit
def _apex(p):
    """inflation.apex_deflection for one pressure (NaN where |p| > 1)."""
    if abs(p) > 1.0:
        return math.nan
    return p / (1.0 + math.sqrt(1.0 - p * p))


@_jit
def history_kernel(pressure, no_slip, kappa_dc, d_fix, p_cr, c, w, a_max, u_mc, u_pin, u_dl,
                   a_end_rel, xtol, rtol, maxiter):
    """loading.history after validation, in one call (see the comment above).

    Returns
    -------
    status : int
        ``H_OK`` or ``H_FAIL``.
    cols : ndarray, shape (7, n)
        ``a, alpha, p, d, f, G, delta`` in history order.
    counts : ndarray of int64, shape (3,)
        Rows of making contact (with the free-inflation row), pinning, delamination.
    tp_pos : int
        Row of the turning point (rows up to it are ``stable``).
    summary : ndarray, shape (3, 6)
        ``a, alpha, p, d, f, G`` at the onset, f_min and the turning point.
    f_max : float
    branch_end : float
        Contact radius where the no-slip delamination branch ends (NaN when it reaches the end).
    """
    fail = (H_FAIL, np.empty((7, 0)), np.zeros(3, dtype=np.int64), 0, np.empty((3, 6)), math.nan,
            math.nan)
    pin_code = PIN_NS if no_slip else PIN_FR
    dl_code = DEL_NS if no_slip else DEL_FR
    dl_implicit = _implicit(dl_code)

    # 1. making contact, a in (0, a_m]
    n_mc = u_mc.size
    a_mc = a_max * u_mc
    if pressure:
        hi = np.empty(n_mc)
        for i in range(n_mc):
            hi[i] = (1.0 + c * a_mc[i] * a_mc[i]) / (1.0 - a_mc[i] * a_mc[i]) * (1 - 1e-12)
        k_mc, st_mc = _mc_pressure_rows(a_mc, c, d_fix, np.full(n_mc, p_cr), hi)
        for i in range(n_mc):
            if st_mc[i] != OK:
                return fail
    else:
        k_mc = np.full(n_mc, kappa_dc)
    out_mc, ok_mc = evaluate_batch(MC, a_mc, k_mc, a_mc, c, w, math.nan)
    if first_bad(ok_mc, out_mc[0], out_mc[1], out_mc[2], out_mc[3], out_mc[4], out_mc[5]) >= 0:
        return fail
    a_m, L_m, kappa_m = a_max, out_mc[6, n_mc - 1], k_mc[n_mc - 1]

    # 2. pinning rows by continuation from its start (G = 0 / alpha = 0) through every row; the last
    # row is the onset (G = w / alpha = atan sqrt(2w))
    end = w if no_slip else math.atan(math.sqrt(2.0 * w))
    n_pin = u_pin.size
    lp = end * (u_pin * u_pin if no_slip else u_pin)
    st, n_out, x_pin, k_pin, _, _, _, _, out_pin = follow_kernel(
        pin_code, pressure, 0.0, lp, 1.0 if no_slip else a_m, kappa_m, c, w, a_m, L_m, d_fix,
        SCALE_SQRT if no_slip else SCALE_LINEAR, 2000, False)
    if st != F_OK or n_out != n_pin:
        return fail
    # every step follow accepts is admissible with a finite force; the rest of first_bad's test:
    for i in range(n_pin):
        if not _admissible(True, out_pin[:, i]):
            return fail
    onset = out_pin[:, n_pin - 1].copy()
    on_x = x_pin[n_pin - 1]
    a_on, k_on = onset[0], onset[2]

    # 3. delamination, a from a_on toward detachment, by continuation through every row
    pull_off = math.sqrt(2.0 * w) / (2.0 * (abs(k_on) + c + 1.0))
    a_end = min(a_end_rel * a_m, 0.1 * pull_off)
    x_start = on_x if no_slip else math.nan
    branch_end = math.nan
    n_dl = u_dl.size
    a_dl = a_end + (a_on - a_end) * u_dl
    if not (pressure or dl_implicit):  # explicit in displacement control when frictionless
        x_dl = a_dl.copy()
        out_dl, ok_dl = evaluate_batch(dl_code, a_dl, np.full(n_dl, kappa_dc), a_dl, c, w, a_m)
        good = first_bad(ok_dl, out_dl[0], out_dl[1], out_dl[2], out_dl[3], out_dl[4],
                         out_dl[5]) < 0
    else:
        st, n_out, x_dl, k_dl, dl_l, dl_x, dl_k, _, out_dl = follow_kernel(
            dl_code, pressure, a_on, a_dl, x_start, k_on, c, w, a_m, L_m, d_fix, SCALE_LOG, 2000,
            no_slip)
        if st != F_OK:
            return fail
        if n_out == n_dl:
            good = True
            for i in range(n_dl):
                good = good and _admissible(True, out_dl[:, i])
        else:
            # the branch ends before a_end: rows up to its end, predictors from the path
            branch_end = a_end = dl_l[dl_l.size - 1]
            a_dl = a_end + (a_on - a_end) * u_dl
            rl, rxp, rkp = dl_l[::-1].copy(), dl_x[::-1].copy(), dl_k[::-1].copy()
            kg = np.interp(a_dl, rl, rkp)
            xg = a_dl.copy()
            if dl_implicit:
                xg = np.interp(a_dl, rl, rxp)
                xg[n_dl - 1] = dl_x[dl_x.size - 1]
            x_dl, k_dl, out_dl, good = _rows_k(dl_code, pressure, a_dl, kappa_dc, kg, xg,
                                               dl_implicit, c, w, a_m, L_m, d_fix, a_on, x_start,
                                               k_on, True)
    if not good:
        return fail

    # 5. extrema: turning point of the control variable, then the force minimum
    summary = np.empty((3, 6))
    summary[S_ONSET, :] = onset[:6]
    ext_stage = np.zeros(2, dtype=np.int64)
    ext_loc = np.empty(2)
    for e in range(2):
        if e == 0:
            key, sign = (2, -1.0) if pressure else (3, 1.0)
        else:
            key, sign = 4, -1.0
        j, best = 0, -math.inf
        for i in range(n_pin):
            v = sign * out_pin[key, i]
            if v > best:
                j, best = i, v
        for i in range(n_dl):
            v = sign * out_dl[key, i]
            if v > best:
                j, best = n_pin + i, v
        if j < n_pin:
            i = j
            lo = lp[i - 1] if i > 0 else 0.0
            hi = lp[i + 1] if i + 1 < n_pin else lp[i]
            loc, obs, good = _extremum_k(pin_code, pressure, lp, x_pin, True, out_pin, i, lo, hi,
                                         kappa_dc, c, w, a_m, L_m, d_fix, key, sign, xtol, rtol,
                                         maxiter)
            ext_stage[e] = 1
        else:
            i = j - n_pin
            lo = a_dl[i - 1] if i > 0 else a_on
            hi = a_dl[i + 1] if i + 1 < n_dl else a_dl[i]
            loc, obs, good = _extremum_k(dl_code, pressure, a_dl, x_dl, dl_implicit, out_dl, i, lo,
                                         hi, kappa_dc, c, w, a_m, L_m, d_fix, key, sign, xtol,
                                         rtol, maxiter)
            ext_stage[e] = 2
        if not good:
            return fail
        if sign * obs[key] < best:  # the row is better (loading._extrema)
            if j < n_pin:
                loc, obs = lp[j], out_pin[:, j].copy()
            else:
                loc, obs = a_dl[j - n_pin], out_dl[:, j - n_pin].copy()
        ext_loc[e] = loc
        summary[S_TP if e == 0 else S_FMIN, :] = obs[:6]
    # each is also held against the other's state (loading._extrema)
    tp, fm = summary[S_TP, :].copy(), summary[S_FMIN, :].copy()
    tp_stage, tp_loc, fm_stage, fm_loc = ext_stage[0], ext_loc[0], ext_stage[1], ext_loc[1]
    k_tp, s_tp = (2, -1.0) if pressure else (3, 1.0)
    if s_tp * fm[k_tp] > s_tp * tp[k_tp]:
        summary[S_TP, :], ext_stage[0], ext_loc[0] = fm, fm_stage, fm_loc
    if -tp[4] > -fm[4]:
        summary[S_FMIN, :], ext_stage[1], ext_loc[1] = tp, tp_stage, tp_loc

    # 6. assemble: free inflation, making contact, pinning, delamination; insert the extrema
    n0 = 1 + n_mc + n_pin + n_dl
    base = np.empty((6, n0 + 2))
    locs = np.empty(n0)
    base[:, 0] = 0.0
    base[2, 0] = p_cr if pressure else kappa_dc
    base[3, 0] = d_fix if pressure else _apex(kappa_dc)
    locs[0] = 0.0
    base[:, 1:1 + n_mc] = out_mc[:6]
    locs[1:1 + n_mc] = a_mc
    base[:, 1 + n_mc:1 + n_mc + n_pin] = out_pin[:6]
    locs[1 + n_mc:1 + n_mc + n_pin] = lp
    base[:, 1 + n_mc + n_pin:n0] = out_dl[:6]
    locs[1 + n_mc + n_pin:] = a_dl
    counts = np.array([1 + n_mc, n_pin, n_dl], dtype=np.int64)
    take = np.arange(n0)
    n_extra = 0
    tp_pos = -1
    for e in (1, 0):  # sorted by name: f_min, then turning_point
        rank, lc = ext_stage[e], ext_loc[e]
        s0 = counts[0] + (counts[1] if rank == 2 else 0)
        m = counts[rank]
        k = m
        for q in range(m):
            lq = locs[s0 + q]
            if (lq <= lc + 1e-15) if rank == 2 else (lq >= lc - 1e-15):
                k = q
                break
        j = s0 + k
        if not (k < m and abs(locs[j] - lc) <= 1e-14):
            base[:, n0 + n_extra] = summary[S_TP if e == 0 else S_FMIN, :]
            take = np.concatenate((take[:j], np.array([n0 + n_extra]), take[j:]))
            locs = np.concatenate((locs[:j], np.array([lc]), locs[j:]))
            counts[rank] += 1
            n_extra += 1
            if tp_pos >= 0 and j <= tp_pos:
                tp_pos += 1
        if e == 0:
            tp_pos = j
    n = take.size
    cols = np.empty((7, n))
    for r in range(n):
        src = take[r]
        for k in range(6):
            cols[k, r] = base[k, src] + 0.0
        if pressure:
            cols[3, r] = d_fix
        cols[6, r] = _apex(cols[2, r]) - cols[3, r]
    return H_OK, cols, counts, tp_pos, summary, out_mc[4, n_mc - 1], branch_end
