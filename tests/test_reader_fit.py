"""A fit of an instrument export recovers the clean file's W_ad and μh (issue 12, item 1).

The layouts hold the clean file's numbers exactly (moved decimal points), so the arrays agree to
~1 ulp and least squares from the same data-based starts must land on the same optimum: the
tolerance (1e-6 relative) is far above that rounding and far below any real difference (the 95 %
intervals are ~1 % wide).  CI fits two layouts without profile intervals (~1 s each once the
engine is compiled); the slow variant fits all six with profiles.
"""
from __future__ import annotations

from pathlib import Path

import pytest

from adhfit.fitting.api import fit as fit_curve

HERE = Path(__file__).resolve().parent / "data" / "instruments"
SCENE = HERE / "scene.toml"
LAYOUTS = ["bluehill.csv", "mts_testsuite.txt", "labview.lvm", "excel_eu.csv", "extra_columns.csv",
           "position_load.csv"]


def _values(name: str, profile: bool) -> dict[str, float]:
    r = fit_curve(HERE / name, SCENE, profile=profile)
    assert r.slip["selected"] == "no-slip"
    return {k: r.parameters[k].value for k in ("work_of_adhesion", "mu_h")}


@pytest.fixture(scope="module")
def clean_fit():
    return _values("clean.csv", profile=False)


@pytest.mark.parametrize("name", ["labview.lvm", "excel_eu.csv"])
def test_export_fits_like_the_clean_file(clean_fit, name):
    got = _values(name, profile=False)
    assert got == pytest.approx(clean_fit, rel=1e-6)
    # and the fit is the sample's truth (W_ad = 0.4 J/m², μh = 2 N/m) within 1 % (0.5 % force noise)
    assert got == pytest.approx({"work_of_adhesion": 0.4, "mu_h": 2.0}, rel=0.01)


@pytest.mark.slow
def test_every_export_fits_like_the_clean_file():
    ref = _values("clean.csv", profile=True)
    for name in LAYOUTS:
        assert _values(name, profile=True) == pytest.approx(ref, rel=1e-6), name
