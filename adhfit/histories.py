"""The one result type of a forward history, whichever membrane model computed it.

Both engines (the large-stretch closed forms, :mod:`adhfit.loading`; the exact membrane,
:mod:`adhfit.exact`) return a :class:`History`; :data:`adhfit.membranes.MEMBRANES` finds them by name.
"""
from __future__ import annotations

from dataclasses import dataclass, field

__all__ = ["History"]


@dataclass(frozen=True)
class History:
    """A dimensionless loading history (docs/contracts.md A2).

    Attributes
    ----------
    columns : dict of str -> ndarray
        ``stage`` (str array) and ``a, alpha, p, d, delta, f, G`` (float; ``delta`` NaN where
        |p| > 1) and ``stable`` (bool), in history order.
    summary : dict
        ``f_max``, ``onset``, ``f_min``, ``turning_point`` (docs/contracts.md A2 ``--json``).
    inputs : dict
        The validated inputs, with the resolved ``a_max``.
    counts : tuple of int
        Rows of making contact (with the free-inflation row), pinning and delamination; empty when
        not known (read the ``stage`` column).
    states : list
        The engine's solved states row by row, where it keeps them (the exact membrane's shooting
        states, for profiles and checks); empty otherwise.
    """

    columns: dict
    summary: dict
    inputs: dict = field(default_factory=dict)
    counts: tuple = ()
    states: list = field(default_factory=list, repr=False)
