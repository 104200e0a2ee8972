"""Synthetic measured curves from the forward model: for sample data, recovery tests and stress runs.

A synthetic test follows a real one: the control variable rises from before contact to its largest
value at a constant step, then falls at the same step past pull-off; the force is the model's, zero
before contact and after the turning point (the jump at pull-off, then the free membrane), plus a
load-cell offset and Gaussian noise.  The measured control variable carries an offset (the contact
point is never known exactly): ``measured = true - offset``.

The forward model is sampled densely (``points`` rows) and interpolated linearly in the history's
own parametrisation (x on loading, u = sqrt(x - x_tp) on the way out) — independently of the
piecewise-cubic interpolation the fit uses.
"""
from __future__ import annotations

import numpy as np

from ..data import Curve
from ..errors import ConvergenceError
from ..simulation import simulate
from .model import CONTROL_KEY

__all__ = ["synthetic_curve"]


def _retraction(frame, key):
    """(x, f) of the stable way out, from the end of loading to the turning point."""
    stage = frame["stage"].to_numpy()
    stable = frame["stable"].to_numpy(bool)
    mc_last = int(np.flatnonzero(stage == "making_contact")[-1])
    rows = np.flatnonzero((stage != "making_contact") & stable)
    rows = np.concatenate([[mc_last], rows])
    return frame[key].to_numpy(float)[rows], frame["f"].to_numpy(float)[rows]


def _history(kw, end, points):
    """The dense history; a neighbouring row count when the engine's continuation stalls."""
    for extra in (0, 13, 37, 101, 211, -499, -997):
        try:
            return simulate(**kw, **end, points=points + extra).frame
        except ConvergenceError as err:
            failure = err
    raise failure


def synthetic_curve(scene, slip: str, *, work_of_adhesion: float, mu_h: float, x_max: float,
                    rows: int = 200, noise: float = 0.005, x_offset: float = 0.0,
                    force_offset: float = 0.0, approach: float = 0.08, tail: float = 0.15,
                    rng: np.random.Generator, points: int = 2000) -> tuple[Curve, dict]:
    """A synthetic measured curve in SI units, and its truth.

    Parameters
    ----------
    scene : adhfit.scene.Scene
        Geometry and the fixed pressure (displacement control) or gap (pressure control).
    slip : {"no-slip", "frictionless"}
    work_of_adhesion, mu_h : float
        W_ad (J/m^2) and μh (N/m).
    x_max : float
        Largest control value reached: contact displacement δ (m) or pressure (Pa).
    rows : int
        Approximate number of rows (loading and unloading at the same step).
    noise : float
        Standard deviation of the Gaussian force noise, as a fraction of the force at the end of
        loading (0.005 = 0.5 %).
    x_offset : float
        True control value minus measured one (m or Pa); the fit's offset estimates it.
    force_offset : float
        Added to every force, N (load-cell zero).
    approach, tail : float
        Rows before contact and after pull-off, as fractions of the loading and unloading ranges.
    rng : numpy.random.Generator
        Source of the noise (explicit: no global seeding).
    points : int
        Rows of the dense forward history.

    Returns
    -------
    (Curve, dict)
        The curve (``path`` = ``"<synthetic>"``) and the truth: parameters, σ (N), offsets, the
        turning point and the index of the first detached row.
    """
    key = CONTROL_KEY[scene.control]
    sc = scene.scales(mu_h)
    kw = scene.to_dimensionless(mu_h=mu_h, work_of_adhesion=work_of_adhesion, slip=slip)
    for end in ("a_max", "delta_max", "p_max"):
        kw.pop(end, None)
    to_x = sc.to_delta if scene.control == "displacement" else sc.to_p
    from_x = sc.from_delta if scene.control == "displacement" else sc.from_p
    end = "delta_max" if scene.control == "displacement" else "p_max"
    frame = _history(kw, {end: to_x(x_max)}, points)
    mc = frame[frame["stage"] == "making_contact"]
    xl, fl = mc[key].to_numpy(float), mc["f"].to_numpy(float)
    xr, fr = _retraction(frame, key)
    x_tp, f_tp = xr[-1], fr[-1]
    x0, x1 = xl[0], xl[-1]
    start = x0 - approach * (x1 - x0)
    stop = x_tp - tail * (x1 - x_tp)
    step = ((x1 - start) + (x1 - stop)) / max(rows - 1, 2)
    up = np.linspace(start, x1, max(int(round((x1 - start) / step)), 3) + 1)
    down = np.linspace(x1, stop, max(int(round((x1 - stop) / step)), 3) + 1)[1:]
    f_up = np.where(up <= x0, 0.0, np.interp(up, xl, fl))
    u_r = np.sqrt(np.clip(xr - x_tp, 0, None))[::-1]
    f_down = np.where(down < x_tp, 0.0, np.interp(np.sqrt(np.clip(down - x_tp, 0, None)), u_r, fr[::-1]))
    f_true = sc.from_f(np.concatenate([f_up, f_down]))
    sigma = noise * float(sc.from_f(fl[-1]))
    force = f_true + force_offset + rng.normal(0.0, sigma, f_true.size)
    x = from_x(np.concatenate([up, down])) - x_offset
    curve = Curve(path="<synthetic>", control=scene.control, x=x, force=force,
                  line=np.arange(2, x.size + 2), i_turn=int(np.argmax(x)))
    truth = {"slip": slip, "work_of_adhesion": float(work_of_adhesion), "mu_h": float(mu_h),
             "x_offset": float(x_offset), "force_offset": float(force_offset), "sigma": sigma,
             "x_turning_point": float(from_x(x_tp)) - x_offset, "force_turning_point": float(sc.from_f(f_tp)),
             "i_jump": int(up.size + np.count_nonzero(down >= x_tp))}
    return curve, truth
