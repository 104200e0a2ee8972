"""The model of a measured curve (adhfit.fitting.model): zero before contact, continuity in the
parameters, row-order segmentation; and the slip verdict's thresholds."""
from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from adhfit.data import Curve
from adhfit.fitting.model import CurveModel, detect_jump, segment
from adhfit.fitting.selection import compare, information_criteria
from adhfit.synthetic import synthetic_curve
from adhfit.scene import Scene

SCENES = {
    "displacement": (Scene(membrane_radius="2 mm", substrate_radius="1 mm", control="displacement",
                           pressure="1.2 kPa"), 0.6e-3, 20e-6),
    "pressure": (Scene(membrane_radius="2 mm", substrate_radius="inf", control="pressure", gap="0.2 mm"),
                 1.6e3, 0.0),
}
TRUE = {"work_of_adhesion": 0.4, "mu_h": 2.0}


def _curve(control, slip="no-slip", noise=0.0, seed=0):
    scene, x_max, off = SCENES[control]
    curve, truth = synthetic_curve(scene, slip, **TRUE, x_max=x_max, x_offset=off, noise=noise,
                                   rng=np.random.default_rng(seed))
    return scene, curve, truth


@pytest.mark.parametrize("control", ["displacement", "pressure"])
@pytest.mark.parametrize("slip", ["no-slip", "frictionless"])
def test_model_reproduces_noise_free_curve(control, slip):
    scene, curve, truth = _curve(control, slip)
    model = CurveModel(curve, scene, slip, fixed_split=True)
    pred = model.predict(TRUE["work_of_adhesion"], TRUE["mu_h"], truth["x_offset"])
    # interpolation of a 150-row history against a 2000-row one: well below 0.5 % noise
    assert np.max(np.abs(pred - curve.force)) < 1e-3 * np.max(curve.force)
    assert model.segments.i_jump == truth["i_jump"]
    # the free split (the default) puts pull-off at the same row from the parameters alone
    assert CurveModel(curve, scene, slip).split(TRUE["work_of_adhesion"], TRUE["mu_h"], truth["x_offset"]) \
        == truth["i_jump"]


@pytest.mark.parametrize("control", ["displacement", "pressure"])
def test_zero_before_contact_and_after_the_jump(control):
    scene, curve, truth = _curve(control)
    model = CurveModel(curve, scene, "no-slip", fixed_split=True)
    pred = model.predict(TRUE["work_of_adhesion"], TRUE["mu_h"], truth["x_offset"])
    xd = model.dimensionless_x(TRUE["mu_h"], truth["x_offset"])
    pcs = model.pieces(TRUE["work_of_adhesion"], TRUE["mu_h"], truth["x_offset"])
    before = model.segments.loading & (xd < pcs.x_contact)
    assert before.sum() >= 3
    assert np.all(pred[before] == 0.0)
    assert np.all(pred[model.segments.detached] == 0.0)
    assert np.all(pred[model.segments.loading & (xd > pcs.x_contact)] > 0.0)


@pytest.mark.parametrize("control", ["displacement", "pressure"])
def test_prediction_is_continuous_in_the_parameters(control):
    """The change of the prediction vanishes with the parameter step (no row jumps between segments;
    the clamp beyond the model's turning point keeps it continuous): ten times smaller steps give at
    least ~3 times (sqrt(10), the Hölder-1/2 rate at the turning point) smaller changes."""
    scene, curve, truth = _curve(control)
    model = CurveModel(curve, scene, "no-slip", fixed_split=True)  # the free split: tests/test_trust_model.py
    base = dict(work_of_adhesion=0.4, mu_h=2.0, x_offset=truth["x_offset"])
    f0 = model.predict(**base)
    scale = np.max(np.abs(f0))
    x_step = 1e-4 * (np.ptp(curve.x))
    for name, step in (("work_of_adhesion", 0.4e-2), ("mu_h", 2e-2), ("x_offset", x_step * 100)):
        diffs = []
        for k in (1.0, 0.1, 0.01):
            p = dict(base)
            p[name] += k * step
            diffs.append(np.max(np.abs(model.predict(**p) - f0)))
        assert diffs[0] < 0.05 * scale, name
        if diffs[0] < 1e-3 * scale:
            # the parameter barely acts on these rows (W_ad under pressure control on a flat substrate
            # moves only the pull-off point): changes stay at the interpolation's noise floor
            assert max(diffs) < 1e-3 * scale
            continue
        assert diffs[1] < diffs[0] / 2.5 and diffs[2] < diffs[1] / 2.5, (name, diffs)


def test_clamp_beyond_the_turning_point_is_the_turning_point_force():
    scene, curve, truth = _curve("displacement")
    model = CurveModel(curve, scene, "no-slip", fixed_split=True)
    # a model that detaches earlier than the data: lower W
    w = 0.3
    pcs = model.pieces(w, 2.0, truth["x_offset"])
    pred = model.predict(w, 2.0, truth["x_offset"])
    xd = model.dimensionless_x(2.0, truth["x_offset"])
    beyond = model.segments.attached & (xd < pcs.x_tp)
    assert beyond.any()
    f_tp = model.scene.scales(2.0).from_f(pcs.f_tp)
    assert np.allclose(pred[beyond], f_tp)


def test_rows_either_side_of_the_jump_share_a_displacement():
    """Segmentation by row order: the row just before the jump and the one just after it have the same
    displacement; the first is attached (adhesive force), the second free (zero)."""
    scene, curve, truth = _curve("displacement")
    j = truth["i_jump"]
    x = np.array(curve.x)
    x[j] = x[j - 1]  # the first detached row at the last attached row's displacement
    same = dataclasses.replace(curve, x=x)
    seg = segment(same)
    assert seg.i_jump == j
    model = CurveModel(same, scene, "no-slip", fixed_split=True)
    pred = model.predict(0.4, 2.0, truth["x_offset"])
    assert pred[j - 1] < -0.1 * np.max(pred)
    assert pred[j] == 0.0


def test_no_jump_when_the_data_end_before_pull_off():
    scene, curve, truth = _curve("displacement")
    j = truth["i_jump"]
    cut = Curve(path="<cut>", control="displacement", x=curve.x[: j - 3], force=curve.force[: j - 3],
                line=curve.line[: j - 3], i_turn=curve.i_turn)
    assert detect_jump(cut.force, cut.i_turn) == (None, 0.0)
    model = CurveModel(cut, scene, "no-slip")
    assert model.jump is None
    assert not model.segments.detached.any()


def test_jump_detection_with_noise():
    for seed in range(5):
        scene, curve, truth = _curve("displacement", noise=0.005, seed=seed)
        assert segment(curve).i_jump == truth["i_jump"]


def test_verdict_thresholds():
    aic = {"no-slip": 0.0, "frictionless": 0.0}
    assert compare({"no-slip": 0.0, "frictionless": 10.5}, aic)["selected"] == "no-slip"
    v = compare({"no-slip": 5.0, "frictionless": 0.0}, aic)
    assert v["selected"] is None and v["evidence"] == "positive" and v["favoured"] == "frictionless"
    assert v["verdict"].startswith("frictionless: positive evidence, not selected")
    v = compare({"no-slip": 0.0, "frictionless": 1.0}, aic)
    assert v["selected"] is None and v["evidence"] == "cannot tell"
    assert v["verdict"] == "the data cannot tell them apart"
    assert compare({"frictionless": 3.0}, {"frictionless": 1.0})["selected"] == "frictionless"


def test_information_criteria():
    aic, bic = information_criteria(100.0, 50, 3, sigma_given=True)
    assert aic == pytest.approx(106.0) and bic == pytest.approx(100.0 + 3 * np.log(50))
    aic, bic = information_criteria(2.0, 50, 3, sigma_given=False)
    assert aic == pytest.approx(50 * np.log(2.0 / 50) + 6)
