"""Plots (the only place matplotlib is imported). Every function draws into a caller's ``ax`` or a
new figure, returns the axes, and writes a file only when given a path."""
from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["plot_history", "STAGE_COLORS", "file_figure", "pyplot", "save"]

STAGE_COLORS = {"making_contact": "#1f77b4", "pinning": "#2ca02c", "delamination": "#d62728"}


def pyplot():
    """``matplotlib.pyplot``, with the Agg backend unless a notebook chose one (plots shown in a notebook)."""
    import matplotlib  # noqa: PLC0415
    if matplotlib.get_backend().lower() not in ("agg", "module://matplotlib_inline.backend_inline"):
        try:
            import IPython  # noqa: F401, PLC0415
            in_notebook = IPython.get_ipython() is not None
        except ImportError:
            in_notebook = False
        if not in_notebook:
            matplotlib.use("Agg")
    import matplotlib.pyplot as plt  # noqa: PLC0415
    return plt


def file_figure(nrows: int = 1, ncols: int = 1, **subplots_kw: Any):
    """A new figure for a file, and its axes, without pyplot: (figure, axes as ``subplots`` returns).

    Report files need no figure manager: ``matplotlib.figure.Figure`` saves itself through the Agg
    canvas, is freed with its last reference (nothing to close) and spares the command line
    pyplot's import and backend selection (~0.4 s).  Notebook plots keep using pyplot.
    """
    from matplotlib.figure import Figure  # noqa: PLC0415
    fig = Figure(figsize=subplots_kw.pop("figsize", None), layout=subplots_kw.pop("layout", "constrained"))
    return fig, fig.subplots(nrows, ncols, **subplots_kw)


def save(fig: Any, path: Any, dpi: int = 130) -> None:
    """Save ``fig`` as PNG to ``path``: a file name atomically (:func:`.files.save_figure`), a binary stream
    (``io.BytesIO``) as it is."""
    if isinstance(path, (str, Path)):
        from .files import save_figure  # noqa: PLC0415
        save_figure(fig, path, dpi=dpi)
    else:
        fig.savefig(path, format="png", dpi=dpi)


def _scales_of(scene: Any):
    """The :class:`~adhfit.units.Scales` itself, of a SceneResult (attribute) or of a Scene (method)."""
    if hasattr(scene, "force") and hasattr(scene, "length"):
        return scene
    sc = scene.scales
    return sc if not callable(sc) else sc(None)


def _mark_extrema(ax, x: np.ndarray, f: np.ndarray, stable: np.ndarray) -> None:
    """The turning point (last stable row: a real test jumps off there) and f_min (most negative force)."""
    j = int(np.flatnonzero(stable)[-1])
    ax.plot([x[j]], [f[j]], "ko", ms=4, label="turning point (a real test jumps off here)")
    i_min = int(np.nanargmin(f))
    ax.plot([x[i_min]], [f[i_min]], "kv", ms=5, mfc="none", label="f_min (the paper's pull-off force)")


def plot_history(result: Any, *, scene: Any = None, ax=None, path: str | Path | None = None):
    """Force against the control variable, coloured by stage; the unstable branch dashed.

    Parameters
    ----------
    result : SimulationResult
        From :func:`adhfit.simulate`.
    scene : Scales, SceneResult or Scene, optional
        When given, axes are in physical units (mN against µm or kPa); else dimensionless.
    ax : matplotlib Axes, optional
        Draw here; a new figure otherwise.
    path : path, optional
        Save the figure there.

    Returns
    -------
    matplotlib.axes.Axes
    """
    plt = pyplot()
    if ax is None:
        _, ax = plt.subplots(figsize=(6.0, 4.2), layout="constrained")
    fr = result.frame
    control = result.inputs.get("control", "displacement")
    xkey = "delta" if control == "displacement" else "p"
    x, f = fr[xkey].to_numpy(float), fr["f"].to_numpy(float)
    xlabel, ylabel = ("δ/b" if xkey == "delta" else "Pb/2μh"), "F/(2μh b)"
    if scene is not None:
        sc = _scales_of(scene)
        if xkey == "delta":
            x, xlabel = x * sc.length * 1e6, "displacement δ (µm)"
        else:
            x, xlabel = x * sc.pressure * 1e-3, "pressure P (kPa)"
        f, ylabel = f * sc.force * 1e3, "force F (mN)"
    stage, stable = fr["stage"].to_numpy(), fr["stable"].to_numpy(bool)
    for name, color in STAGE_COLORS.items():
        for mask, style in ((stable, "-"), (~stable, "--")):
            m = (stage == name) & mask
            if not m.any():
                continue
            # include the previous row so stages join without gaps
            idx = np.flatnonzero(m)
            idx = np.unique(np.concatenate([idx, np.maximum(idx - 1, 0)])) if idx[0] > 0 else idx
            ax.plot(x[idx], f[idx], style, color=color,
                    label=name.replace("_", " ") + ("" if style == "-" else " (unstable)"))
    tp = result.summary["turning_point"]
    _mark_extrema(ax, x, f, stable)
    ax.axhline(0.0, color="0.6", lw=0.6)
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.set_title(f"{control} control, {result.inputs.get('slip')}" + ("" if tp else ""), fontsize=10)
    ax.legend(fontsize=8)
    if path is not None:
        save(ax.figure, path)
    return ax
