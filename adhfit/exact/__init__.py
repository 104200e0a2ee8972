"""The exact incompressible neo-Hookean membrane (no large-stretch approximation).

``exact_history`` computes a full history with the docs/contracts.md A2 columns (what
``adhfit.simulate(..., membrane="exact")`` returns as a frame); ``free_inflation`` the free state.
Modules: ``kernels`` (compiled ODEs and integrator), ``state`` (one shot), ``newton`` and ``solve``
(Newton on the shooting unknowns), ``march`` (compiled continuation over many rows), ``stages`` (the
stage problems), ``control`` (inputs), ``inflation`` (free inflation), ``history``; ``jit`` keys the
numba cache of all of them on one hash of ``adhfit/exact``.
"""
from .history import exact_history
from .inflation import apex_deflection, free_inflation

__all__ = ["exact_history", "apex_deflection", "free_inflation"]
