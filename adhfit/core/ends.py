"""The end of loading from ``delta_max`` or ``p_max``, from the making-contact states themselves.

Making contact is explicit in the contact radius a (docs/numerics.md B3): under displacement control
the state at a is closed-form at the fixed pressure; under pressure control the pressure at a is the
1-D root of the gap condition (unique: the gap grows with the pressure). The loading end is the
first radius where the control value (delta or p) reaches the target along the loading branch, from
a -> 0 up to the largest admissible radius (the table's a_max bound and 0.95 rs, or where the branch
leaves Case I). The branch is scanned on a fixed geometric grid, then the crossing is bracketed and
solved by Brent's method, so the answer and the "unreachable" verdict come from the same states the
history uses; an unreachable end is reported with the largest value the branch reaches (refined
between grid points), where it is reached, and why the branch stops.

Pure Python over the compiled kernels of :mod:`.branches` and :mod:`.newton`; dimensionless.
"""
from __future__ import annotations

import math

import numpy as np
from scipy.optimize import brentq, minimize_scalar

from .branches import MC, evaluate_batch
from .newton import OK, mc_bracketed

__all__ = ["LoadingEnd", "control_value", "resolve_end", "SCAN"]

#: grid points of the scan along the making-contact branch (geometric in a from 1e-6 of the cap)
SCAN = 160
_XTOL = 1e-15


class LoadingEnd:
    """The outcome of :func:`resolve_end`.

    Attributes
    ----------
    a : float
        The contact radius where the control value first reaches the target; NaN when unreachable.
    top : float
        Largest control value the loading branch reaches (the valid range's upper end).
    a_top : float
        Where ``top`` is reached.
    a_end : float
        The largest contact radius of the loading branch (where it leaves the model, or the cap).
    why : str
        Why the branch stops there, in words (``"a_max = 0.95 rs"``, ``"the membrane turns past
        vertical at the clamp (Case I ends)"``, ...).
    """

    def __init__(self, a, top, a_top, why, a_end=math.nan):
        self.a, self.top, self.a_top, self.why, self.a_end = a, top, a_top, why, a_end


def _hi_pressure(a, c):
    """Largest Case I pressure at contact radius a: sin(theta) at the clamp, kappa (1 - a^2) - c a^2, below 1."""
    return (1.0 + c * a * a) / (1.0 - a * a) * (1 - 1e-12)


def control_value(a: float, pressure: bool, kappa: float, d_fix: float, p_cr: float, c: float) -> float:
    """delta (displacement control, pressure ``kappa``) or p (pressure control, gap ``d_fix``) of the
    making-contact state at radius ``a``; NaN outside Case I or where the gap condition has no root."""
    if pressure:
        k, st = mc_bracketed(a, c, d_fix, p_cr, _hi_pressure(a, c))
        if st != OK:
            return math.nan
    else:
        k = kappa
    out, ok = evaluate_batch(MC, np.array([a]), np.array([k]), np.array([a]), c, 0.0, math.nan)
    if not (ok[0] and np.isfinite(out[:6, 0]).all()):
        return math.nan
    if pressure:
        return float(k)
    return float(kappa / (1.0 + math.sqrt(1.0 - kappa * kappa)) - out[3, 0])  # d0(p) - d


def resolve_end(pressure: bool, kappa: float, d_fix: float, p_cr: float, c: float, target: float,
                cap: float) -> LoadingEnd:
    """Solve where the loading branch's control value first reaches ``target``.

    Parameters
    ----------
    pressure : bool
        Pressure control (the value is p) or displacement control (the value is delta).
    kappa, d_fix, p_cr : float
        Fixed pressure (displacement control); fixed gap and the pressure at which contact starts
        (pressure control).
    c : float
        Substrate curvature 1/rs.
    target : float
        ``delta_max`` or ``p_max``.
    cap : float
        Largest admissible contact radius (table bound, 0.95 rs).

    Returns
    -------
    LoadingEnd
        ``a`` the radius (NaN when the branch never reaches the target), ``top``, ``a_top``, ``why``.
    """
    grid = cap * np.geomspace(1e-6, 1.0, SCAN)
    f = lambda a: control_value(a, pressure, kappa, d_fix, p_cr, c)  # noqa: E731
    vals = np.array([f(a) for a in grid])
    good = np.isfinite(vals)
    if not good.any():
        return LoadingEnd(math.nan, math.nan, math.nan, "no making-contact state is inside the model")
    start = int(np.argmax(good))
    stop = start + int(np.argmin(good[start:])) if not good[start:].all() else grid.size
    grid, vals = list(grid[start:stop]), list(vals[start:stop])
    if stop < start + len(good[start:]):  # the branch ends between two grid points: find where
        lo, hi = grid[-1], cap * np.geomspace(1e-6, 1.0, SCAN)[stop]
        for _ in range(60):
            mid = 0.5 * (lo + hi)
            lo, hi = (mid, hi) if math.isfinite(f(mid)) else (lo, mid)
        grid.append(lo)
        vals.append(f(lo))
        why = (f"the loading branch leaves the model at a = {lo:.6g} (the membrane would turn past vertical "
               "at the clamp: Case I ends)")
    else:
        why = f"a = {cap:.6g} is the largest contact radius (0.95 rs, or the a_max bound)"
    for i, v in enumerate(vals):
        if v >= target:
            if i == 0:  # the branch starts above it: only a radius below the grid's first reaches it
                return LoadingEnd(grid[0], v, grid[0], "")
            a = brentq(lambda x: f(x) - target, grid[i - 1], grid[i], xtol=_XTOL, rtol=1e-15, maxiter=200)
            return LoadingEnd(a, math.nan, math.nan, "")
    j = int(np.argmax(vals))
    a_top, top = grid[j], vals[j]
    if 0 < j < len(vals) - 1:  # an interior maximum: refine it between its neighbours
        res = minimize_scalar(lambda x: -f(x), bounds=(grid[j - 1], grid[j + 1]), method="bounded",
                              options={"xatol": 1e-12 * grid[j]})
        if math.isfinite(res.fun) and -res.fun > top:
            a_top, top = float(res.x), float(-res.fun)
        if top >= target:  # reached between the grid's rows, at the peak's rising side
            a = brentq(lambda x: f(x) - target, grid[j - 1], a_top, xtol=_XTOL, rtol=1e-15, maxiter=200)
            return LoadingEnd(a, math.nan, math.nan, "")
        why = f"the control value peaks on loading at a = {a_top:.6g} and falls after it"
    return LoadingEnd(math.nan, top, a_top, why, grid[-1])
