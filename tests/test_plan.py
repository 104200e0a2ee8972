"""``adhfit plan`` (docs/contracts.md A8, docs/planning.md): the predicted widths against the fit's own
intervals, the expected misfit against the fit's own ΔBIC, the JSON keys, and one line for bad input."""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

import adhfit
from adhfit.cli.main import main
from adhfit.synthetic import synthetic_curve
from adhfit.planning.evaluate import predict
from adhfit.planning.protocols import Protocol
from adhfit.scene import load_scene

SAMPLES = Path(__file__).resolve().parents[1] / "sample_data"
DISP = SAMPLES / "flat_displacement_no-slip" / "scene.toml"
PRES = SAMPLES / "flat_pressure_no-slip" / "scene.toml"
W, MU = 0.3, 1.5


@pytest.mark.parametrize("scene, end, value, rel", [(DISP, "displacement_max", 4e-4, 0.15),
                                                    (DISP, "displacement_max", 1.3e-4, 0.20),
                                                    (PRES, "pressure_max", 1200.0, 0.15)],
                         ids=["displacement", "displacement-shallow", "pressure"])
def test_widths_match_the_fits_own_interval_on_the_noiseless_curve(scene, end, value, rel):
    """Independent check: the fit (profiles, the pull-off term, its own nuisances) of the noiseless curve with
    the noise σ given reports the interval a noisy replicate reports on average (its χ² surface is the
    expected one).  The plan's widths must agree with it: 15 %.  The shallow test is the one where the
    likelihood at pull-off is not quadratic: its Fisher W_ad width is 1.6x the fit's profile (and the noisy
    replicates'), so only the plan's own profile there passes; it predicts 0.84 of the fit's W_ad width (the
    fit's profile converged to 0.2 %: 0.00946 J/m^2 against 0.00798; the plan check finds 0.82-0.84 of the
    replicates' too), so that case is held to the issue's 20 %."""
    sc = load_scene(scene)
    e = predict(Protocol(sc, end, value, 300, 0.02), ("no-slip",), W, MU, "large-stretch")
    curve, _ = synthetic_curve(sc, "no-slip", work_of_adhesion=W, mu_h=MU, x_max=value, rows=300, noise=0.0,
                               rng=np.random.default_rng(0))
    fit = adhfit.fit(curve, sc, slip="no-slip", sigma=e["sigma_force"])
    for name in ("work_of_adhesion", "mu_h"):
        lo, hi = fit.parameters[name].ci95
        assert e["by_slip"]["no-slip"]["ci95_width_decided"][name] == pytest.approx(hi - lo, rel=rel), name


def test_misfit_is_the_fits_own_delta_bic_on_the_noiseless_curve():
    """With σ given, the fit's ΔBIC on the noiseless curve is the other slip's χ² excess: the plan's misfit λ
    (its own least squares from the truth, one row split) must agree to 5 %."""
    sc = load_scene(PRES)
    e = predict(Protocol(sc, "pressure_max", 1200.0, 300, 0.03), ("no-slip",), W, MU, "large-stretch")
    curve, _ = synthetic_curve(sc, "no-slip", work_of_adhesion=W, mu_h=MU, x_max=1200.0, rows=300, noise=0.0,
                               rng=np.random.default_rng(0))
    fit = adhfit.fit(curve, sc, slip="auto", sigma=e["sigma_force"], profile=False)
    assert fit.slip["favoured"] == "no-slip"
    assert e["by_slip"]["no-slip"]["misfit_chi2"] == pytest.approx(fit.slip["delta_bic"], rel=0.05)


def test_an_undecided_slip_widens_the_reported_interval():
    """Undecided, the fit reports the hull of both conditions' intervals (adhfit.fitting.stage.reported): the
    expected width mixes the decided width and the hull with the verdict's probabilities (the benchmark checks
    the hull against undecided replicate fits: docs/planning.md).  The fit fits the load-cell drift in some
    replicates of this test and not in others (0 < p_drift_fitted < 1), so each nuisance set's verdict
    weighs its own widths: the mixture is within 5 % of the mean widths mixed with the mean probabilities."""
    sc = load_scene(DISP)
    e = predict(Protocol(sc, "displacement_max", 1.3e-4, 300, 0.03), ("no-slip",), W, MU, "large-stretch")
    b = e["by_slip"]["no-slip"]
    p = e["p_slip_decided"]["no-slip"]
    for name in ("work_of_adhesion", "mu_h"):
        assert b["ci95_width_undecided"][name] > b["ci95_width_decided"][name]
        mean = p * b["ci95_width_decided"][name] + (1 - p - e["p_wrong_slip"]["no-slip"]) * b["ci95_width_undecided"][name]
        assert b["ci95_width"][name] == pytest.approx(mean, rel=0.05)
        assert e["ci95_width"][name] == b["ci95_width"][name]
    assert 0.0 < b["p_drift_fitted"] < 1.0


def test_probabilities_are_consistent():
    sc = load_scene(DISP)
    e = predict(Protocol(sc, "displacement_max", 1.3e-4, 300, 0.03), ("no-slip", "frictionless"), W, MU,
                "large-stretch")
    for slip in ("no-slip", "frictionless"):
        words = e["by_slip"][slip]["evidence"]
        assert sum(words.values()) == pytest.approx(1.0)
        assert e["p_slip_decided"][slip] == words["very strong"]
        assert e["p_wrong_slip"][slip] == words["wrong: very strong"]
        assert 0.0 < e["p_slip_decided"][slip] < 1.0  # a shallow test at 3 %: neither sure nor hopeless


def _run(tmp_path, *extra) -> tuple[int, str, str]:
    return main(["plan", "--scene", str(DISP), "--work-of-adhesion", "0.3 J/m^2", "--mu-h", "1.5 N/m",
                 "-o", str(tmp_path / "plan"), *extra])


def test_json_keys_and_files(tmp_path, capsys):
    status = _run(tmp_path, "--noise", "3%", "--delta-max", "0.2 mm",
                  "--vary", "pressure=0.5:1.2kPa:2,displacement_max=0.15:0.3mm:2", "--target-precision", "0.05")
    assert status == 0, capsys.readouterr().err
    out = tmp_path / "plan"
    plan = json.loads((out / "plan.json").read_text())
    assert {"protocols", "recommended", "why"} <= set(plan)
    assert len(plan["protocols"]) == 4
    for e in plan["protocols"]:
        assert {"settings", "ci95_width", "p_slip_decided", "p_wrong_slip", "in_domain", "membrane"} <= set(e)
        assert set(e["ci95_width"]) == {"work_of_adhesion", "mu_h"}
        assert set(e["p_slip_decided"]) == set(e["p_wrong_slip"]) == {"no-slip", "frictionless"}
        assert e["settings"]["control"] == "displacement" and "pressure" in e["settings"]
        assert e["membrane"] in ("large-stretch", "exact", None)
    assert isinstance(plan["recommended"], int)
    rec = plan["protocols"][plan["recommended"]]
    assert min(rec["p_slip_decided"].values()) >= 0.9
    assert rec["ci95_width"]["work_of_adhesion"] <= 0.05 * W
    scene = load_scene(out / "scene.toml")  # the recommended protocol is a scene adhfit reads
    assert scene.pressure == pytest.approx(rec["settings"]["pressure"])
    assert scene.displacement_max == pytest.approx(rec["settings"]["displacement_max"])
    page = (out / "report.html").read_text()
    assert "data:image/png;base64," in page and "Recommended" in page


@pytest.mark.parametrize("extra, option", [
    (["--noise", "0", "--delta-max", "0.2 mm"], "--noise"),
    (["--noise", "-0.02", "--delta-max", "0.2 mm"], "--noise"),
    (["--noise", "2%", "--delta-max", "0.2 mm", "--vary", "pressure=2:1kPa"], "--vary pressure"),
    (["--noise", "2%", "--delta-max", "0.2 mm", "--vary", "rows=300:100"], "--vary rows"),
    (["--noise", "2%", "--delta-max", "0.2 mm", "--vary", "colour=1:2"], "--vary"),
    (["--noise", "2%", "--delta-max", "3 mm"], "--delta-max"),
    (["--noise", "2%", "--delta-max", "0.2 mm", "--vary", "displacement_max=2:3mm:2"], "--vary displacement_max"),
    (["--noise", "2%", "--delta-max", "0.2 mm", "--rows", "5"], "--rows"),
    (["--noise", "2%", "--pressure-max", "1 kPa"], "--pressure-max"),
], ids=["noise-zero", "noise-negative", "range-reversed", "rows-reversed", "unknown-setting", "out-of-domain",
        "out-of-domain-everywhere", "rows", "wrong-end"])
def test_bad_input_is_one_line_with_exit_2(tmp_path, capsys, extra, option):
    assert _run(tmp_path, *extra) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err
    assert f"'{option}'" in err, err
    assert "must be" in err and "Got" in err


def test_filmed_contact_radius_widths_match_the_fits_own_interval():
    """With a filmed contact radius (--radius-noise) the widths include the fit's second observable: the fit of
    the noiseless curve and radius with both σ given agrees to 5 % (measured: 1e-4), and the radius narrows
    the W_ad interval (here about 3x)."""
    import dataclasses
    from adhfit.synthetic import true_contact_radius
    sc = load_scene(DISP)
    proto = Protocol(sc, "displacement_max", 2e-4, 300, 0.03)
    e = predict(proto, ("no-slip",), W, MU, "large-stretch", radius_noise=0.01)
    force_only = predict(proto, ("no-slip",), W, MU, "large-stretch")
    curve, truth = synthetic_curve(sc, "no-slip", work_of_adhesion=W, mu_h=MU, x_max=2e-4, rows=300, noise=0.0,
                                   rng=np.random.default_rng(0))
    a = true_contact_radius(sc, "no-slip", curve, truth)
    fit = adhfit.fit(dataclasses.replace(curve, contact_radius=a), sc, slip="no-slip", sigma=e["sigma_force"],
                     sigma_contact_radius=0.01 * a.max())
    for name in ("work_of_adhesion", "mu_h"):
        lo, hi = fit.parameters[name].ci95
        assert e["by_slip"]["no-slip"]["ci95_width_decided"][name] == pytest.approx(hi - lo, rel=0.05), name
    decided = "ci95_width_decided"
    assert e["by_slip"]["no-slip"][decided]["work_of_adhesion"] < \
        0.5 * force_only["by_slip"]["no-slip"][decided]["work_of_adhesion"]


def test_global_picks_a_set_and_says_why(tmp_path, capsys):
    status = _run(tmp_path, "--noise", "5%", "--delta-max", "0.15 mm", "--vary", "pressure=0.2:1.4kPa:5",
                  "--global", "2", "--radius-noise", "1%")
    assert status == 0, capsys.readouterr().err
    series = json.loads((tmp_path / "plan" / "plan.json").read_text())["series"]
    assert series["k"] == 2 and len(series["pressure"]) == 2 and len(set(series["pressure"])) == 2
    assert set(series["ci95_width"]) == {"work_of_adhesion", "mu_h"} and "contact radius" in series["why"]
    assert _run(tmp_path, "--noise", "5%", "--delta-max", "0.15 mm", "--global", "2") == 2
    assert "'--global'" in capsys.readouterr().err


def test_contact_radius_end_is_programmed_as_a_pressure(tmp_path, capsys):
    """--a-max (a bare number: the dimensionless group, as in simulate) becomes the pressure the machine is
    programmed to; scene.toml carries that pressure."""
    assert main(["plan", "--scene", str(PRES), "--work-of-adhesion", "0.3", "--mu-h", "1.5", "--noise", "2%",
                 "--a-max", "0.5", "--slip", "no-slip", "-o", str(tmp_path / "p")]) == 0, capsys.readouterr().err
    e = json.loads((tmp_path / "p" / "plan.json").read_text())["protocols"][0]
    assert e["settings"]["a_max"] == 0.5 and e["settings"]["control_max"] > 0
    scene = load_scene(tmp_path / "p" / "scene.toml")
    assert scene.pressure_max == pytest.approx(e["settings"]["control_max"], rel=1e-8)


def test_a_map_between_its_sub_grid_agrees_with_the_full_computation():
    """A map's axis of >= 8 values is computed in full on every other value; the cells between take P(drift
    fitted) from their neighbours where those agree
    (adhfit.planning.api._hint).  They must predict what the full computation predicts, and plan.json must
    say which cell used what."""
    plan = adhfit.plan(DISP, work_of_adhesion=W, mu_h=MU, noise=0.03, delta_max="0.2 mm", membrane="large-stretch",
                       vary="displacement_max=0.09:0.16mm:8")
    comp = plan.to_dict()["computation"]
    assert comp["sub_grid_cells"] == 5 and len(comp["sub_grid"][0]) == 5
    sc = load_scene(DISP)
    between = [i for i in (1, 3, 5) if plan.protocols[i]["in_domain"]]
    used = 0
    assert between
    for i in between:
        e = plan.protocols[i]
        full = predict(Protocol(sc, "displacement_max", e["settings"]["displacement_max"], 300, 0.03),
                       ("no-slip", "frictionless"), W, MU, "large-stretch")
        for s in ("no-slip", "frictionless"):
            b = e["by_slip"][s]
            assert b["p_drift_method"] in ("noisy copies", "interpolated")
            assert b["w_ad_width_method"] in ("fisher", "profile")  # never interpolated: it jumps between cells
            used += b["p_drift_method"] == "interpolated"
            assert e["p_slip_decided"][s] == pytest.approx(full["p_slip_decided"][s], abs=0.1)
            assert b["ci95_width"]["work_of_adhesion"] == pytest.approx(full["by_slip"][s]["ci95_width"]["work_of_adhesion"],
                                                                         rel=0.1)
            assert b["misfit"]["lam"] == pytest.approx(full["by_slip"][s]["misfit"]["lam"], rel=1e-9)
            if b["p_drift_method"] == "interpolated":  # where it was, it is close to what its noisy copies say
                assert b["p_drift_fitted"] == pytest.approx(full["by_slip"][s]["p_drift_fitted"], abs=0.15)
    assert used > 0  # the cells between did use their neighbours
    counts = comp["predictions"]
    assert sum(counts["p_drift"].values()) == 2 * sum(e["in_domain"] for e in plan.protocols)
    if plan.recommended is not None:  # the recommended protocol is computed in full
        for b in plan.protocols[plan.recommended]["by_slip"].values():
            assert b["p_drift_method"] == "noisy copies"
