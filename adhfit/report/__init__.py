"""Reports of a fit: ``write`` puts every one of them into a folder (:mod:`.writer`).

Every report reads ONE report dictionary (report.json, :mod:`.json_report`), for one curve or a series,
least squares or MCMC: :mod:`.view` turns numbers into words with units, :mod:`.sections` (with
:mod:`.curves` and :mod:`.sampling`) builds the page's sections, and one writer per format renders them
(:mod:`.markdown`, :mod:`.html`).  Figures: :mod:`.fit_plot` (one curve or a series), :mod:`.mcmc_plots`,
on :mod:`.plots`; a batch's summary page: :mod:`.summary_html`, :mod:`.thumbnails`.  Files are written
atomically (:mod:`.files`).  Reports read a :class:`~adhfit.fitting.result.FitResult`; they never run a fit.
"""
from .writer import write

__all__ = ["write"]
