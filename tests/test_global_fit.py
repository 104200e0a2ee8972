"""Global fit of a test series (issue 13): shared W_ad and μh, per-curve offsets, contact radius.

The series is synthetic (adhfit.synthetic.synthetic_series): one membrane (W_ad = 0.4 J/m², μh = 2 N/m,
no-slip) at 0.8, 1.2 and 1.6 kPa, 1 % force noise, a contact radius with 1 % of its largest value as
noise; the truth is the generator's input, never the fit's output.  One seeded series is fitted once
through the command line (module fixture) and the report is checked from outside.

Tolerances: at 1 % noise the shared W_ad has a relative standard error of ~0.3 % and μh ~0.1 % (three
curves with the contact radius), so 2 % is > 6 standard errors: a miss means a bias, not bad luck.
"""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from adhfit.errors import InputError
from adhfit.fitting.api import fit as fit_global
from adhfit.fitting.model import CurveModel, Segments
from adhfit.fitting.observables import OBSERVABLES, contact_radius_model as radius_prediction
from adhfit.synthetic import synthetic_series
from adhfit.scene import load_scene

ROOT = Path(__file__).resolve().parents[1]
SCENE = ROOT / "sample_data" / "fea_displacement_no-slip" / "scene.toml"
TRUE = {"work_of_adhesion": 0.4, "mu_h": 2.0}
PRESSURES = (800.0, 1200.0, 1600.0)


def _series(seed, *, rows=160, radius_noise=0.01, mu_h_per_curve=None, pressures=PRESSURES):
    return synthetic_series(load_scene(SCENE), "no-slip", pressures=pressures, **TRUE, x_max=6e-4, noise=0.01,
                            radius_noise=radius_noise, rows=rows, rng=np.random.default_rng(seed),
                            mu_h_per_curve=mu_h_per_curve)


def _write(series, root: Path) -> None:
    text = SCENE.read_text(encoding="utf-8")
    for curve, scene, _ in series:
        d = root / f"p{int(scene.pressure)}"
        d.mkdir(parents=True)
        (d / "scene.toml").write_text(text.replace('"1.2 kPa"', f'"{scene.pressure / 1e3:g} kPa"'), encoding="utf-8")
        cols = {"displacement [um]": curve.x * 1e6, "force [mN]": curve.force * 1e3}
        if curve.contact_radius is not None:
            cols["contact_radius [um]"] = curve.contact_radius * 1e6
        pd.DataFrame(cols).to_csv(d / "curve.csv", index=False)


@pytest.fixture(scope="module")
def report(tmp_path_factory):
    from adhfit.cli import main
    root = tmp_path_factory.mktemp("series")
    _write(_series(20261201), root / "data")
    out = root / "out"
    assert main(["fit", str(root / "data"), "--global", "-o", str(out)]) == 0
    return json.loads((out / "report.json").read_text(encoding="utf-8")), out


def test_cli_global_writes_report_with_curves(report):
    d, out = report
    assert (out / "report.md").is_file() and (out / "fit.png").is_file()
    assert len(d["curves"]) == 3
    for c in d["curves"]:
        assert {"file", "offsets", "redchi", "n_points"} <= set(c)
        assert c["n_points"] > 100 and c["file"].endswith("curve.csv")
        assert {"displacement", "force"} <= set(c["offsets"])
    for key in ("method", "slip", "parameters", "offsets", "model", "observables", "warnings", "fits"):
        assert key in d
    assert d["offsets"]["displacement"]["status"] == "per_curve"


def test_report_html_and_md_show_shared_values_slip_and_every_curve(report):
    """report.html is self-contained (no external resource) and shows what a reader looks for: the shared
    values with their intervals and status, the slip verdict, one row per curve (its scene pressure, its
    χ²/n, its pull), the embedded figure; report.md carries the same table."""
    import re
    d, out = report
    page = (out / "report.html").read_text(encoding="utf-8")
    assert not re.search(r"(src|href)=\"(https?:|//|file:)", page)
    assert page.count("data:image/png;base64,") == 1
    w = d["parameters"]["work_of_adhesion"]
    assert f"{w['ci95'][0]:.4g}" in page and f"{w['ci95'][1]:.4g}" in page and "determined" in page
    assert d["slip"]["verdict"] in page
    md = (out / "report.md").read_text(encoding="utf-8")
    for c in d["curves"]:
        kpa = f"P = {c['scene']['pressure'] / 1e3:g} kPa"
        assert kpa in page and kpa in md
        assert f"{c['redchi']:.3g}" in md
        share = c["leave_one_out"]["contribution"]["work_of_adhesion"]
        assert 0.0 <= share <= 1.0  # a share of the precision: 1 - se²/se²_without with se <= se_without
    assert md.count("\n| ") >= 3 + 2 + 2  # curves table, shared values, slip table (rows incl. headers)


def test_shared_values_recovered_and_covered(report):
    d, _ = report
    for name, true in TRUE.items():
        e = d["parameters"][name]
        assert e["status"] == "determined"
        assert abs(e["value"] / true - 1.0) < 0.02, (name, e["value"])
        assert e["ci95"][0] <= true <= e["ci95"][1], (name, e["ci95"])


def test_right_slip_selected(report):
    d, _ = report
    assert d["slip"]["selected"] == "no-slip"
    assert d["slip"]["delta_bic"] > 10


def test_contact_radius_used_and_interval_not_wider_than_best_single(report):
    d, _ = report
    assert d["observables"] == ["force", "contact_radius"]
    w = d["parameters"]["work_of_adhesion"]["ci95"]
    singles = [c["alone"]["work_of_adhesion"]["ci95"] for c in d["curves"]]
    best = min(hi - lo for lo, hi in singles)
    assert w[1] - w[0] <= best, (w, singles)
    for c in d["curves"]:
        cr = c["contact_radius"]
        assert cr["n_used"] == c["n_points"] and cr["n_missing"] == 0 and cr["n_zero_not_in_contact"] > 0
        assert not c["flags"], c
    # the generator's contact-radius noise is 1 % of each curve's largest radius (~4-5 µm here)
    assert all(1e-6 < c["contact_radius"]["sigma"] < 1e-5 for c in d["curves"])


def test_outlier_curve_is_flagged():
    """A third curve from a membrane 25 % stiffer: its reduced χ² against the shared fit is far above 1."""
    series = _series(7, rows=120, radius_noise=None, mu_h_per_curve=(2.0, 2.0, 2.5))
    r = fit_global([c for c, _, _ in series], [s for _, s, _ in series], slip="no-slip", profile=False)
    flags = [c["flags"] for c in r.curves]
    assert flags[2] and not flags[0] and not flags[1], flags
    assert any("does not follow the shared fit" in w and "1600" in w for w in r.warnings)
    assert r.observables == ("force",)


def test_radius_model_zero_outside_contact_and_missing_rows_counted():
    """The model's contact radius is 0 before contact and after pull-off, equals the generator's (an
    independent linear interpolation of a dense history) to 0.5 % of a_max in contact; NaN rows are
    skipped and counted, 0 rows are used."""
    import dataclasses
    (curve, scene, truth), = _series(11, radius_noise=None, pressures=(1200.0,))
    from adhfit.synthetic import true_contact_radius
    a_true = true_contact_radius(scene, "no-slip", curve, truth)
    seg = Segments(n=len(curve.x), i_turn=curve.i_turn, i_jump=truth["i_jump"])
    model = CurveModel(curve, scene, "no-slip", segments=seg, fixed_split=True)
    a = radius_prediction(model, TRUE["work_of_adhesion"], TRUE["mu_h"], truth["x_offset"])
    assert np.all(a[a_true == 0.0][: 5] == 0.0) and a[-1] == 0.0
    inside = a_true > 0.05 * a_true.max()
    assert np.max(np.abs(a - a_true)[inside]) < 5e-3 * a_true.max()
    meas = a_true.copy()
    meas[[40, 41, 42]] = np.nan
    rd = OBSERVABLES["contact_radius"].rows(dataclasses.replace(curve, contact_radius=meas))
    assert rd.n_missing == 3 and rd.rows.size == meas.size - 3 and rd.n_zero == int(np.sum(a_true == 0.0))


def test_bad_input_is_one_clear_error():
    (curve, scene, _), = _series(5, radius_noise=None, pressures=(1200.0,), rows=60)
    one = fit_global([curve], [scene], profile=False)  # a series of one is a single-curve fit
    assert one.curves == () and one.n_points == len(curve.x) and "curves" not in one.as_dict()
    with pytest.raises(InputError, match="sigma_contact_radius"):
        fit_global([curve, curve], scene, sigma_contact_radius=-1.0)
    with pytest.raises(InputError, match="method"):
        fit_global([curve, curve], scene, method="bayes")


@pytest.mark.slow
def test_series_recovery_study():
    """Bias, coverage and slip decision over seeded series (benchmarks/recovery_series.py, reduced):
    3 replicates x {no-slip, frictionless} x {1 %, 2 %}, each fitted with and without the contact radius.

    Expected from the issue: the right slip in every series with the contact radius (the single-curve
    study found it in 8–67 % of curves at 1–2 %), |bias| of W_ad and μh below 2 %, the 95 % intervals
    covering the truth in at least 10 of 12 series (binomial at 0.95: P(< 10 of 12) ≈ 2 %), and the
    contact radius never widening the W_ad interval.
    """
    import sys
    sys.path.insert(0, str(ROOT))
    from benchmarks.recovery_series import one
    rows = [r for slip in ("no-slip", "frictionless") for noise in (0.01, 0.02) for seed in range(3)
            for r in one(slip, noise, 13_000 + seed, profile=False)]
    with_radius = [r for r in rows if r["radius"]]
    assert all(r["selected"] == r["slip"] for r in with_radius), [(r["slip"], r["selected"]) for r in with_radius]
    assert not any(r["selected"] not in (None, r["slip"]) for r in rows)
    for name in TRUE:
        assert abs(np.median([r[name]["rel_error"] for r in rows])) < 0.02
        assert sum(r[name]["covered"] for r in with_radius) >= 10
    pairs = zip(rows[0::2], rows[1::2])
    assert all(a["work_of_adhesion"]["rel_width"] <= b["work_of_adhesion"]["rel_width"] * 1.05 for a, b in pairs)


def test_cli_global_needs_two_curves(tmp_path, capsys):
    from adhfit.cli import main
    _write(_series(5, radius_noise=None, pressures=(1200.0,), rows=60), tmp_path)
    assert main(["fit", str(tmp_path / "p1200" / "curve.csv"), "--global", "-o", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert "two or more curves for --global" in err and err.count("\n") == 1


def test_radius_noise_reference_ignores_rows_not_in_contact():
    """The reduced χ² of a contact-radius column is taken against its row-to-row noise from the rows in
    contact only: 60 rows measured 0 (no noise) before 240 noisy rows leave the estimate within 20 % of
    the true σ (the median-absolute-deviation estimate of 240 rows scatters by ~8 %; seeded)."""
    radius_noise = OBSERVABLES["contact_radius"].noise
    rng = np.random.default_rng(3)
    t = np.linspace(0.0, 3.0, 240)
    sigma = 4e-6
    values = np.concatenate([np.zeros(60), 3e-4 + 1e-4 * np.sin(t) + rng.normal(0.0, sigma, t.size)])
    assert abs(radius_noise(values) / sigma - 1.0) < 0.2
