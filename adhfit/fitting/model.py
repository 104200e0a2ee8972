"""The model of a measured curve: the predicted force at every measured row (docs/numerics.md B4).

A measured curve is a history: loading (the control variable rises to its largest value, row
``Curve.i_turn``), then unloading, possibly past pull-off.  The model follows the same history:

* **loading rows** (``0 .. i_turn``): zero force before contact (δ < 0 under displacement control,
  p < p_cr under pressure control), then the making-contact branch;
* **unloading rows** (after ``i_turn``): contact pinning then delamination down to the turning point
  of the control variable (least δ or least p), then the free membrane (zero force).  By default
  (**free split**) the model itself decides which rows are detached: a row is detached once the
  control value, in row order, has passed the model's turning point, with a linear ramp one row
  spacing wide so that χ² stays continuous (:meth:`CurveModel.attached_weight`).  Where pull-off
  happened is then weighed by the likelihood, not found by a threshold on the data: at 4 % force
  noise the jump is only 3–4 row-to-row noise steps high and a 6-σ detector missed it in 14 of 15
  curves, which biased W_ad by -30 % (docs/numerics.md B4).
* With a **fixed split** (``fixed_split=True``: the rows of ``segments``) the rows before the jump are
  attached; one beyond the model's turning point is given the turning-point force (a clamp that keeps
  the residual continuous), and the measured pull-off enters as one more residual: the probability
  that the model's turning point lies in the gap between the last attached and the first detached
  row (:attr:`CurveModel.jump`, a censored term, flat inside the gap).  The fit
  uses it as a second stage, at the row the free split found (:mod:`.lsq`): the free split's ramp
  would place pull-off to a fraction of a row when the jump is large against the noise.

:func:`segment` still finds the end of loading (``Curve.i_turn``, by **row order**, never by control
value: rows just before and just after the jump may share a displacement) and a detected jump (the
largest rise of the force toward zero after the most negative force, kept only when it is large
against the noise), which is now only a first guess for reports.

For each parameter set one history is computed as arrays (:func:`adhfit.loading.history`, or the
exact membrane's; no table), ``points`` rows ending the loading at the data's largest control value,
and the force is interpolated along its monotone pieces by compiled kernels (:mod:`adhfit.core.pieces`): making contact in the control variable x (δ/b or p), pinning and delamination in
u = sqrt(x - x_tp).  The force has an infinite slope dF/dx at the turning point x_tp but is smooth in
u (x - x_tp is quadratic in the branch's locator there), and the pinning/delamination kink at the
onset is a node of both pieces, so the piecewise-cubic (PCHIP) interpolants are accurate to ~1e-4 of
the largest force with 150 rows and move smoothly with the parameters: no row-picking step.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from .. import membranes
from ..errors import AdhfitError, InputError
from ..params import CONTROL_KEY, SLIP_CONDITIONS
from .options import DEFAULT_POINTS
from .segments import JUMP_FRACTION, JUMP_NOISE, Segments, detect_jump, segment  # noqa: F401 (re-exported)

__all__ = ["Segments", "segment", "detect_jump", "CurveModel", "Pieces", "ModelDomainError",
           "OFFSET_NAME", "DEFAULT_POINTS", "pieces_from_columns"]

#: dimensionless control variable of each control mode (docs/contracts.md A1)
#: name of the control-variable offset (a row of adhfit.params.FITTED) per control mode
OFFSET_NAME = {"displacement": "displacement_offset", "pressure": "pressure_offset"}
#: extra rows tried when a history fails (the engine's continuation can stall at one row count and
#: succeed at a neighbouring one; the interpolants differ by ~1e-4 of the force, far below the noise)
RETRY_POINTS = (0, 7, 19)
#: the pull-off gap's soft edge is its width over this (:attr:`CurveModel.jump`).  1: inside the gap -2 ln P
#: varies by 0.25 only (no pull to the middle); outside it rises like a Gaussian of the gap's width, 3.5x
#: softer than the old midpoint term.  A steep edge (width/8) let a misfit curve's pull-off dominate a
#: series fit (a 25 % stiffer membrane dragged the shared μh by 4 % and flagged every curve)
JUMP_SOFT = 1.0
class ModelDomainError(AdhfitError, ValueError):
    """The parameters leave the model's domain (the history cannot be computed)."""

    def __init__(self, message: str, params: dict) -> None:
        self.params = dict(params)
        super().__init__(f"{message} (at {', '.join(f'{k}={v:.6g}' for k, v in self.params.items())})")


# ----------------------------------------------------------------------------------------------
# interpolants of one computed history


@dataclass(frozen=True)
class Pieces:
    """The force along one dimensionless history as monotone pieces (x = δ/b or p; f = F/(2 μh b)).

    Built and evaluated by compiled kernels (:mod:`adhfit.core.pieces`): making contact as f(x),
    pinning and delamination as f(u), u = sqrt(x - x_tp), PCHIP through the history's own rows.

    Attributes
    ----------
    x_contact, x_max : float
        Control value where contact starts (0 or p_cr) and where loading ends.
    x_tp, f_tp : float
        The turning point (least x on the way out) and its force.
    x_onset : float
        Control value at the onset of delamination.
    loading : tuple of ndarray
        Nodes, values and slopes of f(x) on making contact.
    retraction : tuple
        Nodes, values, slopes and piece starts of f(u) on pinning and delamination.
    columns : dict of str -> ndarray
        The history itself (:attr:`adhfit.loading.History.columns`).
    counts : tuple of int
        Rows of making contact, pinning and delamination in ``columns``.
    key : str
        The control column, ``"delta"`` or ``"p"``.
    """

    x_contact: float
    x_max: float
    x_tp: float
    f_tp: float
    x_onset: float
    loading: tuple
    retraction: tuple
    columns: dict
    counts: tuple
    key: str

    @cached_property
    def _radius(self) -> tuple:
        """The contact radius a/b as pieces, like the force's (built on first use)."""
        k = _kernels()
        x = np.ascontiguousarray(self.columns[self.key], float)
        a = np.ascontiguousarray(self.columns["a"], float)
        tp_pos = int(np.count_nonzero(self.columns["stable"])) - 1
        *retraction, _, a_tp, _ = k.retraction_nodes(x, a, *self.counts, tp_pos)
        return k.loading_nodes(x, a, self.counts[0]), tuple(retraction), float(a_tp)

    def a_loading(self, x: np.ndarray) -> np.ndarray:
        """Contact radius a/b on loading: zero before contact."""
        nodes = self._radius[0]
        return np.maximum(_kernels().loading_values(*nodes, np.ascontiguousarray(x, float)), 0.0)

    def a_unloading(self, x: np.ndarray) -> np.ndarray:
        """Contact radius a/b on the way out while attached; the turning point's beyond it."""
        _, retraction, a_tp = self._radius
        out = _kernels().retraction_values(*retraction, self.x_tp, a_tp, np.ascontiguousarray(x, float))
        return np.maximum(out, 0.0)

    def f_loading(self, x: np.ndarray) -> np.ndarray:
        """Force on loading: zero before contact, making contact after (clamped at the end)."""
        return _kernels().loading_values(*self.loading, np.ascontiguousarray(x, float))

    def f_unloading(self, x: np.ndarray) -> np.ndarray:
        """Force on the way out while attached; clamped to the turning point beyond it."""
        return _kernels().retraction_values(*self.retraction, self.x_tp, self.f_tp,
                                            np.ascontiguousarray(x, float))


_PIECES = []


def _kernels():
    """:mod:`adhfit.core.pieces`, imported on first use (``import adhfit`` does not load numba)."""
    if not _PIECES:
        from ..core import pieces  # noqa: PLC0415 - compiled kernels load with the engine
        _PIECES.append(pieces)
    return _PIECES[0]


def stage_counts(columns: dict) -> tuple[int, int, int]:
    """Rows of making contact, pinning and delamination of a history's columns."""
    stage = np.asarray(columns["stage"])
    return tuple(int(np.count_nonzero(stage == s)) for s in ("making_contact", "pinning", "delamination"))


def pieces_from_columns(columns: dict, control: str, counts: tuple = ()) -> Pieces:
    """Build the force's pieces of one history (:attr:`adhfit.loading.History.columns`;
    ``counts``: its rows per stage, read from the ``stage`` column when not given)."""
    n_mc, n_pin, n_dl = counts or stage_counts(columns)
    key = CONTROL_KEY[control]
    x = np.ascontiguousarray(columns[key], float)
    f = np.ascontiguousarray(columns["f"], float)
    tp_pos = int(np.count_nonzero(columns["stable"])) - 1
    k = _kernels()
    loading = k.loading_nodes(x, f, n_mc)
    *retraction, x_tp, f_tp, x_onset = k.retraction_nodes(x, f, n_mc, n_pin, n_dl, tp_pos)
    return Pieces(x_contact=float(loading[0][0]), x_max=float(loading[0][-1]), x_tp=float(x_tp),
                  f_tp=float(f_tp), x_onset=float(x_onset), loading=loading,
                  retraction=tuple(retraction), columns=columns, counts=(n_mc, n_pin, n_dl), key=key)


def _moved(x: np.ndarray, pcs: Pieces, d_onset: float, d_tp: float) -> np.ndarray:
    """Where to read this model's unloading branch so that its onset of delamination and its turning point
    appear moved by ``d_onset`` and ``d_tp`` (the loading end fixed): the piecewise-linear map from the
    moved kinks to the model's own.  A pure shift where the kinks are not strictly ordered."""
    xm, on, tp = pcs.x_max, pcs.x_onset, pcs.x_tp
    if not (tp < on < xm and tp + d_tp < on + d_onset < xm):
        return x - d_tp
    return np.interp(x, [tp + d_tp, on + d_onset, xm], [tp, on, xm])  # beyond the fold: clamped there


# ----------------------------------------------------------------------------------------------
# the model


class CurveModel:
    """Predicted force (N) at every row of a measured curve, for one slip condition.

    Parameters
    ----------
    curve : adhfit.data.Curve
        The measured curve (SI).
    scene : adhfit.scene.Scene
        Geometry and the fixed pressure or gap; its μh, W_ad and loading end are ignored.
    slip : {"no-slip", "frictionless"}
    points : int
        Rows per computed history.
    segments : Segments, optional
        Row-order segments; found with :func:`segment` when not given.
    membrane : {"large-stretch", "exact"}
        The forward model (:func:`adhfit.simulate`'s ``membrane``); ``"exact"`` uses the scene's λ0.

    Notes
    -----
    The model counts its histories (:attr:`n_histories`) and predictions (:attr:`n_evaluations`); it
    keeps the last few histories, so a repeated parameter set costs nothing.  It is not thread-safe.
    """

    def __init__(self, curve, scene, slip: str, *, points: int = DEFAULT_POINTS,
                 segments: Segments | None = None, fixed_split: bool = False,
                 membrane: str = "large-stretch") -> None:
        if slip not in SLIP_CONDITIONS:
            raise InputError("slip", slip, "one of " + ", ".join(map(repr, SLIP_CONDITIONS)))
        if curve.control != scene.control:
            raise InputError("control", curve.control, f"'{scene.control}' (the scene's control mode)")
        self.curve, self.scene, self.slip, self.points = curve, scene, slip, int(points)
        self._engine = membranes.membrane(membrane)  # one clear error for an unknown model
        self.control, self.membrane = scene.control, membrane
        self.segments = segments if segments is not None else segment(curve)
        self.x = np.asarray(curve.x, float)
        self.force = np.asarray(curve.force, float)
        binning = getattr(curve, "binning", None)
        self._binning = binning
        # the loading end: the largest control value as measured (a thinned curve's bins average it away)
        self.x_max = float(self.x[self.segments.i_turn]) if binning is None else binning.x_max
        self._loading = self.segments.loading
        self.fixed_split = bool(fixed_split)
        # free split: every unloading row is attached or detached as the parameters say (see predict);
        # fixed split: the rows of ``segments`` (attached ones clamped beyond the turning point)
        self._attached = self.segments.attached if self.fixed_split else np.arange(self.x.size) > self.segments.i_turn
        self._run_min = np.minimum.accumulate(self.x[self._attached]) if self._attached.any() else self.x[:0]
        steps = np.abs(np.diff(self.x[self.segments.i_turn:]))
        steps = steps[steps > 0]
        self.spacing = float(np.median(steps)) if steps.size else 1e-9 * max(abs(self.x_max), 1e-30)
        self._cache: dict = {}
        self._scales_memo = None
        unit = scene.scales(1.0)  # groups that do not depend on μh, converted once
        self._fixed = {"control": self.control, "slip": slip, "rs": float(unit.to_rs(scene.substrate_radius)),
                       "lambda0": float(scene.prestretch)}
        if self.control == "pressure":
            self._fixed["d"] = float(unit.to_d(scene.gap))
        #: row order as a fraction of the test, 0 at the first row and 1 at the last (the drift's basis)
        rows = np.arange(self.x.size) if binning is None else binning.row
        self.row_fraction = rows / max((self.x.size if binning is None else binning.rows) - 1, 1)
        self.n_histories = 0
        self.n_evaluations = 0

    def groups(self, work_of_adhesion: float, mu_h: float, x_offset: float = 0.0) -> dict:
        """Keyword arguments of :func:`adhfit.simulate` for these parameters (loading end from data).

        The scene was converted once (:meth:`__init__`); here only the groups that scale with μh
        and W_ad are formed.  Their ranges are checked where the history is computed.
        """
        w, mu = float(work_of_adhesion), float(mu_h)
        if not (math.isfinite(w) and math.isfinite(mu) and w > 0.0 and mu > 0.0):
            raise ModelDomainError("work_of_adhesion and mu_h must be finite and positive",
                                   self._named(work_of_adhesion, mu_h, x_offset))
        sc = self._scales(mu)
        kw = dict(self._fixed)
        kw["w"] = w / sc.energy
        if self.control == "displacement":
            kw["p"] = self.scene.pressure / sc.pressure
            kw["delta_max"] = (self.x_max + x_offset) / sc.length
        else:
            kw["p_max"] = (self.x_max + x_offset) / sc.pressure
        return kw

    def _scales(self, mu_h: float):
        """The scene's :class:`~adhfit.units.Scales` at ``mu_h`` (the last one is kept)."""
        memo = self._scales_memo
        if memo is None or memo[0] != mu_h:
            memo = self._scales_memo = (mu_h, self.scene.scales(mu_h))
        return memo[1]

    def _named(self, w, mu, off) -> dict:
        return {"work_of_adhesion": float(w), "mu_h": float(mu), OFFSET_NAME[self.control]: float(off)}

    def pieces(self, work_of_adhesion: float, mu_h: float, x_offset: float = 0.0) -> Pieces:
        """The interpolants of the history for these parameters (cached)."""
        key = (float(work_of_adhesion), float(mu_h), float(x_offset))
        if key in self._cache:
            return self._cache[key]
        kw = self.groups(*key)
        pcs = None
        for extra in RETRY_POINTS:
            try:
                self.n_histories += 1
                h = self._history(kw, self.points + extra)
                pcs = pieces_from_columns(h.columns, self.control, getattr(h, "counts", ()))
                break
            except InputError as err:  # a group out of range: no other row count helps
                raise ModelDomainError(str(err), self._named(*key)) from None
            except (AdhfitError, ValueError, IndexError) as err:
                failure = err
        if pcs is None:
            raise ModelDomainError(f"no history: {failure}", self._named(*key)) from None
        if len(self._cache) >= 16:
            self._cache.pop(next(iter(self._cache)))
        self._cache[key] = pcs
        return pcs

    def split_before(self, j: int) -> CurveModel:
        """This model with the detachment fixed before row ``j``, sharing the histories computed so far (the
        split decides which rows are attached, not the history; an exact history is worth keeping)."""
        out = CurveModel(self.curve, self.scene, self.slip, points=self.points, fixed_split=True,
                         segments=self.segments.split_before(j, self.force), membrane=self.membrane)
        out._cache = self._cache
        out.n_histories, out.n_evaluations = self.n_histories, self.n_evaluations
        return out

    def _history(self, kw: dict, points: int):
        """One history as arrays (no table), from the membrane model's registry entry (one attempt: the
        fit retries on its own grids, :data:`RETRY_POINTS`)."""
        return self._engine.history(**kw, points=points, retry=False)

    def dimensionless_x(self, mu_h: float, x_offset: float, x: np.ndarray | None = None) -> np.ndarray:
        """The measured control values (or ``x``) as δ/b or p (with the offset)."""
        return ((self.x if x is None else x) + x_offset) * self._x_factor(float(mu_h))

    def _x_factor(self, mu_h: float) -> float:
        """Measured control value (m or Pa) -> its group (δ/b or p = P b/(2 μh))."""
        sc = self._scales(mu_h)
        return 1.0 / (sc.length if self.control == "displacement" else sc.pressure)

    def predict(self, work_of_adhesion: float, mu_h: float, x_offset: float = 0.0,
                force_offset: float = 0.0, force_drift: float = 0.0,
                unloading_shift: tuple[float, float] | None = None) -> np.ndarray:
        """Predicted force at every measured row, N (compressive positive).

        Parameters
        ----------
        work_of_adhesion : float
            W_ad, J/m^2.
        mu_h : float
            μh, N/m.
        x_offset : float
            Added to the measured control values: displacement offset (m) or pressure offset (Pa).
        force_offset : float
            Added to the predicted force (load-cell zero at the first row), N.
        force_drift : float
            A linear drift of the zero from the first row to the last, N (added in row order).
        unloading_shift : (float, float), optional
            Moves the unloading branch's kinks, the onset of delamination and the turning point, by these
            amounts in the control group (δ/b or p), the loading end staying put (the branch is read
            through the piecewise-linear map between them): the exact membrane's stand-in puts this
            model's kinks where the exact model has them (:mod:`.stand_in`).

        Raises
        ------
        ModelDomainError
            The parameters leave the model's domain.
        """
        self.n_evaluations += 1
        pcs = self.pieces(work_of_adhesion, mu_h, x_offset)
        xd = self.dimensionless_x(mu_h, x_offset)
        f = np.zeros(xd.shape)
        f[self._loading] = pcs.f_loading(xd[self._loading])
        xa = xd[self._attached]
        if unloading_shift is not None:
            xa = _moved(xa, pcs, *unloading_shift)
        f[self._attached] = pcs.f_unloading(xa)
        if not self.fixed_split:
            f[self._attached] *= self.attached_weight(mu_h, x_offset, pcs)
        out = f * self._scales(float(mu_h)).force + force_offset
        return out + force_drift * self.row_fraction if force_drift else out

    def attached_weight(self, mu_h: float, x_offset: float, pcs: Pieces) -> np.ndarray:
        """Weight (0 detached .. 1 attached) of every unloading row, from the model's turning point.

        A row is detached once the control value, in row order, has passed the model's turning point
        (the running minimum of the unloading control values is below x_tp): the row split follows
        from the parameters, not from a threshold on the data.  The switch is a linear ramp one row
        spacing wide, centred on x_tp (the jump happened somewhere between two rows), so that χ² is
        continuous in the parameters.
        """
        if self.fixed_split:
            return np.ones(int(self._attached.sum()))
        if not self._run_min.size:
            return self._run_min
        run = self.dimensionless_x(mu_h, x_offset, self._run_min)
        h = abs(self.spacing * self._x_factor(float(mu_h)))
        return np.clip(0.5 + (run - pcs.x_tp) / max(h, 1e-300), 0.0, 1.0)

    def split(self, work_of_adhesion: float, mu_h: float, x_offset: float = 0.0) -> int | None:
        """First detached row for these parameters (weight below 1/2), ``None`` when the data end
        before the model's pull-off."""
        if self.fixed_split:
            return self.segments.i_jump
        pcs = self.pieces(work_of_adhesion, mu_h, x_offset)
        wt = self.attached_weight(mu_h, x_offset, pcs)
        det = np.flatnonzero(wt < 0.5)
        return int(self.segments.i_turn + 1 + det[0]) if det.size else None

    @property
    def jump(self) -> tuple[float, float, float] | None:
        """Where the data place the pull-off, in measured units (fixed split only: with a free split the
        rows themselves carry it): ``(x_attached, x_detached, soft)``.

        The jump happened between the last attached row and the first detached row, anywhere in that
        gap: the model's turning point must lie in it, and the likelihood is the probability that it
        does (:func:`.lsq.pull_off_term`: nearly flat inside, rising outside), with a soft edge ``soft``
        (the gap's width) for the rows' own imprecision.  ``None`` when the data end before pull-off.
        """
        j = self.segments.i_jump
        if j is None or not self.fixed_split:
            return None
        x_a, x_d = float(self.x[j - 1]), float(self.x[j])
        b = self._binning
        if b is not None and b.gap is not None and j == b.i_jump:  # the gap between two rows as read
            x_a, x_d = b.gap
        return x_a, x_d, max(abs(x_a - x_d), 1e-12 * abs(self.x_max)) / JUMP_SOFT

    def turning_point(self, work_of_adhesion: float, mu_h: float, x_offset: float = 0.0) -> tuple[float, float]:
        """The model's turning point (pull-off) in measured units: (control value, force in N)."""
        pcs = self.pieces(work_of_adhesion, mu_h, x_offset)
        sc = self._scales(float(mu_h))
        x = sc.from_delta(pcs.x_tp) if self.control == "displacement" else sc.from_p(pcs.x_tp)
        return float(x) - x_offset, float(sc.from_f(pcs.f_tp))

    def near_turning_point(self, work_of_adhesion: float, mu_h: float, x_offset: float = 0.0,
                           fraction: float = 0.1) -> bool:
        """True when the optimum sits on the kink: an attached row lies beyond the model's turning point
        (clamped) or closer to it than ``fraction`` of the local row spacing.  The force's slope is
        infinite there, so the Jacobian (and the covariance) is fragile (docs/numerics.md B4)."""
        pcs = self.pieces(work_of_adhesion, mu_h, x_offset)
        xd = self.dimensionless_x(mu_h, x_offset)[self._attached]
        xd = xd[self.attached_weight(mu_h, x_offset, pcs) >= 0.5]
        if xd.size < 2:
            return False
        k = int(np.argmin(xd))
        spacing = float(np.median(np.abs(np.diff(xd))))
        return bool(xd[k] - pcs.x_tp < fraction * spacing)
