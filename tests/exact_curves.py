"""Measured-style curves made with the exact neo-Hookean membrane (for the exact-fit tests).

Built here, not with adhfit.synthetic: the history comes straight from
``adhfit.exact.exact_history`` (dense), the rows are placed like a test machine's (a constant
displacement step up to the end of loading, down past pull-off), the force is interpolated linearly
in the history (x on loading; u = sqrt(x - x_tp) on the way out, where dF/dx is infinite at the
turning point), zero before contact and after pull-off, plus Gaussian noise.
"""
from __future__ import annotations

import numpy as np

from adhfit.data import Curve
from adhfit.exact import exact_history
from adhfit.scene import Scene

B, RS, MU_H, W_AD, PRESSURE = 2e-3, 1e-3, 2.0, 0.4, 600.0  # p = P b / (2 μh) = 0.3; w = 0.2


GAP = 0.2 * B  # pressure control: the gap between the clamp plane and the substrate's apex


def scene(lambda0: float, membrane: str = "auto", pressure: float = PRESSURE, control: str = "displacement") -> Scene:
    """The test's scene (SI): b = 2 mm, R_s = 1 mm, P = 600 Pa under displacement control (or the gap
    ``GAP`` under pressure control)."""
    if control == "pressure":
        return Scene(membrane_radius=B, substrate_radius=RS, control="pressure", gap=GAP, prestretch=lambda0,
                     membrane_model=membrane)
    return Scene(membrane_radius=B, substrate_radius=RS, control="displacement", pressure=pressure,
                 prestretch=lambda0, membrane_model=membrane)


def exact_curve(lambda0: float, slip: str, *, noise: float, seed: int, rows: int = 240,
                delta_max: float = 0.25, pressure: float = PRESSURE, control: str = "displacement",
                pressure_max: float = 1500.0) -> tuple[Curve, dict]:
    """(curve, truth): loading to δ = delta_max·b (or, under pressure control at the gap ``GAP``, to
    P = ``pressure_max`` Pa), unloading past pull-off, force noise ``noise``·F_max."""
    if control == "pressure":
        h = exact_history("pressure", slip, d=GAP / B, w=W_AD / MU_H, rs=RS / B, lambda0=lambda0,
                          p_max=pressure_max * B / (2 * MU_H), points=600)
    else:
        h = exact_history("displacement", slip, p=pressure * B / (2 * MU_H), w=W_AD / MU_H, rs=RS / B,
                          lambda0=lambda0, delta_max=delta_max, points=600)
    c = h.columns
    stage, stable = np.asarray(c["stage"]), np.asarray(c["stable"], bool)
    x, f = np.asarray(c["delta" if control == "displacement" else "p"], float), np.asarray(c["f"], float)
    mc = np.flatnonzero(stage == "making_contact")
    back = np.concatenate([[mc[-1]], np.flatnonzero((stage != "making_contact") & stable)])
    xl, fl, xr, fr = x[mc], f[mc], x[back], f[back]
    x0, x1, x_tp = xl[0], xl[-1], xr[-1]
    start, stop = x0 - 0.08 * (x1 - x0), x_tp - 0.15 * (x1 - x_tp)
    step = ((x1 - start) + (x1 - stop)) / (rows - 1)
    up = np.linspace(start, x1, int(round((x1 - start) / step)) + 1)
    down = np.linspace(x1, stop, int(round((x1 - stop) / step)) + 1)[1:]
    u_r = np.sqrt(np.clip(xr - x_tp, 0, None))[::-1]
    f_up = np.where(up <= x0, 0.0, np.interp(up, xl, fl))
    f_down = np.where(down < x_tp, 0.0, np.interp(np.sqrt(np.clip(down - x_tp, 0, None)), u_r, fr[::-1]))
    scale = 2 * MU_H * B  # F = f · 2 μh b
    f_true = scale * np.concatenate([f_up, f_down])
    sigma = noise * scale * fl[-1]
    rng = np.random.default_rng(seed)
    force = f_true + rng.normal(0.0, sigma, f_true.size)
    if control == "pressure":
        xm = (2 * MU_H / B) * np.concatenate([up, down])  # P = p · 2 μh / b
    else:
        xm = B * np.concatenate([up, down]) - 5e-6  # measured displacement, offset 5 µm
    curve = Curve(path="<exact synthetic>", control=control, x=xm, force=force,
                  line=np.arange(2, xm.size + 2), i_turn=int(np.argmax(xm)))
    return curve, {"work_of_adhesion": W_AD, "mu_h": MU_H, "slip": slip, "sigma": sigma}
