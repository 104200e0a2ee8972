"""fit.png drawn by a second process (adhfit.cli.painter) is the figure drawn in-process, and a painter
that fails leaves the drawing to the caller."""
from __future__ import annotations

import json

import numpy as np
import pytest

from adhfit.cli.painter import Painter
from adhfit.fitting.api import fit as fit_curve
from adhfit.synthetic import synthetic_curve
from adhfit.report.fit_plot import draw_fit, fit_view
from adhfit.scene import Scene


@pytest.fixture(scope="module")
def result():
    scene = Scene(membrane_radius="2 mm", substrate_radius="1 mm", control="displacement", pressure="1.2 kPa",
                  slip="auto", membrane_model="large-stretch")
    curve, _ = synthetic_curve(scene, "no-slip", work_of_adhesion=0.4, mu_h=2.0, x_max=6e-4, rows=60,
                               noise=0.01, rng=np.random.default_rng(1))
    return fit_curve(curve, scene, profile=False)


def test_the_view_is_plain_json(result):
    view = fit_view(result)
    assert json.loads(json.dumps(view, allow_nan=False)) == view
    assert len(view["x"]) == len(result.curve.x) and set(view["fits"]) == {"no-slip", "frictionless"}


def test_painter_draws_the_same_png_as_this_process(result, tmp_path):
    view = fit_view(result)
    painter = Painter()
    painter.paint(view, tmp_path / "painted.png")
    assert painter.finish()
    draw_fit(json.loads(json.dumps(view)), path=tmp_path / "here.png")
    assert (tmp_path / "painted.png").read_bytes() == (tmp_path / "here.png").read_bytes()


def test_a_failing_painter_says_so(tmp_path):
    painter = Painter()
    painter.paint({"control": "displacement"}, tmp_path / "broken.png")  # a view without data
    assert not painter.finish()
    assert not (tmp_path / "broken.png").exists()
    idle = Painter()
    idle.close()  # nothing sent: stopped without drawing
    assert not idle.finish()
