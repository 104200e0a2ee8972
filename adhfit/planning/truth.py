"""The noiseless test of a protocol: the curve the fit would see without noise, its noise level, and
whether the protocol stays inside the model's domain.

The rows are laid out as :func:`adhfit.synthetic.synthetic_curve` lays a measured-style curve (the
control variable rises at a constant step from before contact to the loading end and falls at the
same step past pull-off; ``rows`` in all), so the plan predicts the fit of exactly the curves
``adhfit simulate --scene ... -o`` writes.  The fit's model is then built as the fit builds it
(:class:`adhfit.fitting.CurveModel` with the detachment row fixed where the truth detaches, the
pull-off term included), with the fit's nuisances (:class:`adhfit.fitting.lsq.Parametrisation`:
control offset under displacement control, load-cell zero, and its drift where the rows pin it).
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from types import SimpleNamespace

import numpy as np

from ..errors import AdhfitError, ConvergenceError, InputError
from ..fitting.lsq import Parametrisation, drift_supported
from ..fitting.model import CurveModel, ModelDomainError, segment
from ..synthetic import loading_end_si, synthetic_curve
from ..params import A_MAX_OVER_RS
from ..simulation import simulate
from .protocols import Protocol

__all__ = ["Truth", "OutOfDomain", "loading_end", "noiseless_test", "drift_probability", "DENSE_POINTS", "DRIFT_DRAWS"]

#: rows of the dense forward history the curve is interpolated from (synthetic_curve's default is 2000;
#: the interpolated force differs by < 1e-5 of the peak force at 400, far below any noise a plan accepts)
DENSE_POINTS = 400


class OutOfDomain(AdhfitError, ValueError):
    """The protocol leaves the model's domain (the reason is the message)."""


@dataclass
class Truth:
    """One protocol and one true slip condition, without noise.

    Attributes
    ----------
    curve : adhfit.data.Curve
        The noiseless measured-style curve (SI).
    sigma : float
        Force noise σ, N (the protocol's fraction of the force at the end of loading).
    model : CurveModel
        The fit's model of the true slip, detachment fixed at the truth's row (pull-off term on).
    par : Parametrisation
        The fit's parameters (nuisances as the fit chooses them for this curve).
    values : dict
        The truth in SI (W_ad, μh, offsets 0).
    a_max : float
        Largest contact radius reached on loading, over b.
    """

    curve: object
    sigma: float
    model: CurveModel
    par: Parametrisation
    values: dict
    a_max: float

    def model_of(self, slip: str, membrane: str | None = None, points: int | None = None) -> CurveModel:
        """The fit's model of ``slip`` (or another membrane) on the same rows and row split."""
        m = self.model
        return CurveModel(m.curve, m.scene, slip, points=points or m.points, segments=m.segments, fixed_split=True,
                          membrane=membrane or m.membrane)


def _groups(protocol: Protocol, slip: str, w: float, mu: float) -> dict:
    kw = protocol.scene.to_dimensionless(mu_h=mu, work_of_adhesion=w, slip=slip)
    for end in ("a_max", "delta_max", "p_max"):
        kw.pop(end, None)
    return kw


def loading_end(protocol: Protocol, slip: str, w: float, mu: float) -> float:
    """The largest control value of the protocol's loading, SI (m of displacement or Pa of pressure).

    A contact-radius end (``a_max``) is converted with ``slip``'s history: the lab programs a displacement or
    a pressure, so both slip conditions are then tested to the same control value."""
    if protocol.end != "a_max":
        return float(protocol.end_value)
    sc = protocol.scene.scales(mu)
    try:
        frame = simulate(**_groups(protocol, slip, w, mu), a_max=protocol.end_value, points=200).frame
    except (ConvergenceError, InputError) as err:
        raise OutOfDomain(f"no history to a_max = {protocol.end_value:g}: {err}") from None
    return loading_end_si(frame, protocol.scene.control, sc)


def noiseless_test(protocol: Protocol, slip: str, w: float, mu: float, x_max: float, *,
                   membrane: str = "large-stretch", points: int | None = None, drift: bool | None = None) -> Truth:
    """The noiseless curve of ``protocol`` for a true ``slip`` and its fit model.

    ``drift``: fit the load-cell drift or not (default: as the fit decides on this noiseless curve,
    :func:`adhfit.fitting.lsq.drift_supported`).

    Raises
    ------
    OutOfDomain
        The model has no history there, or the contact leaves the substrate's upper hemisphere.
    """
    scene = protocol.scene
    try:
        _groups(protocol, slip, w, mu)  # the scene's groups in range (e.g. the pressure above -2 μh / R_s)
        curve, truth = synthetic_curve(scene, slip, work_of_adhesion=w, mu_h=mu, x_max=x_max, rows=protocol.rows,
                                       noise=0.0, rng=np.random.default_rng(0), points=DENSE_POINTS)
    except (ConvergenceError, InputError, ValueError, IndexError) as err:
        raise OutOfDomain(f"no {slip} history: {err}") from None
    if not truth["i_jump"] < curve.x.size or truth["i_jump"] <= curve.i_turn + 1:
        raise OutOfDomain(f"the {slip} curve shows no pull-off")
    kw = {} if points is None else {"points": points}
    seg = segment(curve)
    try:
        fixed = CurveModel(curve, scene, slip, segments=seg.split_before(truth["i_jump"], curve.force),
                           fixed_split=True, **kw)
        pcs = fixed.pieces(w, mu, 0.0)
    except (ModelDomainError, AdhfitError) as err:
        raise OutOfDomain(f"the fit's {slip} model has no history: {err}") from None
    a_reached = float(np.max(pcs.columns["a"]))
    rs = scene.substrate_radius / scene.membrane_radius
    if math.isfinite(rs) and a_reached >= A_MAX_OVER_RS * rs:
        raise OutOfDomain(f"the contact reaches a/b = {a_reached:.3g}, beyond the substrate's upper hemisphere "
                          f"({A_MAX_OVER_RS:g} R_s/b = {A_MAX_OVER_RS * rs:.3g})")
    sigma = protocol.noise * float(curve.force[curve.i_turn])
    if membrane != "large-stretch":  # the other membrane's noiseless force on the same rows, its own pull-off
        try:
            other = CurveModel(curve, scene, slip, segments=seg, membrane=membrane, **kw)
            force = other.predict(w, mu)
        except (ModelDomainError, AdhfitError) as err:
            raise OutOfDomain(f"the {membrane} membrane has no {slip} history: {err}") from None
        curve = dataclasses.replace(curve, force=force)
        seg = segment(curve)
        j = other.split(w, mu)
        if j is None:
            raise OutOfDomain(f"the {membrane} {slip} curve shows no pull-off")
        fixed = CurveModel(curve, scene, slip, segments=seg.split_before(j, force), fixed_split=True,
                           membrane=membrane, **kw)
    free = CurveModel(curve, scene, slip, segments=seg)
    control = scene.control
    if drift is None:
        drift = drift_supported(free)
    par = Parametrisation(float(np.ptp(curve.x)) or 1.0, float(np.max(np.abs(curve.force))) or 1.0, control,
                          control == "displacement", True, bool(drift))
    values = {"work_of_adhesion": float(w), "mu_h": float(mu), "x_offset": 0.0, "force_offset": 0.0,
              "force_drift": 0.0}
    return Truth(curve=curve, sigma=sigma, model=fixed, par=par, values=values, a_max=a_reached)


#: noise draws of :func:`drift_probability`: a first batch, and more when it is split
DRIFT_DRAWS = (20, 40)
DRIFT_SEED = 20261205


def drift_probability(truth: Truth) -> float:
    """The probability that the fit fits the load-cell drift on a noisy replicate of this test.

    The fit fits the drift only where its rows pin it (:func:`adhfit.fitting.lsq.drift_supported`: at least
    5 rows before the contact point its hinge fit finds, and after the jump it detects), decided on the
    measured, noisy curve.  Near 5 rows the noise decides: a shallow displacement-control test of the
    sample scene fits it in 19-24 of 30 replicates, and its wrong slip's misfit without the drift is 1.6x
    larger (the drift absorbs part of it), so the verdict and the widths are a mixture of the two
    (:func:`adhfit.planning.evaluate.predict`).  Estimated on noisy copies of the noiseless curve (Gaussian
    force noise of level σ, a fixed seed): a first batch, and more when it is split.
    """
    curve = truth.curve
    rng = np.random.default_rng(DRIFT_SEED)
    hits = []
    for n in DRIFT_DRAWS:
        for _ in range(n):
            noisy = dataclasses.replace(curve, force=curve.force + truth.sigma * rng.standard_normal(curve.force.size))
            try:  # what drift_supported reads of a model: its rows and their segments
                hits.append(drift_supported(SimpleNamespace(x=noisy.x, force=noisy.force, segments=segment(noisy))))
            except (AdhfitError, ValueError, IndexError):
                hits.append(False)
        if 0 < sum(hits) < len(hits):
            continue
        break
    return float(np.mean(hits))
