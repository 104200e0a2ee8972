"""``adhfit.report.write``: every report of a fit, into one folder, whatever the method.

One curve: ``report.json`` (docs/contracts.md A5/A5b), ``report.md``, ``report.html`` (one
self-contained page), ``plot_data.json`` (the data and the fitted curve, for a batch's summary page)
and ``fit.png``; an MCMC fit adds ``fit_mcmc.png`` (posterior-predictive band) and ``corner.png``.
A test series (a result with ``curves``): ``report.json`` with ``curves``, ``report.md``,
``report.html`` and ``fit.png`` (every curve with the shared fit).
"""
from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

__all__ = ["write"]


def write(result: Any, outdir: str | Path, *, plot: bool = True, extra: Mapping[str, Any] | None = None,
          drawn: tuple[str, ...] = ()) -> list[Path]:
    """Write the reports of ``result`` (a :class:`~adhfit.fitting.result.FitResult`) into ``outdir``.

    Parameters
    ----------
    result : FitResult
    outdir : path
        Created if missing.
    plot : bool
        Draw the figures (``fit.png``, and for MCMC ``fit_mcmc.png`` and ``corner.png``).
    extra : mapping, optional
        More top-level keys for ``report.json`` and the page (e.g. ``engine_startup_s``).
    drawn : tuple of str
        Figures already saved in ``outdir`` (e.g. ``("fit.png",)`` drawn by another process): used as
        they are, not drawn again.

    Returns
    -------
    list of Path
        The files written.
    """
    out = Path(outdir)
    out.mkdir(parents=True, exist_ok=True)
    if result.curves:
        return _write_series(result, out, plot)
    from .html import write_html  # noqa: PLC0415
    from .json_report import write_json  # noqa: PLC0415
    from .markdown import write_markdown  # noqa: PLC0415
    from .summary_html import write_plot_data  # noqa: PLC0415
    written = [out / "report.json", out / "report.md", out / "plot_data.json"]
    write_json(result, written[0], extra=extra)
    write_markdown(result, written[1])
    write_plot_data(result, written[2])
    figures = _figures(result, out, drawn) if plot else {}
    write_html(result, out / "report.html", images=figures, extra=extra)
    return written + [out / "report.html"] + list(figures.values())


def _figures(result: Any, out: Path, drawn: tuple[str, ...]) -> dict[str, Path]:
    """fit.png, and an MCMC fit's fit_mcmc.png and corner.png: name -> path."""
    if "fit.png" not in drawn:
        from .fit_plot import plot_fit  # noqa: PLC0415
        plot_fit(result, path=out / "fit.png")
    figures = {"fit.png": out / "fit.png"}
    if result.sampling:
        from .mcmc_plots import plot_corner, plot_predictive  # noqa: PLC0415
        plot_predictive(result, path=out / "fit_mcmc.png")
        plot_corner(result, path=out / "corner.png")
        figures |= {name: out / name for name in ("fit_mcmc.png", "corner.png")}
    return figures


#: the caption of a series' figure in its report.html
_SERIES_CAPTION = ("Every curve (dots) with the shared fit (lines); below, each curve's residuals in units of its own "
                   "noise σ (dashed: ±3), and the contact radius when it was fitted")


def _write_series(result: Any, out: Path, plot: bool) -> list[Path]:
    """report.json (with ``curves``), then report.md and report.html from exactly what report.json says,
    and fit.png (every curve with the shared fit) embedded in the page."""
    import json  # noqa: PLC0415
    from .json_report import write_json  # noqa: PLC0415
    from .series_html import write_series_html  # noqa: PLC0415
    from .series_markdown import write_series_markdown  # noqa: PLC0415
    written = [out / "report.json", out / "report.md", out / "report.html"]
    write_json(result, written[0])
    d = json.loads(written[0].read_text(encoding="utf-8"))
    write_series_markdown(d, written[1])
    images = {}
    if plot:
        from .series_plot import plot_series  # noqa: PLC0415
        plot_series(result, path=out / "fit.png")
        images = {_SERIES_CAPTION: out / "fit.png"}
        written.append(out / "fit.png")
    write_series_html(d, written[2], images=images)
    return written
