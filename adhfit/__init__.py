"""adhfit: adhesion tests with an inflated elastic membrane.

Forward model (Yang, Srivastava & Long, large-stretch neo-Hookean membrane against a rigid sphere or
flat) and fits of the work of adhesion, the membrane stiffness and the interface slip condition.

``simulate`` works in the dimensionless groups of docs/contracts.md A1; ``simulate_scene`` takes a
:class:`Scene` in SI (``load_scene`` reads the TOML scene file).  ``read_curve`` reads a measured curve; ``fit`` fits one measured curve or a
test series, by least squares or MCMC, and returns a :class:`FitResult`.  ``plan`` predicts, before a
test is run, what the fit will find for candidate protocols (docs/planning.md) and returns a ``Plan``.
"""
from .errors import AdhfitError, ConvergenceError, DataError, InputError

__version__ = "0.1.0"
__all__ = ["fit", "FitResult", "read_curve", "simulate", "SimulationResult", "simulate_scene", "SceneResult", "Scene", "load_scene",
           "plan", "Plan", "AdhfitError", "InputError", "ConvergenceError", "DataError", "__version__"]

_LAZY = {"fit": ".fitting.api", "FitResult": ".fitting.result", "read_curve": ".data", "simulate": ".simulation", "SimulationResult": ".simulation", "simulate_scene": ".physical", "SceneResult": ".physical", "Scene": ".scene",
         "load_scene": ".scene", "plan": ".planning.api", "Plan": ".planning.api"}


def __getattr__(name: str):
    # numba, pandas, pint and lmfit are imported on first use, keeping 'import adhfit' light
    import importlib  # noqa: PLC0415
    if name in _LAZY:
        return getattr(importlib.import_module(_LAZY[name], __name__), name)
    if name in ("report", "fitting", "planning"):  # adhfit.report.write(...), adhfit.fitting.fit(...)
        return importlib.import_module(f".{name}", __name__)
    raise AttributeError(f"module 'adhfit' has no attribute {name!r}")
