"""One fit path: ``adhfit.fit`` for one curve or a series, least squares or MCMC, one result type, and
``adhfit.report.write`` for every report."""
from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest

import adhfit
from adhfit.errors import InputError
from adhfit.fitting.result import FitResult
from adhfit.synthetic import synthetic_curve
from adhfit.scene import Scene

SMALL_MCMC = dict(n_walkers=6, n_ensembles=2, tune_steps=10, max_steps=15, evidence_draws=60, predictive_draws=8)


def _scene(**kw):
    base = dict(membrane_radius="2 mm", substrate_radius="1 mm", control="displacement", pressure="1.2 kPa",
                slip="auto", membrane_model="large-stretch")
    return Scene(**(base | kw))


@pytest.fixture(scope="module")
def curve():
    c, _ = synthetic_curve(_scene(), "no-slip", work_of_adhesion=0.4, mu_h=2.0, x_max=6e-4, rows=80,
                           noise=0.005, x_offset=2e-5, rng=np.random.default_rng(3))
    return c


def test_least_squares_and_mcmc_return_the_same_type(curve, tmp_path):
    lsq = adhfit.fit(curve, _scene())
    mc = adhfit.fit(curve, _scene(), method="mcmc", seed=4, workers=1, progress=False, **SMALL_MCMC)
    assert type(lsq) is FitResult and type(mc) is FitResult
    assert {f.name for f in dataclasses.fields(lsq)} == {f.name for f in dataclasses.fields(mc)}
    assert lsq.sampling is None and lsq.converged is None and lsq.mcmc == {}
    assert mc.sampling is not None and set(mc.samples) == {"no-slip", "frictionless"}
    assert mc.method == "mcmc" and lsq.method == "lsq"
    # MCMC starts from the same least-squares fits
    for name in ("work_of_adhesion", "mu_h"):
        assert mc.mcmc["lsq_estimates"][lsq.reported_slip][name] == pytest.approx(lsq.parameters[name].value,
                                                                                   rel=1e-6)
    with pytest.raises(dataclasses.FrozenInstanceError):
        mc.sampling = None  # type: ignore[misc]


def test_mcmc_options_are_refused_by_least_squares(curve):
    with pytest.raises(InputError, match="n_walkers"):
        adhfit.fit(curve, _scene(), n_walkers=6)


def test_report_write_puts_every_file_in_place(curve, tmp_path):
    mc = adhfit.fit(curve, _scene(), method="mcmc", seed=4, workers=1, progress=False, outdir=tmp_path / "m",
                    **SMALL_MCMC)
    written = adhfit.report.write(mc, tmp_path / "m")
    names = {p.name for p in written}
    assert {"report.json", "report.md", "report.html", "plot_data.json", "fit.png", "fit_mcmc.png",
            "corner.png"} <= names
    assert all(p.stat().st_size > 0 for p in written)
    d = json.loads((tmp_path / "m" / "report.json").read_text())
    assert d["method"] == "mcmc" and d["mcmc"]["seed"] == 4 and "model_probabilities" in d
    lsq = adhfit.fit(curve, _scene(), profile=False)
    names = {p.name for p in adhfit.report.write(lsq, tmp_path / "l", plot=False)}
    assert names == {"report.json", "report.md", "report.html", "plot_data.json"}
    assert "mcmc" not in json.loads((tmp_path / "l" / "report.json").read_text())


def test_a_sequence_of_curves_is_one_global_fit(curve):
    c2, _ = synthetic_curve(_scene(pressure="1.6 kPa"), "no-slip", work_of_adhesion=0.4, mu_h=2.0, x_max=6e-4,
                            rows=80, noise=0.005, x_offset=1e-5, rng=np.random.default_rng(4))
    r = adhfit.fit([curve, c2], [_scene(), _scene(pressure="1.6 kPa")], profile=False)
    assert type(r) is FitResult and len(r.curves) == 2
    assert r.parameters["work_of_adhesion"].value == pytest.approx(0.4, rel=0.05)
    ax = r.plot()  # a series draws itself like one curve (every curve, the shared fit)
    assert ax.get_figure() is not None and len(ax.lines) >= 2


def test_cli_mcmc_goes_through_the_same_path(tmp_path, capsys):
    from adhfit.cli import main
    from adhfit.synthetic import measured_frame
    frame, _ = measured_frame(_scene(), "no-slip", mu_h=2.0, work_of_adhesion=0.4, x_max=6e-4, rows=80,
                              noise=0.005, seed=2)
    frame.to_csv(tmp_path / "curve.csv", index=False)
    (tmp_path / "scene.toml").write_text(
        '[membrane]\nradius = "2 mm"\nmodel = "large-stretch"\n[substrate]\nradius = "1 mm"\n'
        '[test]\ncontrol = "displacement"\npressure = "1.2 kPa"\n[interface]\nslip = "auto"\n')
    status = main(["fit", str(tmp_path / "curve.csv"), "--scene", str(tmp_path / "scene.toml"), "--method",
                   "mcmc", "--seed", "1", "-o", str(tmp_path / "out"), "--quiet"])
    assert status == 0, capsys.readouterr().err
    for name in ("report.json", "report.html", "fit.png", "fit_mcmc.png", "corner.png", "chain.h5"):
        assert (tmp_path / "out" / name).stat().st_size > 0, name
    d = json.loads((tmp_path / "out" / "report.json").read_text())
    assert d["method"] == "mcmc" and d["seed"] == 1
    assert abs(d["parameters"]["work_of_adhesion"]["value"] / 0.4 - 1) < 0.05
    assert "MCMC" in capsys.readouterr().out


def test_a_toy_observable_is_one_registry_entry(curve, monkeypatch):
    """A secondary observable is one entry of OBSERVABLES: a toy one (the model's contact radius read back
    from a column the curve carries) is fitted as a block of its own and listed in ``observables``."""
    from adhfit.fitting import observables
    truth = adhfit.fit(curve, _scene(), slip="no-slip", profile=False)
    model_a = observables.OBSERVABLES["contact_radius"].model
    toy = observables.Observable(name="toy", unit="m", label="toy radius", read=lambda c: c.time, model=model_a)
    monkeypatch.setitem(observables.OBSERVABLES, "toy", toy)
    rng = np.random.default_rng(5)
    from adhfit.fitting.model import CurveModel
    m = CurveModel(curve, _scene(), "no-slip")
    a = model_a(m, 0.4, 2.0, 2e-5)
    with_toy = dataclasses.replace(curve, time=a + rng.normal(0.0, 2e-6, a.size))
    r = adhfit.fit(with_toy, _scene(), slip="no-slip", profile=False)
    assert r.observables == ("force", "toy") and truth.observables == ("force",)
    assert r.parameters["work_of_adhesion"].value == pytest.approx(0.4, rel=0.03)
