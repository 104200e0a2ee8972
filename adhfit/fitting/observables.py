"""What a fit can measure besides the force: the registry of secondary observables.

The force is the primary observable: every curve has it, and its residual carries the row split and the
pull-off term (:func:`.lsq.residual_function`).  Every other measured column is an :class:`Observable`
in :data:`OBSERVABLES`, fitted as a block of its own, with its own noise level, wherever a curve has it:
its rows (:meth:`Observable.rows`), the model's value at those rows (:meth:`Observable.predict`) and a
robust noise estimate (:meth:`Observable.noise`).  Adding an observable is one entry here.

Contact radius along the history
    The model's a follows the same row-order history as the force: 0 before contact, the
    making-contact branch on loading, the pinned then delaminating branch on the way out (clamped at
    the turning point's a beyond it), 0 after detachment (with the force's attached weight, so a
    free split switches both together).  Rows where the column is NaN are *missing*: skipped and
    counted.  Rows where it is 0 are *measured as not in contact*: they are used, and they agree with
    the model before contact and after detachment.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from .starts import noise_estimate

__all__ = ["Observable", "ObservedRows", "OBSERVABLES", "PRIMARY", "contact_radius_model"]

#: the observable every curve has; its residual block is :func:`.lsq.residual_function`
PRIMARY = "force"


@dataclass(frozen=True)
class ObservedRows:
    """The usable rows of one secondary observable of one curve.

    Attributes
    ----------
    rows : ndarray of int
        Rows used (finite values; 0 = measured as not in contact).
    values : ndarray
        Measured values at those rows, SI.
    n_missing : int
        Rows skipped because the value is missing (NaN).
    n_zero : int
        Rows measured as 0 (used).
    """

    rows: np.ndarray
    values: np.ndarray
    n_missing: int
    n_zero: int


@dataclass(frozen=True)
class Observable:
    """One secondary observable: where its values are, what the model predicts, how noisy it is.

    Attributes
    ----------
    name : str
        Its key in report.json ``observables`` and the curves' entries.
    unit : str
        SI unit of its values.
    label : str
        Words for reports.
    read : callable
        ``curve -> ndarray or None``: the measured column (NaN = missing), SI.
    model : callable
        ``(CurveModel, W_ad, μh, x_offset) -> ndarray``: the model's value at every row of the curve.
        Raises :class:`~.model.ModelDomainError` outside the model's domain.
    min_nonzero : int
        Fewest nonzero rows for the column to be fitted.
    """

    name: str
    unit: str
    label: str
    read: Callable
    model: Callable
    min_nonzero: int = 3

    def rows(self, curve) -> ObservedRows | None:
        """The usable rows of ``curve``, or ``None`` when it has no usable column."""
        a = self.read(curve)
        if a is None:
            return None
        a = np.asarray(a, float)
        ok = np.isfinite(a)
        if np.count_nonzero(ok & (a != 0)) < self.min_nonzero:
            return None
        rows = np.flatnonzero(ok)
        return ObservedRows(rows=rows, values=a[rows], n_missing=int(np.count_nonzero(~ok)),
                            n_zero=int(np.count_nonzero(a[rows] == 0)))

    def predict(self, model, work_of_adhesion: float, mu_h: float, x_offset: float, rows: np.ndarray) -> np.ndarray:
        """The model's values at ``rows``."""
        return np.asarray(self.model(model, work_of_adhesion, mu_h, x_offset), float)[rows]

    @staticmethod
    def noise(values: np.ndarray) -> float:
        """Row-to-row noise from the nonzero rows only: rows measured as 0 (not in contact) have no
        noise, and their zero second differences would pull the robust estimate down (a 200-row curve
        with 22 such rows flagged its radius at χ²/n = 2 against its own model)."""
        v = np.asarray(values, float)
        return noise_estimate(v[v != 0])


def contact_radius_model(model, work_of_adhesion: float, mu_h: float, x_offset: float = 0.0) -> np.ndarray:
    """The model's contact radius (m) at every measured row of ``model``'s curve (module docstring)."""
    pcs = model.pieces(work_of_adhesion, mu_h, x_offset)
    xd = model.dimensionless_x(mu_h, x_offset)
    seg = model.segments
    n = xd.size
    loading = seg.loading
    attached = seg.attached if model.fixed_split else np.arange(n) > seg.i_turn
    a = np.zeros(n)
    a[loading] = pcs.a_loading(xd[loading])
    if attached.any():
        a[attached] = pcs.a_unloading(xd[attached]) * model.attached_weight(mu_h, x_offset, pcs)
    return a * model.scene.membrane_radius


#: every secondary observable, by name (report.json ``observables`` lists the force and those fitted)
OBSERVABLES: dict[str, Observable] = {
    "contact_radius": Observable(name="contact_radius", unit="m", label="contact radius",
                                 read=lambda curve: getattr(curve, "contact_radius", None),
                                 model=contact_radius_model),
}
