"""report.html (adhfit.report.html): self-contained, escaped, complete."""
from __future__ import annotations

import base64
import re
from pathlib import Path

import pytest

from adhfit.report.html import render_html, write_html

SAMPLE = Path(__file__).resolve().parents[1] / "sample_data" / "fea_displacement_no-slip"
EVIL = "<script>alert('x')</script>&"


def _report(**extra) -> dict:
    est = {"value": 0.4, "stderr": 0.01, "ci95": [0.38, 0.42], "unit": "J/m^2", "ci_method": "profile"}
    d = {"method": "lsq",
         "slip": {"selected": None, "verdict": f"undecided {EVIL}", "delta_aic": 0.5, "delta_bic": 0.5,
                  "explanation": "ΔBIC < 2", "parameters_from": "no-slip"},
         "parameters": {"work_of_adhesion": est, "mu_h": {**est, "value": 2.0, "stderr": None, "ci95": None}},
         "offsets": {"displacement_offset": {**est, "value": 2.3e-5, "unit": "m"}},
         "fits": {"no-slip": {"parameters": {"work_of_adhesion": est}, "chisqr": 190.0, "redchi": 0.95,
                              "aic": 1.0, "bic": 2.0},
                  "frictionless": {"parameters": {}, "chisqr": 191.0, "redchi": 0.96, "aic": 1.5, "bic": 2.5}},
         "warnings": [f"warning with {EVIL}"], "n_points": 200, "n_excluded": 1,
         "excluded": [f"line 7: comment {EVIL}"], "sigma": 1.5e-5, "sigma_source": "estimated",
         "segments": {"i_turn": 84, "i_jump": None},
         "provenance": {"adhfit_version": "0.1.0", "input": f"data/{EVIL}.csv", "input_sha256": "f" * 64,
                        "scene_file": "scene.toml", "scene": {"radius": 0.002, "control": "displacement"},
                        "seed": 11, "method": "lsq"}}
    d.update(extra)
    return d


PNG = base64.b64decode("iVBORw0KGgoAAAANSUhEUgAAAAEAAAABCAYAAAAfFcSJAAAADUlEQVR42mNk+M9QDwADhgGAWjR9awAAAABJRU5ErkJggg==")


def test_text_is_escaped_and_nothing_is_external():
    page = render_html(_report(chain={"note": EVIL}), images={"fit": PNG})
    assert "<script>" not in page and "&lt;script&gt;" in page
    assert not re.search(r"""(src|href)\s*=\s*["']?(https?:|//|file:)""", page, re.I)
    assert "<link" not in page and "@import" not in page
    assert page.count('src="data:image/png;base64,') == 1
    # everything a colleague needs: estimates, verdict, warnings, provenance, unknown keys kept
    for text in ("0.4", "[0.38, 0.42]", "n/a", "undecided", "warning with", "f" * 64, "0.1.0", "seed 11",
                 "Provenance", "More results", "chain", "line 7", "23"):
        assert text in page, text


def test_write_html_from_a_real_fit(tmp_path):
    from adhfit.fitting import fit as fit_curve
    result = fit_curve(SAMPLE / "curve.csv", SAMPLE / "scene.toml", slip="no-slip", profile=False, seed=3)
    path = write_html(result, tmp_path / "report.html")  # draws the fit plot itself
    page = path.read_text(encoding="utf-8")
    assert page.startswith("<!DOCTYPE html>") and page.rstrip().endswith("</html>")
    assert page.count("data:image/png;base64,") == 1
    assert result.provenance["input_sha256"] in page
    assert "no-slip" in page and "W_ad" in page and "μh" in page
    assert f"{result.parameters['work_of_adhesion'].value:.5g}" in page


@pytest.mark.parametrize("images", [None, {}])
def test_a_dictionary_without_images_says_there_is_no_plot(images):
    page = render_html(_report(), images=images)
    assert "No plot in this report" in page
