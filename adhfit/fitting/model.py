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
  the residual continuous), and the measured pull-off position enters as one more residual
  (:attr:`CurveModel.jump`, σ = spacing/√12: the jump happened somewhere between two rows).  The fit
  uses it as a second stage, at the row the free split found (:mod:`.lsq`): the free split's ramp
  would place pull-off to a fraction of a row when the jump is large against the noise.

:func:`segment` still finds the end of loading (``Curve.i_turn``, by **row order**, never by control
value: rows just before and just after the jump may share a displacement) and a detected jump (the
largest rise of the force toward zero after the most negative force, kept only when it is large
against the noise), which is now only a first guess for reports.

For each parameter set one history is computed with :func:`adhfit.simulate` (``points`` rows), ending
the loading at the data's largest control value, and the force is interpolated along its monotone
pieces: making contact in the control variable x (δ/b or p), pinning and delamination in
u = sqrt(x - x_tp).  The force has an infinite slope dF/dx at the turning point x_tp but is smooth in
u (x - x_tp is quadratic in the branch's locator there), and the pinning/delamination kink at the
onset is a node of both pieces, so the piecewise-cubic (PCHIP) interpolants are accurate to ~1e-4 of
the largest force with 150 rows and move smoothly with the parameters: no row-picking step.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.interpolate import PchipInterpolator

from ..errors import AdhfitError, InputError
from ..simulation import simulate
from .options import DEFAULT_POINTS
from .segments import JUMP_FRACTION, JUMP_NOISE, Segments, detect_jump, segment  # noqa: F401 (re-exported)

__all__ = ["Segments", "segment", "detect_jump", "CurveModel", "Pieces", "ModelDomainError",
           "CONTROL_KEY", "OFFSET_NAME", "DEFAULT_POINTS"]

#: dimensionless control variable of each control mode (docs/contracts.md A1)
CONTROL_KEY = {"displacement": "delta", "pressure": "p"}
#: name of the control-variable offset (a row of adhfit.params.FITTED) per control mode
OFFSET_NAME = {"displacement": "displacement_offset", "pressure": "pressure_offset"}
#: extra rows tried when a history fails (the engine's continuation can stall at one row count and
#: succeed at a neighbouring one; the interpolants differ by ~1e-4 of the force, far below the noise)
RETRY_POINTS = (0, 7, 19)
class ModelDomainError(AdhfitError, ValueError):
    """The parameters leave the model's domain (the history cannot be computed)."""

    def __init__(self, message: str, params: dict) -> None:
        self.params = dict(params)
        super().__init__(f"{message} (at {', '.join(f'{k}={v:.6g}' for k, v in self.params.items())})")


# ----------------------------------------------------------------------------------------------
# interpolants of one computed history


@dataclass(frozen=True)
class Pieces:
    """Interpolants of one dimensionless history (x = δ/b or p; f = F/(2 μh b)).

    Attributes
    ----------
    x_contact, x_max : float
        Control value where contact starts (0 or p_cr) and where loading ends.
    x_tp, f_tp : float
        The turning point (least x on the way out) and its force.
    x_onset : float
        Control value at the onset of delamination.
    loading : PchipInterpolator
        f(x) on making contact, x in [x_contact, x_max].
    retraction : list of (u_lo, u_hi, PchipInterpolator)
        f(u), u = sqrt(x - x_tp), one piece per stage (pinning, delamination).
    frame : pandas.DataFrame
        The history itself (for plots and reports).
    """

    x_contact: float
    x_max: float
    x_tp: float
    f_tp: float
    x_onset: float
    loading: PchipInterpolator
    retraction: list
    frame: object

    def f_loading(self, x: np.ndarray) -> np.ndarray:
        """Force on loading: zero before contact, making contact after."""
        xc = np.clip(x, self.x_contact, self.x_max)
        return np.where(x <= self.x_contact, 0.0, self.loading(xc))

    def f_unloading(self, x: np.ndarray) -> np.ndarray:
        """Force on the way out while attached; clamped to the turning point beyond it."""
        u = np.sqrt(np.clip(x - self.x_tp, 0.0, None))
        out = np.full(u.shape, self.f_tp)
        for lo, hi, interp in self.retraction:
            m = (u >= lo) & (u <= hi)
            out[m] = interp(u[m])
        top = self.retraction[-1][1] if self.retraction else 0.0
        if self.retraction:
            out[u > top] = self.retraction[-1][2](top)
        return out


def _piece(x: np.ndarray, f: np.ndarray, x_tp: float):
    """(u_lo, u_hi, interpolant) of f against u = sqrt(x - x_tp) over rows in history order."""
    u = np.sqrt(np.clip(x - x_tp, 0.0, None))[::-1]
    f = f[::-1]
    keep = np.concatenate([[True], np.diff(u) > 0])
    u, f = u[keep], f[keep]
    if u.size < 2:
        return None
    return float(u[0]), float(u[-1]), PchipInterpolator(u, f, extrapolate=True)


def pieces_from_frame(frame, control: str) -> Pieces:
    """Build the interpolants of one history frame (:func:`adhfit.simulate` output)."""
    key = CONTROL_KEY[control]
    stage = frame["stage"].to_numpy()
    stable = frame["stable"].to_numpy(bool)
    x, f = frame[key].to_numpy(float), frame["f"].to_numpy(float)
    mc = np.flatnonzero(stage == "making_contact")
    xl, fl = x[mc], f[mc]
    keep = np.concatenate([[True], np.diff(xl) > 0])
    loading = PchipInterpolator(xl[keep], fl[keep], extrapolate=True)
    j_tp = int(np.flatnonzero(stable)[-1])
    x_tp, f_tp = float(x[j_tp]), float(f[j_tp])
    pin = np.flatnonzero((stage == "pinning") & stable)
    dl = np.flatnonzero((stage == "delamination") & stable)
    parts = []
    pin_rows = np.concatenate([[mc[-1]], pin])  # retraction starts at the end of loading
    parts.append(_piece(x[pin_rows], f[pin_rows], x_tp))
    onset = pin[-1] if pin.size else mc[-1]
    if dl.size:
        rows = np.concatenate([[onset], dl])
        parts.append(_piece(x[rows], f[rows], x_tp))
    parts = sorted((p for p in parts if p is not None), key=lambda p: p[0])
    return Pieces(x_contact=float(xl[0]), x_max=float(xl[-1]), x_tp=x_tp, f_tp=f_tp,
                  x_onset=float(x[onset]), loading=loading, retraction=parts, frame=frame)


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
        if slip not in ("no-slip", "frictionless"):
            raise InputError("slip", slip, "one of 'no-slip', 'frictionless'")
        if curve.control != scene.control:
            raise InputError("control", curve.control, f"'{scene.control}' (the scene's control mode)")
        self.curve, self.scene, self.slip, self.points = curve, scene, slip, int(points)
        self.control, self.membrane = scene.control, membrane  # "large-stretch" or "exact" (simulate's)
        self.segments = segments if segments is not None else segment(curve)
        self.x = np.asarray(curve.x, float)
        self.force = np.asarray(curve.force, float)
        self.x_max = float(self.x[self.segments.i_turn])
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
        self.n_histories = 0
        self.n_evaluations = 0

    def groups(self, work_of_adhesion: float, mu_h: float, x_offset: float = 0.0) -> dict:
        """Keyword arguments of :func:`adhfit.simulate` for these parameters (loading end from data)."""
        try:
            kw = self.scene.to_dimensionless(mu_h=float(mu_h), work_of_adhesion=float(work_of_adhesion),
                                             slip=self.slip)
        except InputError as err:
            raise ModelDomainError(str(err), self._named(work_of_adhesion, mu_h, x_offset)) from None
        for end in ("a_max", "delta_max", "p_max"):
            kw.pop(end, None)
        scales = self.scene.scales(float(mu_h))
        if self.control == "displacement":
            kw["delta_max"] = scales.to_delta(self.x_max + x_offset)
        else:
            kw["p_max"] = scales.to_p(self.x_max + x_offset)
        return kw

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
                pcs = pieces_from_frame(simulate(**kw, points=self.points + extra, membrane=self.membrane).frame, self.control)
                break
            except (AdhfitError, ValueError, IndexError) as err:
                failure = err
        if pcs is None:
            raise ModelDomainError(f"no history: {failure}", self._named(*key)) from None
        if len(self._cache) >= 8:
            self._cache.pop(next(iter(self._cache)))
        self._cache[key] = pcs
        return pcs

    def dimensionless_x(self, mu_h: float, x_offset: float, x: np.ndarray | None = None) -> np.ndarray:
        """The measured control values (or ``x``) as δ/b or p (with the offset)."""
        scales = self.scene.scales(float(mu_h))
        shifted = (self.x if x is None else x) + x_offset
        return scales.to_delta(shifted) if self.control == "displacement" else scales.to_p(shifted)

    def predict(self, work_of_adhesion: float, mu_h: float, x_offset: float = 0.0,
                force_offset: float = 0.0) -> np.ndarray:
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
            Added to the predicted force (load-cell zero), N.

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
        f[self._attached] = pcs.f_unloading(xd[self._attached])
        if not self.fixed_split:
            f[self._attached] *= self.attached_weight(mu_h, x_offset, pcs)
        return self.scene.scales(float(mu_h)).from_f(f) + force_offset

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
        h = abs(float(self.dimensionless_x(mu_h, x_offset, np.array([self.x_max]))[0]
                      - self.dimensionless_x(mu_h, x_offset, np.array([self.x_max - self.spacing]))[0]))
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
    def jump(self) -> tuple[float, float] | None:
        """The measured pull-off position and its uncertainty, (x_jump, σ_jump), in measured units
        (fixed split only: with a free split the rows themselves carry it).

        The jump happened between the last attached row and the first detached row: x_jump is their
        midpoint and σ_jump = |spacing|/sqrt(12), the standard deviation of a position known only to
        lie in that interval.  ``None`` when the data end before pull-off.
        """
        j = self.segments.i_jump
        if j is None or not self.fixed_split:
            return None
        x_a, x_d = self.x[j - 1], self.x[j]
        return float(0.5 * (x_a + x_d)), max(abs(float(x_a - x_d)), 1e-12 * self.x_max) / math.sqrt(12.0)

    def turning_point(self, work_of_adhesion: float, mu_h: float, x_offset: float = 0.0) -> tuple[float, float]:
        """The model's turning point (pull-off) in measured units: (control value, force in N)."""
        pcs = self.pieces(work_of_adhesion, mu_h, x_offset)
        sc = self.scene.scales(float(mu_h))
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
