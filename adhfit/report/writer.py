"""``adhfit.report.write``: every report of a fit, into one folder, whatever the method, one curve or many.

``report.json`` (docs/contracts.md A5/A5b/A7) is built once (:func:`.json_report.report_dict`); report.md
and report.html render that one dictionary (:func:`.sections.build_view`).  Figures: ``fit.png`` (one curve,
or every curve of a series with the shared fit); an MCMC fit adds ``corner.png`` (the posterior of the
reported slip condition) and, for one curve, ``fit_mcmc.png`` (posterior-predictive band); one curve also
writes ``plot_data.json`` (the data and the fitted curve, for a batch's summary page).  Every file is
written atomically (:mod:`.files`).
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
        One curve or a series (``result.curves``), least squares or MCMC (``result.sampling``).
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
    from .html import write_html  # noqa: PLC0415
    from .files import write_text  # noqa: PLC0415
    from .json_report import dumps, report_dict  # noqa: PLC0415
    from .markdown import write_markdown  # noqa: PLC0415
    out = Path(outdir)
    out.mkdir(parents=True, exist_ok=True)
    d = report_dict(result, extra)
    written = [write_text(out / "report.json", dumps(d))]
    if not result.curves:
        from .summary_html import write_plot_data  # noqa: PLC0415
        if write_plot_data(result, out / "plot_data.json") is not None:
            written.append(out / "plot_data.json")
    figures = _figures(result, out, drawn) if plot else {}
    written += [write_markdown(d, out / "report.md", figures=tuple(figures)),
                write_html(d, out / "report.html", images=figures)]
    return written + list(figures.values())


def _figures(result: Any, out: Path, drawn: tuple[str, ...]) -> dict[str, Path]:
    """fit.png, and an MCMC fit's corner.png (one curve: also fit_mcmc.png): name -> path."""
    if "fit.png" not in drawn:
        from .fit_plot import plot_fit  # noqa: PLC0415
        plot_fit(result, path=out / "fit.png")
    figures = {"fit.png": out / "fit.png"}
    if result.sampling and not result.curves and result.predictive:
        from .mcmc_plots import plot_predictive  # noqa: PLC0415
        plot_predictive(result, path=out / "fit_mcmc.png")
        figures["fit_mcmc.png"] = out / "fit_mcmc.png"
    if result.sampling and result.samples:
        from .mcmc_plots import plot_corner  # noqa: PLC0415
        plot_corner(result, path=out / "corner.png")
        figures["corner.png"] = out / "corner.png"
    return figures
