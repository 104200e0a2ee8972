"""Vectorised root solves with complex-step derivatives.

Every residual in the engine is an analytic function built from numpy and Carlson integrals, so its
derivative comes exactly from one complex evaluation, r(x + ih) = r(x) + ih r'(x) + O(h^2). One
complex call therefore gives a full Newton step for a whole array of independent problems (one per
history row). scipy offers vectorised bracketing solvers (``scipy.optimize.elementwise``) but none
that uses an exact derivative, which is what makes a 200-row history cost a handful of array
evaluations.
"""
from __future__ import annotations

from collections.abc import Callable

import numpy as np

from ..errors import ConvergenceError

__all__ = ["newton", "STEP", "XTOL"]

#: Complex step. Any tiny value works: no subtraction is involved.
STEP = 1e-30
#: Newton converges when its step is below XTOL (1 + |x|)
XTOL = 4e-15


def _eval(residual, x):
    with np.errstate(all="ignore"):
        r = np.asarray(residual(x + 1j * STEP), dtype=complex)
    return r.real, r.imag / STEP


def newton(residual: Callable[[np.ndarray], np.ndarray], x0, lo=None, hi=None, *,
           xtol: float = XTOL, maxiter: int = 60, what: str = "root solve",
           inputs: dict | None = None, on_fail: str = "raise") -> np.ndarray:
    """Solve ``residual(x) = 0`` elementwise by Newton's method with a bisection safeguard.

    Parameters
    ----------
    residual : callable
        Takes a complex array shaped like ``x0`` and returns the complex residual; must be analytic.
        NaN marks a point outside the model's domain.
    x0 : array_like
        Start values.
    lo, hi : array_like, optional
        A bracket with residuals of opposite sign (checked). Without one, a step that lands on NaN
        is halved back toward the last good iterate.
    xtol : float
        Converged when the Newton step is below ``xtol * (1 + |x|)``.
    maxiter : int
        Iteration cap.
    what, inputs :
        Carried by :class:`~adhfit.errors.ConvergenceError` when a solve fails.
    on_fail : {"raise", "nan"}
        ``"nan"`` returns NaN for the elements that fail instead of raising: an outer solve then
        backs off from the parameter values that caused it.

    Returns
    -------
    ndarray
        The roots, same shape as ``x0`` (float).

    Raises
    ------
    ConvergenceError
        If the bracket has no sign change or an element has not converged after ``maxiter`` steps.
    """
    x = np.array(np.broadcast_to(x0, np.shape(x0)), dtype=float)
    shape = x.shape
    x = x.ravel().copy()
    bracketed = lo is not None
    if bracketed:
        lo = np.broadcast_to(np.asarray(lo, dtype=float), shape).ravel().copy()
        hi = np.broadcast_to(np.asarray(hi, dtype=float), shape).ravel().copy()
        both, _ = _eval(lambda z: residual(z.reshape((2,) + shape)).reshape(-1),
                        np.concatenate([lo, hi]))
        rlo, rhi = both[: x.size], both[x.size:]
        bad = ~np.isfinite(rlo) | (np.sign(rlo) * np.sign(rhi) > 0)
        failed = bad.copy()
        if np.any(bad) and on_fail == "raise":
            i = int(np.flatnonzero(bad)[0])
            raise ConvergenceError(f"{what}: no sign change on the bracket",
                                   {**(inputs or {}), "index": i, "lo": lo[i], "hi": hi[i],
                                    "r_lo": rlo[i], "r_hi": rhi[i]})
        neg_at_lo = rlo < 0
        x = np.clip(x, np.minimum(lo, hi), np.maximum(lo, hi))
    else:
        failed = np.zeros(x.size, dtype=bool)
    active = ~failed
    last_good = x.copy()
    for _ in range(maxiter):
        idx = np.flatnonzero(active)
        if idx.size == 0:
            if np.any(failed) and on_fail == "raise":
                i = int(np.flatnonzero(failed)[0])
                raise ConvergenceError(f"{what}: the bracket closed on a point outside the domain",
                                       {**(inputs or {}), "index": i, "x": x[i]})
            return np.where(failed, np.nan, x).reshape(shape)
        xa = x[idx]
        full = x.copy()

        def sub(z, idx=idx):
            full_c = full.astype(complex)
            full_c[idx] = z
            return residual(full_c.reshape(shape)).reshape(-1)[idx]

        r, dr = _eval(sub, xa)
        finite = np.isfinite(r) & np.isfinite(dr)
        if bracketed:
            l, h = lo[idx], hi[idx]
            below = np.where(neg_at_lo[idx], r < 0, r > 0) & finite
            l = np.where(below, xa, l)
            h = np.where(finite & ~below, xa, h)
            lo[idx], hi[idx] = l, h
            step = np.where(finite & (dr != 0), -r / np.where(dr != 0, dr, 1.0), np.nan)
            xn = xa + step
            inside = np.isfinite(xn) & (xn >= np.minimum(l, h)) & (xn <= np.maximum(l, h))
            exact = finite & (r == 0)
            xn = np.where(exact, xa, np.where(inside, xn, 0.5 * (l + h)))
            done = exact | (inside & (np.abs(xn - xa) <= xtol * (1 + np.abs(xa)))) \
                | (np.abs(h - l) <= xtol * (1 + np.abs(xa)))
        else:
            good = finite & (dr != 0)
            last_good[idx] = np.where(good, xa, last_good[idx])
            step = np.where(good, -r / np.where(dr != 0, dr, 1.0), 0.0)
            # a NaN means the last step left the domain: go back half way toward the last good point
            xn = np.where(good, xa + step, 0.5 * (xa + last_good[idx]))
            done = good & ((r == 0) | (np.abs(step) <= xtol * (1 + np.abs(xa))))
        x[idx] = xn
        # a bracket can shrink onto an end where the residual is NaN: that is no root
        fake = done & bracketed & ~finite
        failed[idx[fake]] = True
        active[idx[done]] = False
    if np.any(active) and on_fail == "nan":
        return np.where(failed | active, np.nan, x).reshape(shape)
    if np.any(active):
        i = int(np.flatnonzero(active)[0])
        raise ConvergenceError(f"{what}: no convergence in {maxiter} iterations",
                               {**(inputs or {}), "index": i, "x": x[i],
                                "unconverged": int(active.sum())})
    return x.reshape(shape)
