"""Fits with the exact neo-Hookean membrane (issue 11 item 3; docs/contracts.md A3, A5b ``model``, A6).

The curves are made with ``adhfit.exact.exact_history`` (tests/exact_curves.py), not with the fit's
own model code; the truth is W_ad = 0.4 J/m^2, μh = 2 N/m.  Tolerances: the issue's "within 2 %"
for the estimates; coverage of single seeded curves (a 95 % interval misses 1 time in 20: the seeds
are fixed, so a failure is reproducible, and the slow matrix shows whether misses are systematic).
"""
from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from adhfit.errors import DataError, InputError
from adhfit.fitting.api import fit as fit_curve
from adhfit.fitting.lsq import fit_slip
from adhfit.fitting.membrane import approximation_effect
from adhfit.fitting.model import CurveModel
from adhfit.scene import load_scene

from .exact_curves import exact_curve, scene

ROOT = Path(__file__).resolve().parents[1]
SCENE_TEXT = """
[membrane]
radius = "2 mm"
prestretch = 1.3
{model}
[substrate]
radius = "1 mm"
[test]
control = "displacement"
pressure = "600 Pa"
"""


def _check_recovery(result, truth, tol=0.02):
    for name in ("work_of_adhesion", "mu_h"):
        e = result.parameters[name]
        assert abs(e.value / truth[name] - 1.0) < tol, (name, e.value)
        assert e.status == "determined" and e.ci95[0] <= truth[name] <= e.ci95[1], (name, e.ci95)
    assert result.slip["selected"] in (truth["slip"], None), result.slip


# ---------------------------------------------------------------------------------------------
# contracts: scene key, CLI option, Python argument (cheap)


def test_model_choice_when_the_large_stretch_optimum_is_outside_the_exact_domain():
    """No exact history at the large-stretch optimum: the approximation is off beyond any data, so auto
    picks the exact membrane and a large-stretch request says so (instead of 'effect unknown')."""
    from adhfit.fitting.membrane import decide
    auto = decide({}, 1.1, "auto", ("no-slip",))
    assert auto["membrane"] == "exact" and "no history" in auto["why"] and "no-slip" in auto["why"]
    ls = decide({}, 1.1, "large-stretch", ("no-slip",))
    assert ls["membrane"] == "large-stretch" and "no history" in ls["why"] and "--membrane exact" in ls["why"]
    assert decide({}, 1.1, "exact", ("no-slip",))["membrane"] == "exact"
    assert decide({}, 1.1, "auto")["membrane"] == "large-stretch"  # nothing computed, nothing outside


def test_scene_membrane_model_key(tmp_path):
    path = tmp_path / "scene.toml"
    path.write_text(SCENE_TEXT.format(model=""))
    assert load_scene(path).membrane_model == "auto"
    path.write_text(SCENE_TEXT.format(model='model = "exact"'))
    assert load_scene(path).membrane_model == "exact"
    path.write_text(SCENE_TEXT.format(model='model = "neo-hookean"'))
    with pytest.raises(DataError) as err:
        load_scene(path)
    text = str(err.value)
    assert "[membrane] model" in text and "'large-stretch'" in text and "neo-hookean" in text


def test_cli_membrane_option():
    from adhfit.cli.main import _build_parser
    args = _build_parser().parse_args(["fit", "data.csv", "--membrane", "exact"])
    assert args.membrane == "exact"
    assert _build_parser().parse_args(["fit", "data.csv"]).membrane is None  # the scene's then
    out = subprocess.run([sys.executable, "-m", "adhfit.cli", "fit", "data.csv", "--membrane", "finite"],
                         cwd=ROOT, capture_output=True, text=True, env={"PYTHONPATH": str(ROOT)})
    assert out.returncode == 2 and "--membrane" in out.stderr and "large-stretch" in out.stderr


def test_fit_rejects_unknown_membrane():
    curve, _ = exact_curve(3.0, "frictionless", noise=0.005, seed=3, rows=60)
    with pytest.raises(InputError, match="membrane"):
        fit_curve(curve, scene(3.0), membrane="finite")


# ---------------------------------------------------------------------------------------------
# auto keeps the large-stretch membrane where the data cannot tell; the estimated effect is right


def test_auto_keeps_large_stretch_at_lambda0_3():
    """At λ0 = 3 the approximation's force error is ~0.08 % of the largest force and it shifts μh by
    ~0.1 %: at 3 % noise that is ~0.3 σ and ~0.15 standard errors, below what the data resolve.
    (At 0.5 % noise on 240 rows the same shift is ~0.9 standard errors: auto then rightly goes exact.)"""
    curve, truth = exact_curve(3.0, "frictionless", noise=0.03, seed=3)
    res = fit_curve(curve, scene(3.0))
    assert res.model["membrane"] == "large-stretch"
    why = res.model["why"]
    assert "λ0 = 3" in why and "σ" in why and "W_ad" in why and "μh" in why
    assert not any("approximation" in w for w in res.warnings)  # nothing to distrust: the numbers are in why
    _check_recovery(res, truth, tol=0.05)  # 3 % noise: the standard error of μh alone is ~0.7 %


def test_estimated_effect_matches_the_large_stretch_bias():
    """The shift the approximation is said to cause (refit of the large-stretch model to the exact
    prediction) against the bias that the large-stretch fit of exact data actually has (λ0 = 1.5):
    they must agree to 1/4 of the shift plus 3 standard errors (first-order estimate, noisy data)."""
    curve, truth = exact_curve(1.5, "frictionless", noise=0.005, seed=5)
    raw = fit_slip(CurveModel(curve, scene(1.5), "frictionless"))
    sigma = raw.scale * float(raw.best.redchi) ** 0.5
    eff = approximation_effect(raw, sigma)
    si = raw.par.si(raw.best.params)
    for name in ("work_of_adhesion", "mu_h"):
        actual = si[name] / truth[name] - 1.0
        assert abs(eff.shift[name] - actual) < 0.25 * abs(actual) + 3 * eff.se[name], (name, eff.shift, actual)
    assert abs(eff.shift["mu_h"]) > 0.03  # the case is one where the approximation matters
    assert eff.force_error > 0.5 * sigma and eff.resolved()


def test_large_stretch_fit_reports_its_computed_effect():
    """A large-stretch fit where the data resolve the approximation (λ0 = 1.5, 0.5 % noise) warns with
    the computed shifts at the user's λ0; its μh is indeed low by about the stated amount."""
    curve, truth = exact_curve(1.5, "no-slip", noise=0.005, seed=5, rows=120)
    res = fit_curve(curve, scene(1.5), membrane="large-stretch", slip="no-slip", profile=False)
    assert res.model["membrane"] == "large-stretch" and "λ0 = 1.5" in res.model["why"]
    note = [w for w in res.warnings if "λ0 = 1.5" in w and "shifts W_ad" in w]
    assert len(note) == 1, res.warnings
    stated = float(note[0].split("μh by ")[1].split(" %")[0]) / 100
    actual = res.parameters["mu_h"].value / truth["mu_h"] - 1.0
    assert stated < -0.03 and abs(stated - actual) < 0.25 * abs(actual), (stated, actual)


# ---------------------------------------------------------------------------------------------
# exact fits recover the truth (one reduced case in CI, the matrix with --runslow)


def test_exact_fit_recovers_lambda0_1_2_frictionless_cli(tmp_path, capsys):
    """Through ``adhfit fit --membrane exact``: report.json says which model ran, and it recovers."""
    from adhfit.cli import main
    curve, truth = exact_curve(1.2, "frictionless", noise=0.01, seed=11, rows=200)
    data = tmp_path / "curve.csv"
    rows = "\n".join(f"{x:.9e},{f:.9e}" for x, f in zip(curve.x, curve.force))
    data.write_text("displacement [m],force [N]\n" + rows + "\n")
    (tmp_path / "scene.toml").write_text(SCENE_TEXT.format(model="").replace("1.3", "1.2"))
    out = tmp_path / "out"
    assert main(["fit", str(data), "--membrane", "exact", "--slip", "frictionless", "--no-plot", "-o", str(out)]) == 0
    report = json.loads((out / "report.json").read_text())
    assert report["model"]["membrane"] == "exact" and "λ0 = 1.2" in report["model"]["why"]
    assert "membrane: exact" in capsys.readouterr().out
    for name in ("work_of_adhesion", "mu_h"):
        p = report["parameters"][name]
        assert abs(p["value"] / truth[name] - 1.0) < 0.02 and p["ci95"][0] <= truth[name] <= p["ci95"][1], p


def test_exact_fit_of_a_test_stopped_before_pull_off():
    """Unloading stops inside pinning: the exact fit profiles (its covariance says nothing about W_ad)
    and reports a one-sided W_ad bound below the truth, never an invented value; μh stays determined."""
    from adhfit.data import Curve
    c, truth = exact_curve(1.5, "no-slip", noise=0.005, seed=3)
    end = c.i_turn + 60
    cut = Curve(path="<cut>", control=c.control, x=c.x[:end], force=c.force[:end], line=c.line[:end],
                i_turn=c.i_turn)
    res = fit_curve(cut, scene(1.5), slip="no-slip")
    assert res.model["membrane"] == "exact"
    w, mu = res.parameters["work_of_adhesion"], res.parameters["mu_h"]
    assert w.status in ("lower_bound", "undetermined") and (w.ci95 is None or w.ci95[0] <= truth["work_of_adhesion"])
    assert mu.status == "determined" and mu.ci95[0] <= truth["mu_h"] <= mu.ci95[1]


@pytest.mark.parametrize("slip", ["frictionless", "no-slip"])
def test_exact_fit_pressure_control_small_prestretch(slip):
    """An F–P curve (pressure control at a 0.4 mm gap) at λ0 = 1.1, loaded to P = 1.5 kPa (P b/2μh =
    0.75). The large-stretch optimum lies outside the exact membrane's domain (its μh, 33 % low, puts
    P b/2μh beyond what Case I reaches) and its pull-off row is 4 rows early. Default settings must still
    choose the exact membrane and recover W_ad and μh within 2 % with covering intervals and the right
    slip (before: a ConvergenceError on frictionless data, W_ad 28 % low on no-slip data)."""
    curve, truth = exact_curve(1.1, slip, noise=0.005, seed=1, control="pressure")
    res = fit_curve(curve, scene(1.1, control="pressure"))
    assert res.model["membrane"] == "exact"
    _check_recovery(res, truth)


@pytest.mark.slow
@pytest.mark.parametrize("noise", [0.005, 0.01])
@pytest.mark.parametrize("slip", ["frictionless", "no-slip"])
@pytest.mark.parametrize("lambda0", [1.2, 1.5])
def test_exact_fit_default_settings(lambda0, slip, noise):
    curve, truth = exact_curve(lambda0, slip, noise=noise, seed=int(100 * lambda0) + (slip == "no-slip"))
    res = fit_curve(curve, scene(lambda0))
    assert res.model["membrane"] == "exact"
    _check_recovery(res, truth)
    assert np.isfinite(res.sigma)


@pytest.mark.slow
@pytest.mark.parametrize("slip", ["frictionless", "no-slip"])
@pytest.mark.parametrize("lambda0", [1.1, 2.0])
def test_exact_fit_default_settings_issue_pressure(lambda0, slip):
    """The issue's p = 0.6 (P = 1.2 kPa here) at λ0 = 1.1 and 2 (where the large-stretch fit's μh
    interval missed the truth in 6 of 6 draws at λ0 = 2)."""
    curve, truth = exact_curve(lambda0, slip, noise=0.005, seed=7, pressure=1200.0)
    res = fit_curve(curve, scene(lambda0, pressure=1200.0))
    assert res.model["membrane"] == "exact"
    _check_recovery(res, truth)
