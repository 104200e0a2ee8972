"""Start values from the data (DESIGN.md B4: far-off starts fall into local minima).

* **offset** (displacement control): the contact point, where a straight line through the loading
  rows with forces between 5 % and 30 % of the largest force reaches zero force;
* **μh**: a 1-D solve over μh of the making-contact model so that it matches the force at the
  largest control value (the loading stiffness);
* **W_ad**: given μh and the offset, a 1-D solve over w = W_ad/μh so that the model's most negative
  force on the stable way out matches the data's most negative force.

Each solve scans a logarithmic grid (skipping parameters outside the model's domain) and refines the
first sign change with ``brentq``; each step is one history of the :class:`~.model.CurveModel`.
"""
from __future__ import annotations

import math

import numpy as np
from scipy.optimize import brentq

from .model import CurveModel, ModelDomainError

__all__ = ["Start", "data_start", "noise_estimate", "contact_offset"]


class Start(dict):
    """Start values in SI: ``work_of_adhesion``, ``mu_h``, ``x_offset``, ``force_offset``."""


def noise_estimate(force: np.ndarray) -> float:
    """Robust σ of the force noise (N) from second differences: var(Δ²F) = 6σ² for white noise.

    The median absolute deviation ignores the few large second differences at the stage changes and
    at the jump.
    """
    d2 = np.diff(np.asarray(force, float), 2)
    if d2.size == 0:
        return 0.0
    return float(1.4826 * np.median(np.abs(d2 - np.median(d2))) / math.sqrt(6.0))


def contact_offset(x: np.ndarray, force: np.ndarray, i_turn: int, sigma: float = 0.0) -> float:
    """Offset that puts the contact point at δ = 0 (minus the measured control value at contact).

    With rows before contact (forces within 3σ of zero at the start), contact is placed between the
    last such row and the next; otherwise a straight line through the loading rows with forces
    between 5 % and 30 % of the largest force is extrapolated to zero force.
    """
    xl, fl = np.asarray(x[: i_turn + 1], float), np.asarray(force[: i_turn + 1], float)
    f_max = float(fl.max())
    level = max(3.0 * sigma, 0.01 * f_max)
    above = fl > level
    # the last loading row still at zero force, counting from the end of loading back
    low = np.flatnonzero(~above)
    if low.size >= 2 and low[0] == 0:
        k = int(low[-1])
        return -float(0.5 * (xl[k] + xl[min(k + 1, xl.size - 1)]))
    band = (fl > 0.05 * f_max) & (fl < 0.3 * f_max)
    if band.sum() >= 2:
        slope, icpt = np.polyfit(xl[band], fl[band], 1)
        if slope > 0:
            return -float(-icpt / slope)
    first = np.flatnonzero(above)
    return -float(xl[first[0]] if first.size else xl[0])


def _roots_log(g, lo: float, hi: float, n: int = 13) -> list[float]:
    """Roots of g on a log grid [lo, hi] (every sign change, refined by brentq).

    Grid points outside the model's domain are skipped; when there is no sign change the grid point
    closest to a match is returned.  Several roots are possible (under pressure control the force at
    the largest pressure is not monotone in μh): the caller picks one by the residual.
    """
    grid = np.geomspace(lo, hi, n)
    vals = []
    for v in grid:
        try:
            vals.append(g(v))
        except ModelDomainError:
            vals.append(np.nan)
    vals = np.array(vals)
    roots = []
    for i in range(n - 1):
        a, b = vals[i], vals[i + 1]
        if np.isfinite(a) and np.isfinite(b) and a * b <= 0:
            try:
                roots.append(math.exp(brentq(lambda s: g(math.exp(s)), math.log(grid[i]),
                                             math.log(grid[i + 1]), xtol=1e-4, rtol=1e-5, maxiter=30)))
            except (ModelDomainError, ValueError):
                roots.append(float(grid[i]))
    good = np.isfinite(vals)
    if not roots and good.any():
        roots.append(float(grid[good][np.argmin(np.abs(vals[good]))]))
    return roots


def _best(model: CurveModel, candidates: list[dict], rows: np.ndarray) -> dict | None:
    """The candidate parameter set with the least squared residual over ``rows``."""
    best, cost = None, np.inf
    for c in candidates:
        try:
            r = model.predict(c["work_of_adhesion"], c["mu_h"], c["x_offset"])[rows] - model.force[rows]
        except ModelDomainError:
            continue
        if float(r @ r) < cost:
            best, cost = c, float(r @ r)
    return best


def data_start(model: CurveModel, *, fit_offset: bool) -> Start:
    """Start values for one slip condition from the data (see the module docstring).

    Raises
    ------
    ModelDomainError
        No μh in a wide range gives a history that reaches the data's largest control value.
    """
    x, force, seg = model.x, model.force, model.segments
    b = model.scene.membrane_radius
    off = contact_offset(x, force, seg.i_turn, noise_estimate(force)) \
        if (fit_offset and model.control == "displacement") else 0.0
    f_max = float(force[seg.i_turn])
    w_probe = 0.1

    def stiffness(mu):
        pcs = model.pieces(w_probe * mu, mu, off)
        return model.scene.scales(mu).from_f(pcs.f_loading(np.array([pcs.x_max]))[0]) / f_max - 1.0

    mu_scale = f_max / (2.0 * b * 0.3)  # f ~ 0.3 at the end of a typical loading
    mus = _roots_log(stiffness, mu_scale / 300.0, mu_scale * 300.0, n=17)
    start = _best(model, [{"work_of_adhesion": w_probe * m, "mu_h": m, "x_offset": off} for m in mus],
                  seg.loading)
    if start is None:
        raise ModelDomainError("no start value of mu_h reaches the data's largest control value",
                               {"x_max": model.x_max})
    mu = start["mu_h"]
    f_min = float(force[seg.i_turn:].min())
    ws = [0.1]
    if f_min < 0:
        def pull_off(w):
            pcs = model.pieces(w * mu, mu, off)
            stable = pcs.frame["stable"].to_numpy(bool)
            f_po = float(pcs.frame["f"].to_numpy(float)[stable].min())
            return model.scene.scales(mu).from_f(f_po) / f_min - 1.0
        ws = _roots_log(pull_off, 1e-3, 10.0, n=13) or [0.1]
    best = _best(model, [{"work_of_adhesion": w * mu, "mu_h": mu, "x_offset": off} for w in ws],
                 np.ones(len(force), bool))
    w_ad = best["work_of_adhesion"] if best is not None else 0.1 * mu
    return Start(work_of_adhesion=w_ad, mu_h=mu, x_offset=off, force_offset=0.0)
