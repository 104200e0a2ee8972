"""One-dimensional root solves of one row: the material condition in the unknown, the making-contact
gap in the pressure, and the making-contact radius for a loading end (delta_max / p_max).

Derivatives by complex steps (``STEP``): exact to rounding. Solves never raise: each returns a status
(``OK`` or a ``FAIL_*`` code) and the caller words the error.
"""
from __future__ import annotations

import math

import numpy as np

from .branches import MC, bracket, material_residual, state
from .jit import jit

__all__ = ["OK", "FAIL_BRACKET", "FAIL_INNER", "FAIL_OUTER", "STEP", "XTOL", "MAXITER",
           "JOINT_MAXITER", "CHORD_RATE", "ACCEPT", "NOISE", "R_MATERIAL", "R_MC_GAP", "R_MC_RADIUS", "bracketed",
           "damped_step", "inner_one", "stop", "gap_from", "mc_gap", "mc_bracketed",
           "mc_pressure_rows"]

OK, FAIL_BRACKET, FAIL_INNER, FAIL_OUTER = 0, 1, 2, 3
#: complex step of the derivatives
STEP = 1e-30
XTOL = 4e-15
MAXITER = 60
#: iterations of a Newton with chord steps (:func:`gap_from`, ``solve._joint_one``)
JOINT_MAXITER = 12
#: a chord step (the last Jacobian reused) is kept up while each step is below this fraction of the
#: step before it; otherwise the next iteration takes a fresh Jacobian
CHORD_RATE = 0.01
#: largest residual (material condition J0 - target, gap d - d_fix; both O(1)) of a state a solve
#: reports converged. At the Case I limit (the clamp tangent vertical) the derivatives are infinite,
#: a Newton step vanishes and a state ~1e-6 off its root looked converged (issue-24 audit: the
#: continuation then walked along the limit and stalled there); a true root's residual is ~1e-13
#: even next to the limit (measured 1.6e-11 for the gap, 8e-13 for J0)
ACCEPT = 1e-8
#: a residual (J0 - target, O(1)) this small that has stopped falling is a root at rounding level
#: (:func:`_newton_free`): next to a fold of the material condition in x its slope is small and the
#: step, rounding / slope, stays above XTOL (issue-24 stress scene 8535: slope 0.013, steps ~3e-14
#: against XTOL 5e-15, 60 iterations, then no root)
NOISE = 1e-13
#: residuals of :func:`bracketed`: the material condition in x, the making-contact gap in kappa,
#: the making-contact gap in the radius a (at fixed kappa)
R_MATERIAL, R_MC_GAP, R_MC_RADIUS = 0, 1, 2


@jit
def _resid(kind, code, z, kappa, loc, c, w, a_m, L_m, d_fix):
    """Residual at complex z: the material condition in x at fixed kappa (``R_MATERIAL``), the gap
    of the making-contact state at radius ``loc`` with pressure z (``R_MC_GAP``), or its gap at
    radius z and pressure ``kappa`` (``R_MC_RADIUS``), less ``d_fix``."""
    if kind == R_MC_GAP:
        return mc_gap(z, loc, c, d_fix)
    if kind == R_MC_RADIUS:  # z is the radius; kappa fixed; d_fix is the gap aimed at
        st = state(MC, 0j, complex(kappa, 0.0), z, c, 0.0, 0.0, True)
        return st[2] - d_fix if st[6] else complex(math.nan, math.nan)
    return material_residual(code, z, complex(kappa, 0.0), complex(loc, 0.0), c, w, a_m, L_m)


@jit
def bracketed(kind, code, kappa, loc, c, w, a_m, L_m, d_fix, x0, lo, hi):
    """Newton with a bracket for one row: (x, status, r_lo, r_hi).

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
    # a residual of hi's sign seen: the bracket holds a sign change, not only the edge of the
    # domain (NaN beyond it), where the bracket also closes, on a point that is no root
    crossed = math.isfinite(rhi)
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
            crossed = True
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
            if not (crossed or exact or abs(r) <= ACCEPT):
                # the residual of the answer itself: at the domain's edge it keeps lo's sign and
                # stays off zero (no root); a steep root's is small or of hi's sign
                rx = _resid(kind, code, complex(x, 0.0), kappa, loc, c, w, a_m, L_m, d_fix).real
                if not (math.isfinite(rx) and (abs(rx) <= ACCEPT or (rx < 0) != neg_at_lo)):
                    return math.nan, FAIL_INNER, rlo, rhi
            return x, OK, rlo, rhi
    return math.nan, FAIL_INNER, rlo, rhi


@jit
def _newton_bracketed(code, kappa, loc, c, w, a_m, L_m, x0, lo, hi):
    """The unknown x of one row by :func:`bracketed`: (x, status, r_lo, r_hi)."""
    return bracketed(R_MATERIAL, code, kappa, loc, c, w, a_m, L_m, 0.0, x0, lo, hi)


@jit
def damped_step(x, last_good, r, dr):
    """One step of Newton without a bracket: (next x, last good x, converged).

    A Newton step from a finite residual and derivative; otherwise halfway back toward the last
    good iterate. Converged on an exact zero or a step below XTOL (1 + |x|).
    """
    if math.isfinite(r) and math.isfinite(dr) and dr != 0:
        step = -r / dr
        return x + step, x, r == 0 or abs(step) <= XTOL * (1.0 + abs(x))
    return 0.5 * (x + last_good), last_good, False


@jit
def _newton_free(code, kappa, loc, c, w, a_m, L_m, x0):
    """Newton without a bracket for one row: (x, status); NaN when it does not converge.

    A step that lands on NaN is halved back toward the last good iterate. An iteration that leaves
    (x, last good) as they were would repeat itself to MAXITER (a start outside the model, NaN
    there: halfway back to itself), so it fails at once (the same answer, 60 evaluations sooner).
    """
    kc, lc = complex(kappa, 0.0), complex(loc, 0.0)
    x = last_good = x0
    r_prev = math.inf
    for _ in range(MAXITER):
        z = material_residual(code, complex(x, STEP), kc, lc, c, w, a_m, L_m)
        xn, gn, done = damped_step(x, last_good, z.real, z.imag / STEP)
        if done:
            # a vanishing step at the Case I limit is not a root (ACCEPT)
            return (xn, OK) if abs(z.real) <= ACCEPT else (math.nan, FAIL_INNER)
        r = abs(z.real)
        if r <= NOISE and r >= 0.5 * r_prev:
            # the residual has stopped falling at rounding level while the step stays above XTOL:
            # a root where the material condition is flat in x (next to a fold of it), known to
            # rounding / slope; this iterate is it
            return x, OK
        if xn == x and gn == last_good:
            return math.nan, FAIL_INNER
        if math.isfinite(r):
            r_prev = r
        x, last_good = xn, gn
    return math.nan, FAIL_INNER


@jit
def inner_one(code, kappa, loc, c, w, a_m, L_m, x0, has_x0):
    """The unknown of one row at fixed kappa: (x, status).

    From a finite start value the row is first solved by unbracketed Newton (the root near a
    continuation predictor); if that fails or leaves the bracket, the row is solved again, bracketed,
    from the middle of its bracket.
    """
    lo, hi = bracket(code, loc, c, w, a_m)
    if has_x0 and math.isfinite(x0):
        x, st = _newton_free(code, kappa, loc, c, w, a_m, L_m, x0)
        if math.isfinite(x) and min(lo, hi) <= x <= max(lo, hi):
            return x, OK
    x, st, _, _ = _newton_bracketed(code, kappa, loc, c, w, a_m, L_m, 0.5 * (lo + hi), lo, hi)
    return x, st


@jit
def stop(fresh, size, prev):
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


@jit
def gap_from(code, loc, c, w, a_m, d_fix, kappa, lo, hi):
    """Pressure control on an explicit branch (making contact, frictionless delamination): kappa for
    the gap from a predictor, Newton with chord steps as in :func:`_joint_one`; (kappa, converged).

    Converged also requires the root inside [lo, hi] (pass -inf, inf for no bracket)."""
    lc = complex(loc, 0.0)
    dr = 0.0
    fresh = True
    prev = math.inf
    for _ in range(JOINT_MAXITER):
        if fresh:
            st = state(code, 0j, complex(kappa, STEP), lc, c, w, a_m, True)
            r, dr = st[2].real - d_fix, st[2].imag / STEP
        else:
            st = state(code, 0.0, kappa, loc, c, w, a_m, True)
            r = st[2].real - d_fix
        if not (st[6] and math.isfinite(r) and math.isfinite(dr)) or dr == 0:
            return math.nan, False
        step = -r / dr
        size = abs(step) / (1.0 + abs(kappa))
        kappa += step
        if r == 0 or stop(fresh, size, prev):
            if abs(r) > ACCEPT:  # a vanishing step at the Case I limit is no root (ACCEPT)
                st = state(code, 0.0, kappa, loc, c, w, a_m, True)
                if not (st[6] and abs(st[2] - d_fix) <= ACCEPT):
                    return math.nan, False
            return kappa, lo <= kappa <= hi
        fresh = not (size <= CHORD_RATE * prev)
        prev = size
    return math.nan, False


@jit
def mc_gap(kc, a, c, d_fix):
    """Gap residual of the making-contact state at complex pressure kc (NaN outside the model)."""
    st = state(MC, 0j, kc, complex(a, 0.0), c, 0.0, 0.0, True)
    return st[2] - d_fix if st[6] else complex(math.nan, math.nan)


@jit
def mc_bracketed(a, c, d_fix, l, h):
    """Making contact, the pressure for the gap d_fix at radius a, by :func:`bracketed` from the middle of [l, h].

    Returns (kappa, status): ``OK``, ``FAIL_BRACKET`` or ``FAIL_INNER``.
    """
    k, st, rl, rh = bracketed(R_MC_GAP, MC, 0.0, a, c, 0.0, 0.0, 0.0, d_fix, 0.5 * (l + h), l, h)
    if st == FAIL_BRACKET and not math.isfinite(rl) and math.isfinite(rh) and rh > 0:
        # near p_cr a contact of radius a can be outside the model (on small, strongly curved
        # substrates): bisect for a pressure in the model with the gap below d_fix, the low end
        lo, hi = l, h
        for _ in range(80):
            m = 0.5 * (lo + hi)
            r = mc_gap(complex(m, 0.0), a, c, d_fix).real
            if not math.isfinite(r):
                lo = m
            elif r > 0:
                hi = m
            else:
                k, st, _, _ = bracketed(R_MC_GAP, MC, 0.0, a, c, 0.0, 0.0, 0.0, d_fix, 0.5 * (m + h), m, h)
                return k, st
    return k, st


@jit
def _mc_from(a, c, d_fix, l, h, k0):
    """One making-contact pressure from a predictor k0 (:func:`gap_from`), accepted when it
    converges inside [l, h], where the root is unique (d grows with kappa); otherwise
    :func:`mc_bracketed`."""
    k, good = gap_from(MC, a, c, 0.0, 0.0, d_fix, k0, min(l, h), max(l, h))
    if good:
        return k, OK
    return mc_bracketed(a, c, d_fix, l, h)


@jit
def extrapolate(s, v, i, fallback):
    """Predictor of v at s[i] from rows i-3..i-1 (quadratic, Lagrange); ``fallback`` for i < 3."""
    if i < 3:
        return fallback
    s0, s1, s2, z = s[i - 3], s[i - 2], s[i - 1], s[i]
    if s0 == s1 or s1 == s2 or s0 == s2:
        return fallback
    return (v[i - 3] * (z - s1) * (z - s2) / ((s0 - s1) * (s0 - s2))
            + v[i - 2] * (z - s0) * (z - s2) / ((s1 - s0) * (s1 - s2))
            + v[i - 1] * (z - s0) * (z - s1) / ((s2 - s0) * (s2 - s1)))


@jit
def mc_pressure_rows(a, c, d_fix, lo, hi):
    """mc_pressure_batch along a history's rows (ascending a): each row from a predictor
    extrapolated from the rows before it (:func:`_mc_from`); the first rows bracketed."""
    n = a.size
    ks = np.empty(n)
    status = np.zeros(n, dtype=np.int64)
    for i in range(n):
        k0 = extrapolate(a, ks, i, ks[i - 1] if i > 0 else math.nan)
        if math.isfinite(k0):
            ks[i], status[i] = _mc_from(a[i], c, d_fix, lo[i], hi[i], k0)
        else:
            ks[i], status[i] = mc_bracketed(a[i], c, d_fix, lo[i], hi[i])
        if status[i] != OK and i > 0 and status[i - 1] == OK and ks[i - 1] > lo[i]:
            # at p_cr a contact of radius a[i] can be outside the model (no residual at the
            # bracket's low end, on coarse grids whose predictor fails); the row before's pressure
            # is a low end with a residual (its gap at a larger radius falls below d_fix)
            ks[i], status[i] = mc_bracketed(a[i], c, d_fix, ks[i - 1], hi[i])
    return ks, status
