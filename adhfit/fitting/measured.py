"""``adhfit simulate --scene``: a curve as a testing machine would record it, in physical units.

The rows follow a real test (:func:`.synthetic.synthetic_curve`): the control variable rises at a
constant step from before contact to the end of loading, then falls at the same step; the membrane
stays on the stable branch down to the turning point, where a real test jumps off, and the rows after
it are the detached, free membrane (force zero, plus noise).  The columns are those ``adhfit fit``
reads (``displacement [um]`` or ``pressure [kPa]``, ``force [mN]``), so a synthetic study goes
simulate → fit through the command line.
"""
from __future__ import annotations

import numpy as np
import pandas as pd

from ..errors import InputError
from ..scene import Scene
from ..units import parse_quantity
from .synthetic import synthetic_curve

__all__ = ["measured_frame", "loading_end_si", "parse_end"]

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
