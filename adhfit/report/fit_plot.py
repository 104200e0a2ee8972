"""fit.png of any fit: one curve (the data, both fitted curves, the stages shaded, the residuals of the
reported fit) or a test series (every curve with the shared fit, normalised residuals, the contact radius).

Draws from a :class:`~adhfit.fitting.result.FitResult`'s stored predictions and model curves; never
re-runs a fit.  :func:`fit_view` extracts what the one-curve figure shows as plain JSON-ready data, and
:func:`draw_fit` draws from that alone, so that another process can draw it (``cli/painter.py``).  A
series is drawn from :func:`series_data` (the one place that reads the fit's stored series predictions).
Files are saved atomically (:func:`.files.save_figure`).
"""
from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from .plots import STAGE_COLORS, pyplot, file_figure, save
from .view import curve_label, estimate_text

__all__ = ["plot_fit", "fit_view", "draw_fit", "series_data", "plot_series"]


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
    names = {"work_of_adhesion": "W_ad", "mu_h": "μh"}
    lines = [f"{names.get(k, k)} = {estimate_text(k, v)}" for k, v in view["parameters"].items()
             if isinstance(v, dict)]
    lines.append(f"slip: {view['verdict']}")
    ax.text(0.98, 0.03, "\n".join(lines), transform=ax.transAxes, ha="right", va="bottom", fontsize=8, multialignment="left",
            bbox={"boxstyle": "round,pad=0.4", "fc": "white", "ec": "0.7", "alpha": 0.9})


def plot_fit(result, *, ax=None, path: str | Path | None = None, residuals: bool = True):
    """Plot a fit result: one curve, or every curve of a series with the shared fit.

    Parameters
    ----------
    result : FitResult
        A one-curve fit, or a series (``result.curves``: drawn by :func:`plot_series`).
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
    if result.curves:
        return plot_series(result, ax=ax, path=path, residuals=residuals)
    return draw_fit(fit_view(result), ax=ax, path=path, residuals=residuals)


def draw_fit(view: dict, *, ax=None, path: str | Path | None = None, residuals: bool = True):
    """Draw fit.png from :func:`fit_view`'s data (parameters as :func:`plot_fit`); returns the main axes."""
    kx, xlabel = _axis(view["control"])
    rax = None
    if ax is None:
        subplots = file_figure if path is not None else pyplot().subplots
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
        save(ax.figure, path)
    return ax


# ---------------------------------------------------------------- a test series
def series_data(result) -> list[dict]:
    """Per curve of a series: ``control``, ``x``, ``force``, ``predicted``, ``sigma_force`` and, when the
    contact radius was fitted, ``a``, ``a_rows``, ``a_predicted`` (SI), ``label``.

    The one accessor of the series predictions a global fit stores in ``result.raw["series_plot"]``.
    """
    return list(result.raw["series_plot"])


def _short(est) -> str:
    """``= 0.4012 [0.398, 0.404]``, ``≥ 0.35`` or ``not determined`` for the figure's title."""
    ci = est.ci95
    if est.status == "determined" and ci:
        return f"= {est.value:.4g} [{ci[0]:.4g}, {ci[1]:.4g}]"
    if est.status == "lower_bound" and ci:
        return f"≥ {ci[0]:.4g}"
    if est.status == "upper_bound" and ci:
        return f"≤ {ci[1]:.4g}"
    return "not determined"


def _series_curve(axes, k: int, d: dict, c: dict, color: str) -> None:
    from .curves import scene_text  # noqa: PLC0415
    kx, _ = _axis(d["control"])
    x = np.asarray(d["x"]) * kx
    name = f"{k + 1}: {curve_label(c.get('file', d.get('label')))}" + (f" ({scene_text(c)})" if c else "")
    axes[0].plot(x, np.asarray(d["force"]) * 1e3, ".", ms=2.5, color=color, alpha=0.6, label=name)
    axes[0].plot(x, np.asarray(d["predicted"]) * 1e3, "-", lw=1.1, color=color)
    if len(axes) > 1:
        axes[1].plot(x, (np.asarray(d["force"]) - np.asarray(d["predicted"])) / d["sigma_force"], ".", ms=2.5,
                     color=color, alpha=0.7)
    if "a" in d and len(axes) > 2:
        rows = np.asarray(d["a_rows"])
        axes[2].plot(x[rows], np.asarray(d["a"]) * 1e6, ".", ms=2.5, color=color, alpha=0.6)
        axes[2].plot(x, np.asarray(d["a_predicted"]) * 1e6, "-", lw=1.1, color=color)


def plot_series(result, *, ax=None, path: str | Path | None = None, residuals: bool = True):
    """Force of every curve with the shared fit, residuals in units of each curve's σ, and the contact radius
    (if fitted).  ``ax``: draw the force panel only, there.  Returns the force panel's axes."""
    data = series_data(result)
    radius = residuals and any("a" in d for d in data)
    if ax is None:
        n = 1 + residuals + radius
        subplots = file_figure if path is not None else pyplot().subplots
        _, axes = subplots(n, 1, figsize=(7.0, 3.0 * n), layout="constrained", sharex=True, squeeze=False,
                           gridspec_kw={"height_ratios": [3, 1.4, 2][:n]})
        axes = list(axes[:, 0])
    else:
        axes = [ax]
    colors = ["#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2", "#7f7f7f"]
    curves = list(result.curves) or [{}] * len(data)
    for k, (d, c) in enumerate(zip(data, curves)):
        _series_curve(axes, k, d, c, colors[k % len(colors)])
    p = result.parameters
    axes[0].set_title(f"shared fit ({result.method}): W_ad {_short(p['work_of_adhesion'])} J/m², "
                      f"μh {_short(p['mu_h'])} N/m\nslip: {result.slip['verdict']}", fontsize=9)
    axes[0].set_ylabel("force (mN)")
    axes[0].axhline(0.0, color="0.6", lw=0.6)
    axes[0].legend(fontsize=7)
    if len(axes) > 1:
        axes[1].axhline(0.0, color="0.6", lw=0.6)
        axes[1].set_ylabel("residual / σ of its curve", fontsize=8)
        for y in (-3.0, 3.0):
            axes[1].axhline(y, color="0.8", lw=0.5, ls="--")
    if radius:
        axes[2].set_ylabel("contact radius (µm)")
        axes[2].set_title("contact radius: dots measured, lines the shared fit", fontsize=8)
    axes[-1].set_xlabel(_axis(data[0]["control"])[1])
    if path is not None:
        save(axes[0].figure, path)
    return axes[0]
