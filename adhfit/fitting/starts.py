"""Start values from the data (docs/numerics.md B4: far-off starts fall into local minima).

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
import weakref

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

    A hinge is fitted by linear least squares to the loading rows below half the largest force:
    F = c + a·h + b·h², h = max(x - x_c, 0), for every candidate contact point x_c between two rows
    (and before the first); the x_c with the least squared residual wins.  Unlike a threshold on the
    force (which at a few per cent noise places contact many rows late), the fit uses every row and
    stays unbiased at 5 % noise.  ``sigma`` is accepted for backward compatibility.
    """
    return -hinge_contact(x, force, i_turn)[0]


def hinge_contact(x: np.ndarray, force: np.ndarray, i_turn: int) -> tuple[float, float]:
    """(x_c, c): contact point (measured units) and force level before contact of the hinge fit
    (see :func:`contact_offset`).

    Every candidate's least squares comes from running sums, so the cost is linear in the rows (one
    3-parameter solve per candidate over all rows was quadratic: 5 s of a 50,000-row fit's 338 s went
    here per start, and more as the rows grew).  With u = (x - x_0)/span and a candidate u_c, the rows
    past the candidate have h = u - u_c, and the normal equations need only the sums of u^p (p <= 4) and
    F u^p (p <= 2) over those rows, and the sums of 1 and F over the rows before it.
    """
    xl, fl = np.asarray(x[: i_turn + 1], float), np.asarray(force[: i_turn + 1], float)
    f_max = float(fl.max())
    above = np.flatnonzero(fl > 0.5 * f_max)
    end = max(int(above[0]) if above.size else xl.size, min(6, xl.size))
    order = np.argsort(xl[:end], kind="stable")
    xs, fs = xl[:end][order], fl[:end][order]
    span = float(xs[-1] - xs[0]) or 1.0
    u = (xs - xs[0]) / span
    cands = np.concatenate([[-0.05], 0.5 * (u[1:] + u[:-1])])[: max(xs.size - 3, 1)]
    k = np.arange(cands.size)  # rows k.. are past candidate k (u sorted)
    suffix = lambda v: np.cumsum(v[::-1])[::-1][k]  # noqa: E731 - sum over rows k..n-1
    up = [suffix(u ** p) for p in range(5)]
    fu = [suffix(fs * u ** p) for p in range(3)]
    n_all, f_all = float(xs.size), float(fs.sum())
    c = cands
    # moments of h = u - c over the rows past the candidate
    h1 = up[1] - c * up[0]
    h2 = up[2] - 2 * c * up[1] + c ** 2 * up[0]
    h3 = up[3] - 3 * c * up[2] + 3 * c ** 2 * up[1] - c ** 3 * up[0]
    h4 = up[4] - 4 * c * up[3] + 6 * c ** 2 * up[2] - 4 * c ** 3 * up[1] + c ** 4 * up[0]
    fh1 = fu[1] - c * fu[0]
    fh2 = fu[2] - 2 * c * fu[1] + c ** 2 * fu[0]
    a = np.empty((c.size, 3, 3))
    a[:, 0, 0] = n_all
    a[:, 0, 1] = a[:, 1, 0] = h1
    a[:, 0, 2] = a[:, 2, 0] = a[:, 1, 1] = h2
    a[:, 1, 2] = a[:, 2, 1] = h3
    a[:, 2, 2] = h4
    rhs = np.stack([np.full(c.size, f_all), fh1, fh2], axis=1)
    ok = np.abs(np.linalg.det(a)) > 1e-300
    coef = np.zeros((c.size, 3))
    coef[ok] = np.linalg.solve(a[ok], rhs[ok][..., None])[..., 0]
    rss = float(fs @ fs) - np.einsum("ij,ij->i", coef, rhs)
    good = ok & (coef[:, 1] + 2 * coef[:, 2] > 0)
    if not good.any():
        return float(xs[0]), 0.0
    i = int(np.flatnonzero(good)[np.argmin(rss[good])])
    return float(xs[0] + c[i] * span), float(coef[i, 0])


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


def _best(model: CurveModel, candidates: list[dict], rows: np.ndarray, f0: float = 0.0) -> dict | None:
    """The candidate parameter set with the least squared residual over ``rows``."""
    best, cost = None, np.inf
    for c in candidates:
        try:
            r = model.predict(c["work_of_adhesion"], c["mu_h"], c["x_offset"], f0)[rows] - model.force[rows]
        except ModelDomainError:
            continue
        if float(r @ r) < cost:
            best, cost = c, float(r @ r)
    return best


#: model -> {(fit_offset, fit_force_offset): Start}: a model's data-based start is computed once (~30
#: histories; a restart of the same slip condition from the other's optimum needs it again)
_STARTS: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def data_start(model: CurveModel, *, fit_offset: bool, fit_force_offset: bool = False) -> Start:
    """Start values for one slip condition from the data (see the module docstring; computed once per model).

    Raises
    ------
    ModelDomainError
        No μh in a wide range gives a history that reaches the data's largest control value.
    """
    memo = _STARTS.setdefault(model, {})
    key = (bool(fit_offset), bool(fit_force_offset))
    if key not in memo:
        memo[key] = _data_start(model, fit_offset=fit_offset, fit_force_offset=fit_force_offset)
    return Start(memo[key])


def _data_start(model: CurveModel, *, fit_offset: bool, fit_force_offset: bool) -> Start:
    x, seg = model.x, model.segments
    f0 = force_zero(x, model.force, seg.i_turn) if fit_force_offset else 0.0
    force = model.force - f0
    b = model.scene.membrane_radius
    off = contact_offset(x, force, seg.i_turn) if (fit_offset and model.control == "displacement") else 0.0
    f_max = float(force[seg.i_turn])
    w_probe = 0.1

    def stiffness(mu):
        pcs = model.pieces(w_probe * mu, mu, off)
        return model.scene.scales(mu).from_f(pcs.f_loading(np.array([pcs.x_max]))[0]) / f_max - 1.0

    mu_scale = f_max / (2.0 * b * 0.3)  # f ~ 0.3 at the end of a typical loading
    mus = _roots_log(stiffness, mu_scale / 300.0, mu_scale * 300.0, n=17)
    start = _best(model, [{"work_of_adhesion": w_probe * m, "mu_h": m, "x_offset": off} for m in mus],
                  seg.loading, f0)
    if start is None:
        raise ModelDomainError("no start value of mu_h reaches the data's largest control value",
                               {"x_max": model.x_max})
    mu = start["mu_h"]
    # the most negative force of the way out, smoothed over 5 rows (a single noisy row overshoots)
    tail = force[seg.i_turn:]
    f_min = float(np.convolve(tail, np.ones(5) / 5, mode="valid").min()) if tail.size >= 5 else float(tail.min())
    ws = [0.1]
    if f_min < 0:
        def pull_off(w):
            pcs = model.pieces(w * mu, mu, off)
            stable = np.asarray(pcs.columns["stable"], bool)
            f_po = float(np.asarray(pcs.columns["f"], float)[stable].min())
            return model.scene.scales(mu).from_f(f_po) / f_min - 1.0
        ws = _roots_log(pull_off, 1e-3, 10.0, n=13) or [0.1]
    best = _best(model, [{"work_of_adhesion": w * mu, "mu_h": mu, "x_offset": off} for w in ws],
                 np.ones(len(force), bool), f0)
    w_ad = best["work_of_adhesion"] if best is not None else 0.1 * mu
    return Start(work_of_adhesion=w_ad, mu_h=mu, x_offset=off, force_offset=f0)


def force_zero(x: np.ndarray, force: np.ndarray, i_turn: int) -> float:
    """Start value of the load-cell zero (N): the force level before contact from the hinge fit."""
    return hinge_contact(x, force, i_turn)[1]
