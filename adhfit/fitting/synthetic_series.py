"""Synthetic test series (one membrane at several pressures or gaps) with a filmed contact radius.

Each curve is :func:`~.synthetic.synthetic_curve`; the contact radius column is added here from the
same dense forward history (linear interpolation in the history's own parametrisation, as the force:
x on loading, u = sqrt(x - x_tp) on the way out; independent of the fit's piecewise-cubic
interpolants), 0 before contact and after pull-off, plus Gaussian noise on the rows in contact.  A
camera reports no contact as 0, so a noisy value below 0 is recorded as 0.
"""
from __future__ import annotations

import dataclasses

import numpy as np

from .model import CONTROL_KEY
from .synthetic import _history, _retraction, synthetic_curve

__all__ = ["synthetic_series", "true_contact_radius"]


def true_contact_radius(scene, slip: str, curve, truth: dict, *, points: int = 2000) -> np.ndarray:
    """The model's contact radius (m) at every row of a synthetic curve (its truth)."""
    key = CONTROL_KEY[scene.control]
    mu, w = truth["mu_h"], truth["work_of_adhesion"]
    sc = scene.scales(mu)
    kw = scene.to_dimensionless(mu_h=mu, work_of_adhesion=w, slip=slip)
    for end in ("a_max", "delta_max", "p_max"):
        kw.pop(end, None)
    to_x = sc.to_delta if scene.control == "displacement" else sc.to_p
    x_true = to_x(np.asarray(curve.x, float) + truth["x_offset"])
    end = "delta_max" if scene.control == "displacement" else "p_max"
    frame = _history(kw, {end: float(x_true[curve.i_turn])}, points)
    mc = frame[frame["stage"] == "making_contact"]
    xl, al = mc[key].to_numpy(float), mc["a"].to_numpy(float)
    xr, ar = _retraction(frame.assign(f=frame["a"]), key)
    x_tp = xr[-1]
    n = x_true.size
    a = np.zeros(n)
    load = np.arange(n) <= curve.i_turn
    a[load] = np.where(x_true[load] <= xl[0], 0.0, np.interp(x_true[load], xl, al))
    att = (np.arange(n) > curve.i_turn) & (np.arange(n) < truth["i_jump"])
    u_r = np.sqrt(np.clip(xr - x_tp, 0, None))[::-1]
    a[att] = np.interp(np.sqrt(np.clip(x_true[att] - x_tp, 0, None)), u_r, ar[::-1])
    return a * scene.membrane_radius


def synthetic_series(scene, slip: str, *, pressures=None, gaps=None, work_of_adhesion: float, mu_h: float,
                     x_max, noise: float = 0.01, radius_noise: float | None = 0.01, x_offsets=None,
                     force_offset: float = 0.0, rows: int = 200, rng: np.random.Generator,
                     mu_h_per_curve=None) -> list[tuple]:
    """Curves of one membrane at several pressures (displacement control) or gaps (pressure control).

    Parameters
    ----------
    scene : Scene
        Geometry; its pressure (or gap) is replaced per curve.
    slip : str
    pressures, gaps : sequence of float
        One per curve, Pa or m (which one follows the scene's control).
    work_of_adhesion, mu_h : float
        The shared truth.
    x_max : float or sequence
        Largest control value per curve.
    noise : float
        Force noise as a fraction of each curve's force at the end of loading.
    radius_noise : float or None
        Contact-radius noise as a fraction of the curve's largest contact radius; ``None``: no column.
    x_offsets : sequence, optional
        Control offsets per curve (default: 2 % of b under displacement control, 0 otherwise).
    mu_h_per_curve : sequence, optional
        Override μh per curve (an outlier membrane).
    rng : numpy.random.Generator

    Returns
    -------
    list of (Curve, Scene, truth)
    """
    values = pressures if scene.control == "displacement" else gaps
    field = "pressure" if scene.control == "displacement" else "gap"
    n = len(values)
    x_maxs = list(x_max) if np.ndim(x_max) else [x_max] * n
    if x_offsets is None:
        x_offsets = [0.02 * scene.membrane_radius * (1 + 0.3 * i) if scene.control == "displacement" else 0.0
                     for i in range(n)]
    mus = list(mu_h_per_curve) if mu_h_per_curve is not None else [mu_h] * n
    out = []
    for i, v in enumerate(values):
        sc = dataclasses.replace(scene, **{field: float(v)})
        curve, truth = synthetic_curve(sc, slip, work_of_adhesion=work_of_adhesion, mu_h=mus[i], x_max=x_maxs[i],
                                       rows=rows, noise=noise, x_offset=x_offsets[i], force_offset=force_offset,
                                       rng=rng)
        curve = dataclasses.replace(curve, path=f"<synthetic {field} {v:g}>")
        if radius_noise is not None:
            a = true_contact_radius(sc, slip, curve, truth)
            s_a = radius_noise * float(a.max())
            meas = np.where(a > 0, np.clip(a + rng.normal(0.0, s_a, a.size), 0.0, None), 0.0)
            curve = dataclasses.replace(curve, contact_radius=meas)
            truth["sigma_contact_radius"] = s_a
        out.append((curve, sc, truth))
    return out
