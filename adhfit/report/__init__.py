"""Reports of a fit: ``write`` puts every one of them into a folder (:mod:`.writer`).

report.json (:mod:`.json_report`), report.md (:mod:`.markdown`), report.html (:mod:`.html`), the
figures (:mod:`.fit_plot`, :mod:`.mcmc_plots`, :mod:`.series_plot`, :mod:`.plots`) and a batch's
summary page (:mod:`.summary_html`).  Reports read a :class:`~adhfit.fitting.result.FitResult`; they
never run a fit.
"""
from .writer import write

__all__ = ["write"]
