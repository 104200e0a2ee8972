"""``adhfit.simulate``: the dimensionless forward model as a table (docs/contracts.md A2b)."""
from __future__ import annotations

import math
from dataclasses import dataclass

import pandas as pd

from . import membranes
from .loading import COLUMNS
from .params import check_scene

__all__ = ["SimulationResult", "simulate"]


@dataclass(frozen=True)
class SimulationResult:
    """A computed history.

    Attributes
    ----------
    frame : pandas.DataFrame
        Columns ``stage, a, alpha, p, d, delta, f, G, stable`` (docs/contracts.md A2), history order,
        dimensionless; ``delta`` is NaN where d0(p) is undefined (|p| > 1).
    summary : dict
        ``f_max``, ``onset``, ``f_min``, ``turning_point`` as in ``adhfit simulate --json``.
    inputs : dict
        The validated inputs (with the resolved ``a_max``).
    """

    frame: pd.DataFrame
    summary: dict
    inputs: dict

    def _repr_html_(self) -> str:  # notebooks
        s = self.summary
        return (f"<b>adhfit history</b> ({self.inputs.get('control')} control, {self.inputs.get('slip')}), "
                f"{len(self.frame)} rows; f_max = {s['f_max']:.6g}, f_min = {s['f_min']['f']:.6g}"
                + self.frame.head(5)._repr_html_())


def simulate(control: str, slip: str, *, p: float | None = None, d: float | None = None,
             w: float, rs: float, a_max: float | None = None, delta_max: float | None = None,
             p_max: float | None = None, lambda0: float = 2.0, points: int = 200,
             membrane: str = "large-stretch") -> SimulationResult:
    """Simulate a loading history in dimensionless groups (docs/contracts.md A1, A2b).

    Parameters
    ----------
    control : {"displacement", "pressure"}
        Displacement control at fixed pressure ``p`` or pressure control at fixed gap ``d``.
    slip : {"no-slip", "frictionless"}
        Interface condition during pinning and delamination.
    p : float, optional
        P b/(2 mu h), displacement control only, in (-1, 1) and > -b/R_s.
    d : float, optional
        Gap over b, pressure control only, in (-1, 1).
    w : float
        W_ad/(mu h), in (0, 10].
    rs : float
        R_s/b in [0.02, inf]; ``float("inf")`` for a flat substrate.
    a_max, delta_max, p_max : float, optional
        Exactly one: contact radius, displacement (displacement control) or pressure (pressure
        control) at the end of loading.
    lambda0 : float, default 2.0
        Pre-stretch; cancels from every observable under the large-stretch approximation.
    points : int, default 200
        Approximate number of rows, spread over the three stages.
    membrane : {"large-stretch", "exact"}, default "large-stretch"
        The paper's closed forms, or the exact neo-Hookean membrane (docs/contracts.md A6; lambda0 matters).

    Returns
    -------
    SimulationResult

    Examples
    --------
    >>> r = simulate("displacement", "no-slip", p=0.6, w=0.2, rs=0.5, a_max=0.25)
    >>> round(r.summary["f_max"], 4)
    0.5105
    """
    model = membranes.membrane(membrane)
    # one validation of every shared setting, from the one parameter table, whichever engine runs
    check_scene(control, slip, p=p, d=d, w=w, rs=rs, a_max=a_max, delta_max=delta_max, p_max=p_max,
                lambda0=lambda0, points=points)
    h = model.history(control, slip, p=p, d=d, w=w, rs=rs, a_max=a_max, delta_max=delta_max, p_max=p_max,
                      lambda0=lambda0, points=points)
    frame = pd.DataFrame({k: h.columns[k] for k in COLUMNS})
    return SimulationResult(frame=frame, summary=h.summary, inputs=h.inputs)


def _finite(x) -> bool:
    return x is None or (isinstance(x, float) and math.isfinite(x))
