"""The joint model of a test series (issue 13, docs/contracts.md A7): several curves, one W_ad and one μh.

Every curve keeps its own :class:`~.model.CurveModel` (its own scene: its own pressure or gap) and its
own offsets, parametrised exactly as the single-curve fit does (:class:`~.lsq.Parametrisation`: the
control offset over the curve's control range, the load-cell zero over its largest force).  The joint
residual is the concatenation of the single-curve residuals (:func:`~.lsq.residual_function`, pull-off
term included), each in units of its own curve's noise σ_i, plus, where a curve has a
``contact_radius`` column, a second block (a_measured - a_model)/σ_a,i.

Contact radius along the history
    The model's a follows the same row-order history as the force: 0 before contact, the
    making-contact branch on loading, the pinned then delaminating branch on the way out (clamped at
    the turning point's a beyond it), 0 after detachment (with the force's attached weight, so a
    free split switches both together).  Rows where the column is NaN are *missing*: skipped and
    counted.  Rows where it is 0 are *measured as not in contact*: they are used, and they agree with
    the model before contact and after detachment.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import lmfit
import numpy as np

from .lsq import PENALTY, Parametrisation, residual_function
from .model import CurveModel, ModelDomainError

__all__ = ["RadiusData", "Member", "SeriesParametrisation", "radius_prediction", "radius_data",
           "series_residual", "Values"]


class Values(dict):
    """A dict that answers ``valuesdict()`` like lmfit Parameters (what :func:`residual_function` needs)."""

    def valuesdict(self) -> dict:
        return self


@dataclass(frozen=True)
class RadiusData:
    """The usable contact-radius rows of one curve.

    Attributes
    ----------
    rows : ndarray of int
        Rows used (finite values; 0 = measured as not in contact).
    values : ndarray
        Measured contact radius at those rows, m.
    n_missing : int
        Rows skipped because the value is missing (NaN).
    n_zero : int
        Rows measured as not in contact (value 0), used.
    """

    rows: np.ndarray
    values: np.ndarray
    n_missing: int
    n_zero: int


def radius_data(curve) -> RadiusData | None:
    """The contact-radius rows of a curve, or ``None`` when it has no usable column."""
    a = getattr(curve, "contact_radius", None)
    if a is None:
        return None
    a = np.asarray(a, float)
    ok = np.isfinite(a)
    if np.count_nonzero(ok & (a > 0)) < 3:
        return None
    rows = np.flatnonzero(ok)
    return RadiusData(rows=rows, values=a[rows], n_missing=int(np.count_nonzero(~ok)),
                      n_zero=int(np.count_nonzero(a[rows] == 0)))


def radius_prediction(model: CurveModel, work_of_adhesion: float, mu_h: float, x_offset: float = 0.0) -> np.ndarray:
    """The model's contact radius (m) at every measured row of ``model``'s curve.

    Raises
    ------
    ModelDomainError
        The parameters leave the model's domain.
    """
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


@dataclass
class Member:
    """One curve of a series: its force model, its parametrisation, its noise levels.

    Attributes
    ----------
    model : CurveModel
    par : Parametrisation
        The single-curve parametrisation (its offsets' scales).
    sigma_f : float
        Force noise σ_i, N (the residual scale of this curve's force block).
    radius : RadiusData or None
    sigma_a : float or None
        Contact-radius noise, m.
    label : str
    """

    model: CurveModel
    par: Parametrisation
    sigma_f: float
    radius: RadiusData | None = None
    sigma_a: float | None = None
    label: str = ""
    _residual: object = field(default=None, repr=False)

    def force_residual(self):
        """The single-curve residual closure of this member at its current σ_i."""
        if self._residual is None or self._residual[0] != self.sigma_f:
            self._residual = (self.sigma_f, residual_function(self.model, self.par, self.sigma_f, self.sigma_f))
        return self._residual[1]


@dataclass(frozen=True)
class SeriesParametrisation:
    """lmfit names of the joint fit: shared ``ln_work_of_adhesion``, ``ln_mu_h``; per curve i
    ``x_offset_i`` and ``force_offset_i`` (internal units of that curve's :class:`Parametrisation`)."""

    pars: tuple

    def member_values(self, v: dict, i: int) -> Values:
        """Internal values of curve i under the single-curve names."""
        out = Values(ln_work_of_adhesion=v["ln_work_of_adhesion"], ln_mu_h=v["ln_mu_h"])
        for name in ("x_offset", "force_offset"):
            if f"{name}_{i}" in v:
                out[name] = v[f"{name}_{i}"]
        return out

    def params(self, shared: dict, offsets: list[dict]) -> lmfit.Parameters:
        """lmfit Parameters from SI values: ``shared`` (W_ad, μh) and per-curve SI offsets
        (``x_offset``, ``force_offset``)."""
        p = lmfit.Parameters()
        for i, (par, off) in enumerate(zip(self.pars, offsets)):
            one = par.params({**shared, **off})
            if i == 0:
                for name in ("ln_work_of_adhesion", "ln_mu_h"):
                    q = one[name]
                    p.add(name, value=q.value, min=q.min, max=q.max)
            for name in ("x_offset", "force_offset"):
                if name in one:
                    q = one[name]
                    p.add(f"{name}_{i}", value=q.value, min=q.min, max=q.max)
        return p

    def si(self, params) -> tuple[dict, list[dict]]:
        """(shared SI values, per-curve SI offsets) of lmfit Parameters or a values dict."""
        v = {k: float(getattr(params[k], "value", params[k])) for k in params}
        per = [par.si(self.member_values(v, i)) for i, par in enumerate(self.pars)]
        shared = {"work_of_adhesion": per[0]["work_of_adhesion"], "mu_h": per[0]["mu_h"]}
        return shared, [{"x_offset": s["x_offset"], "force_offset": s["force_offset"]} for s in per]


def block_sizes(members: list[Member]) -> list[tuple[int, int]]:
    """(force block length incl. the pull-off term, contact-radius block length) per member."""
    return [(m.model.force.size + (m.model.jump is not None), 0 if m.radius is None else m.radius.rows.size)
            for m in members]


def series_residual(members: list[Member], spar: SeriesParametrisation):
    """The joint residual (params -> array): per curve its force block, then its contact-radius block."""
    sizes = block_sizes(members)

    def residual(params):
        v = params.valuesdict()
        out = []
        for i, (m, (nf, na)) in enumerate(zip(members, sizes)):
            sub = spar.member_values(v, i)
            rf = m.force_residual()(sub)
            out.append(rf)
            if not na:
                continue
            if np.all(rf == PENALTY):
                out.append(np.full(na, PENALTY))
                continue
            si = m.par.si(sub)
            try:
                a = radius_prediction(m.model, si["work_of_adhesion"], si["mu_h"], si["x_offset"])
                out.append((m.radius.values - a[m.radius.rows]) / m.sigma_a)
            except ModelDomainError:
                out.append(np.full(na, PENALTY))
        return np.concatenate(out)
    return residual


def split_blocks(r: np.ndarray, members: list[Member]) -> list[tuple[np.ndarray, np.ndarray]]:
    """Split a joint residual vector into per-member (force rows, contact-radius rows), without the
    pull-off term (in units of each block's σ)."""
    out, k = [], 0
    for m, (nf, na) in zip(members, block_sizes(members)):
        n = m.model.force.size
        out.append((r[k:k + n], r[k + nf:k + nf + na]))
        k += nf + na
    return out


def noise_floor(values: np.ndarray) -> float:
    """A last-resort noise level: 1e-3 of the largest magnitude (never 0)."""
    v = float(np.max(np.abs(values))) if np.size(values) else 1.0
    return 1e-3 * v if v > 0 else 1e-12


def finite_or(x: float, fallback: float) -> float:
    return x if (x is not None and math.isfinite(x) and x > 0) else fallback
