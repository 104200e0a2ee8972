"""The membrane models, one registry entry each (docs/contracts.md A6).

:data:`MEMBRANES` maps a model's name to its :class:`Membrane`: how to compute a history (every engine
returns the one :class:`~adhfit.histories.History`), what it is, and how to warm its kernels up.  A new
membrane model is one entry here: ``adhfit.simulate(..., membrane=NAME)``, the fit's model
(:class:`adhfit.fitting.model.CurveModel`) and the choice lists of the scene file, ``adhfit.fit`` and the
command line all find it by name.  Engines are imported on first use, so this module stays light.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

from .errors import InputError
from .histories import History

__all__ = ["Membrane", "MEMBRANES", "membrane", "membrane_choices", "AUTO"]

#: the fit's choice that picks a membrane model from the data (docs/contracts.md A6)
AUTO = "auto"


@dataclass(frozen=True)
class Membrane:
    """One membrane model.

    Attributes
    ----------
    name : str
    description : str
        One line for help texts and reports.
    history : callable
        ``(control, slip, *, p, d, w, rs, a_max, delta_max, p_max, lambda0, points, retry=True) -> History``,
        the dimensionless history (docs/contracts.md A1, A2); ``retry=False`` (a fit's evaluations) asks for
        one attempt, where the engine would retry on other row grids.
    uses_prestretch : bool
        Whether λ0 changes the observables (under the large-stretch approximation it cancels).
    """

    name: str
    description: str
    history: Callable[..., History]
    uses_prestretch: bool

    def __post_init__(self) -> None:
        if not self.name or not callable(self.history):
            raise ValueError(f"membrane {self.name!r}: a name and a history function are required")


def _large_stretch(control: str, slip: str, **kw) -> History:
    from .loading import history  # noqa: PLC0415 - the engine (numba) loads on first use
    return history(control, slip, **kw)


def _exact(control: str, slip: str, retry: bool = True, **kw) -> History:
    from .exact.history import exact_history  # noqa: PLC0415 - the exact model loads on demand
    return exact_history(control, slip, **kw)  # its one retry (a 4x finer delamination march) always runs


#: every membrane model, by name
MEMBRANES: dict[str, Membrane] = {
    "large-stretch": Membrane("large-stretch", "the paper's large-stretch neo-Hookean membrane (eq. 10), closed "
                              "forms", _large_stretch, uses_prestretch=False),
    "exact": Membrane("exact", "the incompressible neo-Hookean membrane without the large-stretch approximation, "
                      "shot from the apex", _exact, uses_prestretch=True),
}


def membrane_choices(*, auto: bool = True) -> tuple[str, ...]:
    """The membrane names a scene or a fit accepts (with ``auto`` for a fit)."""
    return ((AUTO,) if auto else ()) + tuple(MEMBRANES)


def membrane(name: str) -> Membrane:
    """The registry entry of ``name``; one clear error for an unknown name."""
    if name not in MEMBRANES:
        raise InputError("membrane", name, "one of " + ", ".join(map(repr, MEMBRANES)))
    return MEMBRANES[name]
