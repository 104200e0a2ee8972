"""What a person sees in report.html and summary.html: tables, units, honest one-sided bounds, no raw
JSON, no internal keys, no "seed None" (checked on the HTML text, no browser needed)."""
from __future__ import annotations

import html as _html
import json
import re
from html.parser import HTMLParser
from pathlib import Path

import pytest

from adhfit.report.html import fit_summary_html, render_html
from adhfit.report.summary_html import render_summary_html
from adhfit.report.view import estimate_text


class _Text(HTMLParser):
    """The visible text of a page (what a reader sees), and the tags used."""

    def __init__(self):
        super().__init__()
        self.text, self.tags, self._skip = [], [], 0

    def handle_starttag(self, tag, attrs):
        self.tags.append(tag)
        self._skip += tag in ("style", "script")

    def handle_endtag(self, tag):
        self._skip -= tag in ("style", "script")

    def handle_data(self, data):
        if not self._skip:
            self.text.append(data)


def _visible(page: str) -> tuple[str, list[str]]:
    p = _Text()
    p.feed(page)
    return " ".join(" ".join(p.text).split()), p.tags


def _est(value, lo, hi, unit, **kw):
    return {"value": value, "stderr": None if value is None else value / 100, "ci95": [lo, hi], "unit": unit,
            "ci_method": "profile", **kw}


def _trust_report() -> dict:
    """A report with the keys a fit with per-parameter status has (docs/contracts.md A5b)."""
    return {
        "method": "lsq",
        "slip": {"selected": "no-slip", "verdict": "no-slip selected", "delta_aic": 12.0, "delta_bic": 12.0,
                 "explanation": "ΔBIC = 12 > 10: no-slip is selected.", "parameters_from": "no-slip"},
        "parameters": {"work_of_adhesion": {"value": None, "stderr": None, "ci95": [0.35, None], "unit": "J/m^2",
                                            "status": "lower_bound"},
                       "mu_h": _est(2.0, 1.96, 2.04, "N/m", status="determined")},
        "offsets": {"displacement": 2.3e-5, "force": 1.0e-6},
        "model": {"membrane": "large-stretch", "why": "λ0 = 2: the approximation is below the noise."},
        "observables": ["force"],
        "warnings": ["The test never reached delamination."],
        "diagnostics": ["no-slip: 3 starts, best χ² 190.2", {"solver": "lmfit", "nfev": 140}],
        "fits": {"no-slip": {"parameters": {"mu_h": _est(2.0, 1.96, 2.04, "N/m")}, "redchi": 0.95, "aic": 1.0,
                             "bic": 2.0, "success": True, "message": "ok"},
                 "frictionless": {"parameters": {}, "redchi": 1.4, "aic": 13.0, "bic": 14.0}},
        "n_points": 200, "n_excluded": 0, "excluded": [], "sigma": 1.5e-5, "sigma_source": "estimated",
        "segments": {"i_turn": 84, "i_jump": 185, "jump": 8.5e-4, "n_loading": 85, "n_attached": 100,
                     "n_detached": 15},
        "model_evaluations": 140, "histories": 200, "wall_time_s": 1.5, "engine_startup_s": 0.8,
        "provenance": {"adhfit_version": "0.1.0", "input": "curve.csv", "input_sha256": "a" * 64,
                       "scene_file": "scene.toml", "seed": None, "method": "lsq",
                       "scene": {"membrane_radius": 0.002, "substrate_radius": float("inf"),
                                 "control": "displacement", "prestretch": 2.0, "mu_h": None,
                                 "pressure": 1200.0, "gap": None}},
        "ignored_columns": [{"column": "temperature [C]", "why": "not used by the fit"}],
    }


def _mcmc_report() -> dict:
    d = _trust_report()
    diag = {"acceptance": {"mean": 0.78, "min": 0.7, "max": 0.86}, "tau": {"work_of_adhesion": 1.35},
            "n_over_tau": {"work_of_adhesion": 96.2}, "rhat": {"work_of_adhesion": 1.0003},
            "ess_bulk": {"work_of_adhesion": 2767.3}, "ess_tail": {"work_of_adhesion": 3041.5},
            "n_ensembles": 4, "n_walkers": 8, "steps": 130, "tune_steps": 15, "burn": 18, "thin": 1,
            "kept_samples": 4064, "cap_hit": False, "converged": True, "warnings": []}
    d.update(method="mcmc", seed=5, converged=True, model_probabilities={"no-slip": 0.9995},
             diagnostics={"no-slip": diag},
             mcmc={"seed": 5, "converged": True, "noise_model": "Gaussian, sigma unknown",
                   "priors": {"work_of_adhesion": {"dist": "loguniform", "min": 0.004, "max": 40.0,
                                                   "description": "loguniform on [0.004, 40] J/m^2 (default)"}},
                   "sampler": "emcee", "stopping_rule": "50 tau",
                   "model_probabilities": {"probabilities": {"no-slip": 0.9995, "frictionless": 0.0005},
                                           "threshold": 0.95, "method": "importance sampling",
                                           "explanation": "no-slip is selected."},
                   "slips": {"no-slip": {"diagnostics": diag,
                                         "evidence": {"log_evidence": 1915.62, "stderr": 0.022,
                                                      "weights_ess": 261.3, "n_draws": 300}}},
                   "chain_file": "chain.h5", "model_evaluations": 11440, "lsq_seconds": 3.5})
    d["provenance"] = {**d["provenance"], "seed": 5, "method": "mcmc"}
    return d


def _no_raw_json(text: str) -> None:
    assert not re.search(r"\{\s*\"", text), "a raw JSON object is shown"
    assert not re.search(r"\[\s*\{", text), "a raw JSON list is shown"


def test_one_sided_bound_is_written_as_a_bound():
    d = {"value": None, "ci95": [0.35, None], "unit": "J/m^2", "status": "lower_bound"}
    assert estimate_text("work_of_adhesion", d) == "≥ 0.35 J/m² (lower bound: the test never reached delamination)"
    up = {"value": None, "ci95": [None, 3.0], "unit": "N/m", "status": "upper_bound"}
    assert estimate_text("mu_h", up).startswith("≤ 3 N/m (upper bound")
    assert estimate_text("mu_h", {"value": None, "ci95": None, "status": "undetermined"}).startswith("not determined")


def test_lsq_page_has_tables_units_and_no_internal_keys():
    page = render_html(_trust_report())
    text, tags = _visible(page)
    assert tags.count("table") >= 5
    _no_raw_json(text)
    for unit in ("J/m²", "N/m", "µm", "mN", "mm", "kPa"):
        assert unit in text, unit
    assert "≥ 0.35" in text and "lower bound" in text
    assert "[0.35," not in text  # a one-sided interval is never printed as two-sided
    assert "seed None" not in text and "None" not in text and "no random numbers used" in text
    for key in ("i_turn", "i_jump", "n_loading", "membrane_radius", "input_sha256", "ci_method"):
        assert key not in text, key
    assert "∞ (flat)" in text and "large-stretch" in text and "temperature [C]" in text
    # solver details in their own collapsed section
    solver = page[page.index("<h2>Solver details</h2>"):]
    assert solver.removeprefix("<h2>Solver details</h2>").startswith("<details>") and "best χ² 190.2" in solver
    assert "0.8 s starting the engine" in text


def test_mcmc_page_shows_diagnostics_priors_and_evidence_as_tables():
    page = render_html(_mcmc_report())
    text, _ = _visible(page)
    _no_raw_json(text)
    flat = page.replace("\n", "")
    for heading in ("Priors", "Slip condition: evidence", "Convergence diagnostics</h3><h4>no-slip: converged"):
        assert f"<h3>{heading}</h" in flat and "<table" in flat.split(f"<h3>{heading}</h")[1][:30], heading
    assert "R-hat" in text and "1.0003" in text and "1915.62" in text and "loguniform on [0.004, 40]" in text
    assert "seed 5" in text and "11440" in text
    assert "NOT CONVERGED" not in text
    d = _mcmc_report()
    d["converged"] = False
    d["mcmc"]["converged"] = False
    page = render_html(d)
    assert page.index("NOT CONVERGED") < page.index("<h2>Warnings</h2>")  # said first, not buried


def test_notebook_view_is_a_table():
    block = fit_summary_html(_trust_report())
    text, tags = _visible(block)
    assert "table" in tags and "≥ 0.35 J/m²" in text and "no-slip selected" in text


def _batch(tmp_path):
    rows = []
    for i, w in enumerate((0.4, 0.41)):
        folder = tmp_path / f"c{i}"
        folder.mkdir()
        rep = _trust_report()
        rep["parameters"]["work_of_adhesion"] = _est(w, w - 0.01, w + 0.01, "J/m^2", status="determined")
        (folder / "report.json").write_text(json.dumps(rep, allow_nan=True))
        (folder / "plot_data.json").write_text(json.dumps(
            {"control": "displacement", "x": [0.0, 1e-4, 0.0], "force": [0.0, 1e-3, -1e-4],
             "model": {"x_loading": [0.0, 1e-4], "force_loading": [0.0, 1e-3]}}))
        rows.append({"file": str(tmp_path / "data" / f"run{i}.csv"), "status": "ok", "report_dir": str(folder)})
    rows.append({"file": str(tmp_path / "data" / "bad<b>.csv"), "status": "failed",
                 "error": "The file has no force column", "report_dir": str(tmp_path / "bad")})
    return rows


def test_summary_page_links_every_curve_and_draws_them(tmp_path):
    page = render_summary_html(_batch(tmp_path), tmp_path)
    text, tags = _visible(page)
    _no_raw_json(text)
    assert 'href="c0/report.html"' in page and 'href="c1/report.html"' in page
    assert "0.41 ± 0.0041" in text and "[0.4, 0.42]" in text and "≥" not in text.split("W_ad 95 %")[1][:40]
    assert "failed:" in text and "no force column" in text and "bad&lt;b&gt;" in page
    # values across curves, and one small figure per fitted curve (drawn from plot_data.json here)
    assert page.count("data:image/png;base64,") == 3
    assert "no fit" in text  # the failed curve's place in the grid
    assert "J/m²" in text and "N/m" in text and "adhfit batch: 3 curves" in text


def test_summary_page_embeds_the_small_figure_its_job_drew(tmp_path):
    """A curve whose batch job drew thumbnail.png is shown with exactly those bytes (not drawn again); a
    folder without one is drawn from its plot_data.json."""
    import base64

    from adhfit.report.thumbnails import THUMBNAIL, write_thumbnail
    rows = _batch(tmp_path)
    drawn = write_thumbnail(rows[0]["report_dir"])
    assert drawn is not None and drawn.name == THUMBNAIL and drawn.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    page = render_summary_html(rows, tmp_path)
    assert base64.b64encode(drawn.read_bytes()).decode("ascii") in page
    assert page.count("data:image/png;base64,") == 3
    assert write_thumbnail(tmp_path / "bad") is None  # no plot data: nothing drawn, nothing raised


def test_summary_page_ignores_a_small_figure_older_than_its_fit(tmp_path):
    """A thumbnail.png left by an earlier run (e.g. the folder refitted with --no-plot) is older than the
    plot_data.json of the fit on the page: the page draws the figure again instead of showing it."""
    import base64
    import os

    from adhfit.report.thumbnails import THUMBNAIL
    rows = _batch(tmp_path)
    folder = Path(rows[0]["report_dir"])
    stale = b"\x89PNG\r\n\x1a\n stale bytes"
    (folder / THUMBNAIL).write_bytes(stale)
    t = (folder / "plot_data.json").stat().st_mtime_ns
    os.utime(folder / THUMBNAIL, ns=(t - 10**9, t - 10**9))
    page = render_summary_html(rows, tmp_path)
    assert base64.b64encode(stale).decode("ascii") not in page
    assert page.count("data:image/png;base64,") == 3


@pytest.mark.parametrize("bad", ["{", "<script>"])
def test_summary_page_escapes_errors(tmp_path, bad):
    rows = [{"file": "x.csv", "status": "failed", "error": bad, "report_dir": ""}]
    page = render_summary_html(rows, tmp_path)
    assert _html.escape(bad) in page and "<script>" not in page.replace("<script>" if bad != "<script>" else "", "")


def test_fit_result_renders_itself_in_a_notebook():
    """``FitResult._repr_html_`` is the report's own results table (units, status), not raw reprs."""
    from adhfit.fitting import fit as fit_curve
    sample = Path(__file__).resolve().parents[1] / "sample_data" / "fea_displacement_no-slip"
    result = fit_curve(sample / "curve.csv", sample / "scene.toml", slip="no-slip", profile=False)
    html = result._repr_html_()
    assert "<table" in html and "J/m²" in html and "N/m" in html and "determined" in html
    assert "Estimate(" not in html and "None" not in html
