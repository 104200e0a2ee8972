"""Physical units on top of the dimensionless engine: a scene in SI in, SI tables and profiles out.

The only conversions are :class:`adhfit.units.Scales` (length b, force 2 mu h b, pressure 2 mu h / b,
energy per area mu h); the physics stays in :func:`adhfit.simulate`.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
import pandas as pd

from .core.profile import profile as _profile
from .scene import Scene
from .simulation import SimulationResult, simulate
from .units import Scales

__all__ = ["SceneResult", "simulate_scene", "SI_COLUMNS"]

#: SI column -> (A1 group, scale attribute of Scales or None for dimensionless)
SI_COLUMNS = {
    "contact_radius [m]": ("a", "length"),
    "contact_angle [rad]": ("alpha", None),
    "pressure [Pa]": ("p", "pressure"),
    "gap [m]": ("d", "length"),
    "displacement [m]": ("delta", "length"),
    "force [N]": ("f", "force"),
    "energy_release_rate [J/m^2]": ("G", "energy"),
}


@dataclass(frozen=True)
class SceneResult:
    """A history of one scene, in SI and dimensionless form.

    Attributes
    ----------
    scene : Scene
        The input (SI).
    scales : Scales
        Length, force, pressure and energy scales used.
    result : SimulationResult
        The dimensionless history (``result.frame`` has the docs/contracts.md A2 columns).
    """

    scene: Scene
    scales: Scales
    result: SimulationResult

    @property
    def frame(self) -> pd.DataFrame:
        """The dimensionless history (docs/contracts.md A2 columns)."""
        return self.result.frame

    @property
    def si(self) -> pd.DataFrame:
        """The history in SI: stage, contact radius, angle, pressure, gap, displacement, force,
        energy release rate, stable."""
        fr = self.result.frame
        out = {"stage": fr["stage"].to_numpy()}
        for col, (group, scale) in SI_COLUMNS.items():
            factor = 1.0 if scale is None else getattr(self.scales, scale)
            out[col] = fr[group].to_numpy(float) * factor
        out["stable"] = fr["stable"].to_numpy(bool)
        return pd.DataFrame(out)

    @property
    def summary_si(self) -> dict[str, Any]:
        """The summary (f_max, onset, f_min, turning point) in SI: force N, displacement m,
        pressure Pa, contact radius m; ``None`` where undefined."""
        s, sc = self.result.summary, self.scales

        def point(pt):
            conv = {"f": ("force [N]", sc.force), "delta": ("displacement [m]", sc.length),
                    "p": ("pressure [Pa]", sc.pressure), "a": ("contact_radius [m]", sc.length)}
            return {name: (None if pt[k] is None else pt[k] * f) for k, (name, f) in conv.items()}
        return {"force_max [N]": s["f_max"] * sc.force,
                **{k: point(s[k]) for k in ("onset", "f_min", "turning_point")}}

    def profile(self, row: int, n: int = 200) -> tuple[np.ndarray, np.ndarray]:
        """Membrane profile of history row ``row`` in metres: (r, z), z = 0 at the clamp, the
        substrate apex at z = -gap. Computed on request only."""
        fr = self.result.frame
        if not 0 <= row < len(fr):
            from .errors import InputError  # noqa: PLC0415
            raise InputError("row", row, f"an integer in [0, {len(fr) - 1}]")
        x = fr.iloc[row]
        r, z = _profile(x["stage"], self.result.inputs["slip"], a=float(x["a"]), alpha=float(x["alpha"]),
                        p=float(x["p"]), d=float(x["d"]), f=float(x["f"]), G=float(x["G"]),
                        rs=self.result.inputs["rs"], n=n)
        return r * self.scales.length, z * self.scales.length

    def plot(self, ax=None, path=None):
        """Force against displacement (mN, µm) or pressure (kPa), stages coloured; returns the axes."""
        from .report.plots import plot_history  # noqa: PLC0415 - matplotlib only when plotting
        return plot_history(self.result, scene=self, ax=ax, path=path)


def simulate_scene(scene: Scene, *, mu_h: float | str | None = None,
                   work_of_adhesion: float | str | None = None, slip: str | None = None,
                   points: int = 200, **loading_end: float) -> SceneResult:
    """Simulate one scene given in SI units.

    Parameters
    ----------
    scene : Scene
        Geometry, material, interface and loading (:func:`adhfit.scene.load_scene`).
    mu_h, work_of_adhesion : float or str, optional
        Override the scene's values (N/m, J/m^2; strings with units accepted).
    slip : {"no-slip", "frictionless"}, optional
        Required when the scene says ``"auto"``.
    points : int
        Approximate number of rows.
    **loading_end
        One of ``a_max``, ``delta_max``, ``p_max`` (dimensionless) to override the scene's loading
        end.

    Returns
    -------
    SceneResult
    """
    kwargs = scene.to_dimensionless(mu_h, work_of_adhesion, slip=slip)
    if loading_end:
        for k in ("a_max", "delta_max", "p_max"):
            kwargs.pop(k, None)
        kwargs.update(loading_end)
    result = simulate(**kwargs, points=points)
    return SceneResult(scene=scene, scales=scene.scales(mu_h), result=result)


def _finite(x) -> bool:
    return x is None or math.isfinite(x)
