"""The ``adhfit`` command line (docs/contracts.md A2, A5, A7).

Thin: parse the arguments, call the library, write the files, print.  Only this package prints.

Modules: :mod:`.main` (the parser, ``adhfit simulate``, the entry point and its one-line errors),
:mod:`.arguments` (``adhfit fit``'s options), :mod:`.fit` (one curve, least squares or MCMC, and the
dispatch to the others), :mod:`.series` (``--global``), :mod:`.batch` (several curves: local processes
or a Dask cluster), :mod:`.writing` (the output folder, the summary lines), :mod:`.engine` (the first
run's compile notice, the warm-up and the running clock).  Every fit goes through :func:`adhfit.fit`
and every report through :func:`adhfit.report.write`.
"""
from .main import main, run

__all__ = ["main", "run"]
