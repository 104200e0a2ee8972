"""Synthetic measured curves from the forward model: for sample data, recovery tests and stress runs.

A synthetic test follows a real one: the control variable rises from before contact to its largest
value at a constant step, then falls at the same step past pull-off; the force is the model's, zero
before contact and after the turning point (the jump at pull-off, then the free membrane), plus a
load-cell offset and Gaussian noise.  The measured control variable carries an offset (the contact
point is never known exactly): ``measured = true - offset``.

The forward model is sampled densely (``points`` rows) and interpolated linearly in the history's
own parametrisation (x on loading, u = sqrt(x - x_tp) on the way out) — independently of the
piecewise-cubic interpolation the fit uses.

Test series: Synthetic test series (one membrane at several pressures or gaps) with a filmed contact radius.

Each curve is :func:`~.synthetic.synthetic_curve`; the contact radius column is added here from the
same dense forward history (linear interpolation in the history's own parametrisation, as the force:
x on loading, u = sqrt(x - x_tp) on the way out; independent of the fit's piecewise-cubic
interpolants), 0 before contact and after pull-off, plus Gaussian noise on the rows in contact.  A
camera reports no contact as 0, so a noisy value below 0 is recorded as 0.

**As a testing machine records it** (``adhfit simulate --scene``). ``adhfit simulate --scene``: a curve as a testing machine would record it, in physical units.

The rows follow a real test (:func:`.synthetic.synthetic_curve`): the control variable rises at a
constant step from before contact to the end of loading, then falls at the same step; the membrane
stays on the stable branch down to the turning point, where a real test jumps off, and the rows after
it are the detached, free membrane (force zero, plus noise).  The columns are those ``adhfit fit``
reads (``displacement [um]`` or ``pressure [kPa]``, ``force [mN]``), so a synthetic study goes
simulate → fit through the command line.
"""
from __future__ import annotations

import dataclasses

import numpy as np
import pandas as pd

from .data import Curve
from .errors import ConvergenceError, InputError
from .scene import Scene
from .simulation import simulate
from .units import parse_quantity
from .params import CONTROL_KEY

__all__ = ["synthetic_curve", "synthetic_series", "true_contact_radius", "measured_frame", "loading_end_si",
           "parse_end"]


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
                    rng: np.random.Generator, points: int = 2000, force_drift: float = 0.0) -> tuple[Curve, dict]:
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
    force_drift : float
        A drift of the load-cell zero, N, added linearly in row order (0 at the first row, this at the last).
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
    force = force + force_drift * np.arange(force.size) / max(force.size - 1, 1)
    x = from_x(np.concatenate([up, down])) - x_offset
    curve = Curve(path="<synthetic>", control=scene.control, x=x, force=force,
                  line=np.arange(2, x.size + 2), i_turn=int(np.argmax(x)))
    truth = {"slip": slip, "work_of_adhesion": float(work_of_adhesion), "mu_h": float(mu_h),
             "x_offset": float(x_offset), "force_offset": float(force_offset), "sigma": sigma,
             "force_drift": float(force_drift),
             "x_turning_point": float(from_x(x_tp)) - x_offset, "force_turning_point": float(sc.from_f(f_tp)),
             "i_jump": int(up.size + np.count_nonzero(down >= x_tp))}
    return curve, truth


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


_END_DIM = {"a_max": "length", "delta_max": "length", "p_max": "pressure"}


def measured_frame(scene: Scene, slip: str, *, mu_h: float, work_of_adhesion: float, x_max: float,
                   rows: int = 200, noise: float = 0.0, seed: int | None = None) -> tuple[pd.DataFrame, dict]:
    """A measured-style curve of ``scene`` and its truth.

    Parameters
    ----------
    scene : Scene
    slip : {"no-slip", "frictionless"}
    mu_h, work_of_adhesion : float
        N/m and J/m².
    x_max : float
        Largest displacement (m) or pressure (Pa) reached on loading.
    rows : int
        Approximate number of rows.
    noise : float
        Gaussian force noise as a fraction of the force at the end of loading (0.01 = 1 %), ≥ 0.
    seed : int, optional
        Seed of the noise (numpy ``default_rng``); not used when ``noise`` is 0.

    Returns
    -------
    (pandas.DataFrame, dict)
        Columns ``displacement [um]`` or ``pressure [kPa]``, then ``force [mN]``; the truth
        (parameters, σ in N, the turning point and the first detached row, 0-based).
    """
    if not (isinstance(noise, (int, float)) and 0.0 <= noise <= 1.0):
        raise InputError("--noise", noise, "a fraction of the largest force in [0, 1], e.g. 0.01")
    if not 20 <= int(rows) <= 100_000:
        raise InputError("--points", rows, "an integer in [20, 100000] (rows of the measured curve)")
    rng = np.random.default_rng(seed)
    curve, truth = synthetic_curve(scene, slip, work_of_adhesion=work_of_adhesion, mu_h=mu_h, x_max=x_max,
                                   rows=int(rows), noise=float(noise), rng=rng)
    if scene.control == "displacement":
        x = pd.Series(curve.x * 1e6, name="displacement [um]")
    else:
        x = pd.Series(curve.x * 1e-3, name="pressure [kPa]")
    frame = pd.DataFrame({x.name: x, "force [mN]": curve.force * 1e3})
    truth = {**truth, "noise_fraction": float(noise), "seed": seed}
    return frame, truth


def loading_end_si(frame: pd.DataFrame, control: str, scales) -> float:
    """The largest control value of a history's loading (SI: m of displacement or Pa of pressure)."""
    loading = frame[frame["stage"] != "delamination"]
    if control == "displacement":
        return float(scales.from_delta(float(np.nanmax(loading["delta"].to_numpy(float)))))
    return float(scales.from_p(float(np.nanmax(loading["p"].to_numpy(float)))))


def parse_end(key: str, value: float | str, scales) -> float:
    """A loading end (``a_max``, ``delta_max`` or ``p_max``) as its dimensionless group: a bare number
    is already dimensionless (docs/contracts.md A1 groups), a string with a unit ("0.6 mm", "1.6 kPa") is converted."""
    if not isinstance(value, str):
        return float(value)
    si = parse_quantity(value, _END_DIM[key], name=f"--{key.replace('_', '-')}")
    return float(si / scales.length if _END_DIM[key] == "length" else scales.to_p(si))
