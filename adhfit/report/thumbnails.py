"""A batch's small figure of each curve (the data and the reported fit), drawn where the curve was fitted.

summary.html shows every curve of a batch.  Drawn as one many-panel figure by the submitting process
after the last fit, the panels cost about 0.07 s each, one after the other, at the very end of the run
(most of a second for eight curves, minutes for a thousand), while every worker idles.  Drawn by the
job that fitted the curve (:func:`write_thumbnail`, called by the batch runner), they cost the same
but run on every core or cluster worker; the summary page only embeds them
(:func:`thumbnail_png` falls back to drawing from ``plot_data.json`` when a folder has none).
"""
from __future__ import annotations

import json
from pathlib import Path
from typing import Any, Mapping

import numpy as np

from .files import write_bytes
from .plots import file_figure

__all__ = ["THUMBNAIL", "draw_thumbnail", "write_thumbnail", "thumbnail_png"]

#: the file name of a curve's small figure, next to its report.json
THUMBNAIL = "thumbnail.png"
#: inches (width, height) and dots per inch: four to a row on a wide summary page
_SIZE, _DPI = (2.7, 2.1), 110


def draw_thumbnail(plot: Mapping[str, Any], path: str | Path | None = None) -> bytes:
    """A small figure of ``plot`` (the content of ``plot_data.json``): the data (dots) and the reported
    fit (lines), force in mN against the displacement in µm or the pressure in kPa.

    Parameters
    ----------
    plot : mapping
        ``control``, ``x``, ``force`` and optionally ``model`` (``x_loading``, ``force_loading``,
        ``x_unloading``, ``force_unloading``), in SI.
    path : path, optional
        Also save the PNG there.

    Returns
    -------
    bytes
        The PNG.
    """
    import io  # noqa: PLC0415
    displacement = plot.get("control") == "displacement"
    kx = 1e6 if displacement else 1e-3
    # fixed margins: a layout engine would cost as much again as the drawing
    fig, ax = file_figure(figsize=_SIZE, layout=None)
    fig.subplots_adjust(left=0.2, right=0.97, bottom=0.2, top=0.96)
    ax.tick_params(labelsize=6)
    ax.plot(_floats(plot["x"]) * kx, _floats(plot["force"]) * 1e3, ".", ms=2, color="#1f77b4", alpha=0.6)
    model = plot.get("model") or {}
    for part in ("loading", "unloading"):
        if f"x_{part}" in model:
            ax.plot(_floats(model[f"x_{part}"]) * kx, _floats(model[f"force_{part}"]) * 1e3, "-", color="#d62728",
                    lw=0.9)
    ax.axhline(0.0, color="0.7", lw=0.5)
    ax.set_xlabel("displacement (µm)" if displacement else "pressure (kPa)", fontsize=7, labelpad=1)
    ax.set_ylabel("force (mN)", fontsize=7, labelpad=1)
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=_DPI)
    png = buf.getvalue()
    if path is not None:
        write_bytes(path, png)
    return png


def _floats(values: Any) -> np.ndarray:
    """A JSON list (``null`` for a missing value) as floats (NaN, which matplotlib leaves out)."""
    return np.array([np.nan if v is None else v for v in values], dtype=float)


def _plot_data(folder: Path) -> dict | None:
    try:
        return json.loads((folder / "plot_data.json").read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None


def write_thumbnail(folder: str | Path) -> Path | None:
    """Draw ``folder/thumbnail.png`` from ``folder/plot_data.json`` (written by :func:`adhfit.report.write`);
    None when the folder holds no plot data."""
    folder = Path(folder)
    plot = _plot_data(folder)
    if not plot:
        return None
    draw_thumbnail(plot, folder / THUMBNAIL)
    return folder / THUMBNAIL


def thumbnail_png(folder: str | Path) -> bytes | None:
    """The curve's small figure: ``thumbnail.png`` when its job drew it after the fit that wrote
    ``plot_data.json`` (an older one, e.g. left by an earlier run with figures, is not used), else
    drawn now from ``plot_data.json``; None when the folder holds neither."""
    folder = Path(folder)
    png, data = folder / THUMBNAIL, folder / "plot_data.json"
    try:
        if not data.exists() or png.stat().st_mtime_ns >= data.stat().st_mtime_ns:
            return png.read_bytes()
    except OSError:
        pass
    plot = _plot_data(folder)
    return draw_thumbnail(plot) if plot else None
