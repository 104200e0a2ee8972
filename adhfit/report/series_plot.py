"""fit.png of a global fit (issue 13): every curve with the shared fit and its residuals.

Draws from the stored predictions of a :class:`~adhfit.fitting.result.FitResult` with ``curves``
(``raw["series_plot"]``); never re-runs a fit.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from .plots import _pyplot
from .series_text import curve_label, scene_text

__all__ = ["plot_series", "series_markdown", "write_series_markdown"]

from .series_markdown import series_markdown, write_series_markdown  # noqa: E402 - the old import path


def _kx(control: str) -> tuple[float, str]:
    return (1e6, "displacement (µm, measured)") if control == "displacement" else (1e-3, "pressure (kPa)")


def _short(e) -> str:
    """``= 0.4012 [0.398, 0.404]``, ``≥ 0.35`` or ``not determined`` for the figure's title."""
    if e.status == "determined" and e.ci95:
        return f"= {e.value:.4g} [{e.ci95[0]:.4g}, {e.ci95[1]:.4g}]"
    if e.status == "lower_bound" and e.ci95:
        return f"≥ {e.ci95[0]:.4g}"
    if e.status == "upper_bound" and e.ci95:
        return f"≤ {e.ci95[1]:.4g}"
    return "not determined"


def plot_series(result, *, path: str | Path | None = None):
    """Force of every curve with the shared fit, normalised residuals, and the contact radius (if fitted).

    Returns the matplotlib Figure.
    """
    plt = _pyplot()
    data = result.raw["series_plot"]
    radius = any("a" in d for d in data)
    n_rows = 3 if radius else 2
    fig, axes = plt.subplots(n_rows, 1, figsize=(7.0, 3.0 * n_rows), layout="constrained", sharex=True,
                             gridspec_kw={"height_ratios": [3, 1.4] + ([2] if radius else [])})
    kx, xlabel = _kx(data[0]["control"])
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    curves = list(result.curves) or [{}] * len(data)
    for k, (d, c) in enumerate(zip(data, curves)):
        col = colors[k % len(colors)]
        x = np.asarray(d["x"]) * kx
        name = f"{k + 1}: {curve_label(c.get('file', d['label']))}" + (f" ({scene_text(c)})" if c else "")
        axes[0].plot(x, np.asarray(d["force"]) * 1e3, ".", ms=2.5, color=col, alpha=0.6, label=name)
        axes[0].plot(x, np.asarray(d["predicted"]) * 1e3, "-", lw=1.1, color=col)
        axes[1].plot(x, (np.asarray(d["force"]) - np.asarray(d["predicted"])) / d["sigma_force"], ".", ms=2.5,
                     color=col, alpha=0.7)
        if "a" in d:
            rows = np.asarray(d["a_rows"])
            axes[2].plot(x[rows], np.asarray(d["a"]) * 1e6, ".", ms=2.5, color=col, alpha=0.6)
            axes[2].plot(x, np.asarray(d["a_predicted"]) * 1e6, "-", lw=1.1, color=col)
    p = result.parameters
    w, mu = p["work_of_adhesion"], p["mu_h"]
    axes[0].set_title(f"shared fit ({result.method}): W_ad {_short(w)} J/m², μh {_short(mu)} N/m\n"
                      f"slip: {result.slip['verdict']}", fontsize=9)
    axes[0].set_ylabel("force (mN)")
    axes[0].axhline(0.0, color="0.6", lw=0.6)
    axes[0].legend(fontsize=7)
    axes[1].axhline(0.0, color="0.6", lw=0.6)
    axes[1].set_ylabel("residual / σ of its curve", fontsize=8)
    for y in (-3.0, 3.0):
        axes[1].axhline(y, color="0.8", lw=0.5, ls="--")
    if radius:
        axes[2].set_ylabel("contact radius (µm)")
        axes[2].set_title("contact radius: dots measured, lines the shared fit", fontsize=8)
    axes[-1].set_xlabel(xlabel)
    if path is not None:
        fig.savefig(path, dpi=130)
        plt.close(fig)
    return fig
