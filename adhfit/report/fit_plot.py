"""fit.png: the data, both fitted curves, the stages shaded, and the residuals of the reported fit.

Draws from a :class:`~adhfit.fitting.result.FitResult`'s stored predictions and model curves; never
re-runs a fit.  :func:`fit_view` extracts what the figure shows as plain JSON-ready data, and
:func:`draw_fit` draws from that alone, so that another process can draw it (:mod:`.painter`).
"""
from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from .plots import STAGE_COLORS, _pyplot, file_figure

__all__ = ["plot_fit", "fit_view", "draw_fit"]


def _plain(x: Any) -> Any:
    """Arrays to lists and NaN to None, recursively (JSON-ready)."""
    if isinstance(x, dict) or hasattr(x, "items"):
        return {k: _plain(v) for k, v in x.items()}
    if isinstance(x, (list, tuple, np.ndarray)):
        return [_plain(v) for v in (x.tolist() if isinstance(x, np.ndarray) else x)]
    if isinstance(x, (float, np.floating)):
        return None if not np.isfinite(x) else float(x)
    if isinstance(x, np.integer):
        return int(x)
    return x


def fit_view(result) -> dict:
    """What fit.png shows, as JSON-ready data: the curve, the segments, each fit's model curve and
    predictions, the reported slip condition, the verdict and the fitted values."""
    d = result.as_dict()
    return _plain({"control": result.curve.control, "x": result.curve.x, "force": result.curve.force,
                   "segments": {k: result.segments[k] for k in ("i_turn", "i_jump")},
                   "fits": {s: {"model_curve": dict(f.model_curve), "predicted": f.predicted}
                            for s, f in result.fits.items()},
                   "reported_slip": result.reported_slip, "verdict": result.slip["verdict"],
                   "parameters": d.get("parameters") or {}})

_SLIP_STYLE = {"no-slip": ("k", "-"), "frictionless": ("#9467bd", "--")}


def _axis(control: str):
    return (1e6, "displacement (µm, measured)") if control == "displacement" else (1e-3, "pressure (kPa)")


def _shade(ax, curve: dict, kx: float) -> None:
    if not curve:
        return
    spans = (("making_contact", curve["x_contact"], curve["x_onset"]),
             ("pinning", curve["x_onset"], float(np.max(curve["x_loading"]))),
             ("delamination", curve["x_turning_point"], curve["x_onset"]))
    for name, lo, hi in spans[1:]:
        ax.axvspan(lo * kx, hi * kx, color=STAGE_COLORS[name], alpha=0.07, lw=0,
                   label=f"{name} (unloading)")
    ax.axvline(curve["x_contact"] * kx, color=STAGE_COLORS["making_contact"], lw=0.7, ls=":",
               label="contact (reported fit)")


def _main(ax, view: dict, kx: float) -> None:
    x, force = np.asarray(view["x"], float), np.asarray(view["force"], float)
    seg = view["segments"]
    n = len(x)
    idx = np.arange(n)
    load, det = idx <= seg["i_turn"], (idx >= seg["i_jump"]) if seg["i_jump"] is not None else np.zeros(n, bool)
    att = ~load & ~det
    for mask, color, label in ((load, "#1f77b4", "data: loading"), (att, "#d62728", "data: unloading"),
                               (det, "0.5", "data: after pull-off")):
        if mask.any():
            ax.plot(x[mask] * kx, force[mask] * 1e3, ".", ms=3, color=color, label=label)
    reported = view["reported_slip"]
    for slip, fit in view["fits"].items():
        mc = fit["model_curve"]
        if not mc:
            continue
        color, ls = _SLIP_STYLE.get(slip, ("k", "-"))
        ax.plot(np.asarray(mc["x_loading"]) * kx, np.asarray(mc["force_loading"]) * 1e3, ls, color=color, lw=1.1,
                label=f"fit: {slip}" + (" (reported)" if slip == reported else ""))
        ax.plot(np.asarray(mc["x_unloading"]) * kx, np.asarray(mc["force_unloading"]) * 1e3, ls, color=color, lw=1.1)
        ax.plot([mc["x_turning_point"] * kx] * 2, [mc["force_turning_point"] * 1e3, 0.0], ":", color=color, lw=0.8)
    _mark_extrema(ax, view["fits"][reported]["model_curve"], kx)
    _shade(ax, view["fits"][reported]["model_curve"], kx)
    ax.axhline(0.0, color="0.6", lw=0.6)
    ax.set_ylabel("force (mN, compressive positive)")
    ax.set_title(f"{view['verdict']}", fontsize=10)
    ax.legend(fontsize=7, ncol=2, loc="upper left")
    _values_box(ax, view)


def _mark_extrema(ax, mc, kx: float) -> None:
    """The reported fit's turning point (where the test jumps off) and f_min (most negative force)."""
    if not mc:
        return
    ax.plot([mc["x_turning_point"] * kx], [mc["force_turning_point"] * 1e3], "o", ms=5, mfc="none", color="k",
            label="turning point: the test jumps off")
    fu = np.asarray(mc["force_unloading"], float)
    if fu.size:
        i = int(np.nanargmin(fu))
        ax.plot([np.asarray(mc["x_unloading"], float)[i] * kx], [fu[i] * 1e3], "v", ms=5, color="k",
                label="f_min: most negative force (paper's pull-off force)")


def _values_box(ax, view: dict) -> None:
    """The fitted values with their 95 % intervals, written on the plot (lower right)."""
    from .text import estimate_text  # noqa: PLC0415
    names = {"work_of_adhesion": "W_ad", "mu_h": "μh"}
    lines = [f"{names.get(k, k)} = {estimate_text(k, v)}" for k, v in view["parameters"].items()
             if isinstance(v, dict)]
    lines.append(f"slip: {view['verdict']}")
    ax.text(0.98, 0.03, "\n".join(lines), transform=ax.transAxes, ha="right", va="bottom", fontsize=8, multialignment="left",
            bbox={"boxstyle": "round,pad=0.4", "fc": "white", "ec": "0.7", "alpha": 0.9})


def plot_fit(result, *, ax=None, path: str | Path | None = None, residuals: bool = True):
    """Plot a fit result.

    Parameters
    ----------
    result : FitResult
    ax : matplotlib Axes, optional
        Draw the main panel here (no residual panel); a new figure with a residual panel otherwise
        (a pyplot figure, shown in a notebook, unless ``path`` is given: then a figure of its own).
    path : path, optional
        Save the figure there.
    residuals : bool
        Add the residual panel (new figures only).

    Returns
    -------
    matplotlib.axes.Axes
        The main panel.
    """
    return draw_fit(fit_view(result), ax=ax, path=path, residuals=residuals)


def draw_fit(view: dict, *, ax=None, path: str | Path | None = None, residuals: bool = True):
    """Draw fit.png from :func:`fit_view`'s data (parameters as :func:`plot_fit`); returns the main axes."""
    kx, xlabel = _axis(view["control"])
    rax = None
    if ax is None:
        subplots = file_figure if path is not None else _pyplot().subplots
        if residuals:
            fig, (ax, rax) = subplots(2, 1, figsize=(7.0, 6.2), sharex=True, layout="constrained",
                                      gridspec_kw={"height_ratios": (3, 1)})
        else:
            fig, ax = subplots(figsize=(7.0, 4.6), layout="constrained")
    _main(ax, view, kx)
    if rax is not None:
        x, force = np.asarray(view["x"], float), np.asarray(view["force"], float)
        for slip, fit in view["fits"].items():
            color, _ = _SLIP_STYLE.get(slip, ("k", "-"))
            rax.plot(x * kx, (force - np.asarray(fit["predicted"], float)) * 1e3, ".", ms=2.5, color=color,
                     label=slip)
        rax.axhline(0.0, color="0.6", lw=0.6)
        rax.set_ylabel("residual (mN)")
        rax.set_xlabel(xlabel)
        rax.legend(fontsize=7)
    else:
        ax.set_xlabel(xlabel)
    if path is not None:
        ax.figure.savefig(path, dpi=130)
    return ax
