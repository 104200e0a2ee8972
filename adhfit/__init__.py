"""adhfit: adhesion tests with an inflated elastic membrane.

Forward model (Yang, Srivastava & Long, large-stretch neo-Hookean membrane against a rigid sphere or
flat) and fits of the work of adhesion, the membrane stiffness and the interface slip condition.

``simulate`` works in the dimensionless groups of docs/contracts.md A1; ``simulate_scene`` takes a
:class:`Scene` in SI (``load_scene`` reads the TOML scene file).
"""
from .errors import AdhfitError, ConvergenceError, DataError, InputError

__version__ = "0.1.0"
__all__ = ["simulate", "SimulationResult", "simulate_scene", "SceneResult", "Scene", "load_scene",
           "AdhfitError", "InputError", "ConvergenceError", "DataError", "__version__"]

_LAZY = {"simulate": ".simulation", "SimulationResult": ".simulation", "simulate_scene": ".physical", "SceneResult": ".physical", "Scene": ".scene",
         "load_scene": ".scene"}


def __getattr__(name: str):
    # pandas (simulation) and pint (units) are imported on first use, keeping 'import adhfit' light
    if name in _LAZY:
        import importlib  # noqa: PLC0415
        return getattr(importlib.import_module(_LAZY[name], __name__), name)
    raise AttributeError(f"module 'adhfit' has no attribute {name!r}")
