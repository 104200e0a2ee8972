"""adhfit: adhesion tests with an inflated elastic membrane.

Forward model (Yang, Srivastava & Long, large-stretch neo-Hookean membrane against a rigid sphere or
flat) and fits of the work of adhesion, the membrane stiffness and the interface slip condition.
"""
from .errors import AdhfitError, ConvergenceError, DataError, InputError
from .simulation import SimulationResult, simulate

__version__ = "0.1.0"
__all__ = ["simulate", "SimulationResult", "AdhfitError", "InputError", "ConvergenceError",
           "DataError", "__version__"]
