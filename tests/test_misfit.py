"""A misfit in words (issue 23 item 3): mistakes the model can still fit must not give confident numbers.

A force column headed [N] that holds mN, a scene pressure written as a bare number (read in Pa, meant
kPa) and a substrate radius of 1 m (meant 1 mm) each leave residuals several times the row-to-row
scatter.  Before, all three exited 0 with the correlated-noise warning as the only explanation.  Now the
first warning says the model does not describe the data and names the likely causes, the slip verdict is
capped at 'positive', and ``adhfit fit`` exits with status 5 (docs/contracts.md).  The correctly read
sample exits 0 without it.
"""
from __future__ import annotations

import json
from pathlib import Path

import pytest

from adhfit.cli import main
from adhfit.cli.writing import EXIT_MISFIT

SAMPLE = Path(__file__).resolve().parents[1] / "sample_data" / "fea_displacement_no-slip"


def _mistakes(tmp_path: Path) -> dict:
    lines = (SAMPLE / "curve.csv").read_text(encoding="utf-8").splitlines()
    mn_as_n = tmp_path / "mN_as_N.csv"
    mn_as_n.write_text("\n".join([lines[0].replace("[mN]", "[N]"), *lines[1:]]) + "\n", encoding="utf-8")
    scene = (SAMPLE / "scene.toml").read_text(encoding="utf-8")
    bare = tmp_path / "pa.toml"
    bare.write_text(scene.replace('pressure = "1.2 kPa"', "pressure = 1.2"), encoding="utf-8")
    metre = tmp_path / "metre.toml"
    metre.write_text(scene.replace('radius = "1 mm"', 'radius = "1 m"'), encoding="utf-8")
    assert bare.read_text() != scene and metre.read_text() != scene
    return {"force in mN headed [N]": (mn_as_n, SAMPLE / "scene.toml"),
            "pressure = 1.2 (Pa)": (SAMPLE / "curve.csv", bare),
            "substrate radius 1 m": (SAMPLE / "curve.csv", metre)}


@pytest.mark.parametrize("case", ["force in mN headed [N]", "pressure = 1.2 (Pa)", "substrate radius 1 m"])
def test_a_unit_mistake_ends_in_a_misfit_message(case, tmp_path, capsys):
    curve, scene = _mistakes(tmp_path)[case]
    out = tmp_path / "out"
    code = main(["fit", str(curve), "--scene", str(scene), "-o", str(out), "--no-plot", "--no-profile", "--quiet"])
    printed = capsys.readouterr().out
    assert code == EXIT_MISFIT == 5
    d = json.loads((out / "report.json").read_text(encoding="utf-8"))
    first = d["warnings"][0]
    assert first.startswith("The model does not describe these data"), d["warnings"]
    for cause in ("unit", "pressure", "radius"):
        assert cause in first
    assert d["slip"]["evidence"] not in ("strong", "very strong") and d["slip"]["selected"] is None
    assert "WARNING: The model does not describe these data" in printed


def test_the_sample_read_right_is_no_misfit(tmp_path, capsys):
    code = main(["fit", str(SAMPLE / "curve.csv"), "--scene", str(SAMPLE / "scene.toml"), "-o", str(tmp_path / "o"),
                 "--no-plot", "--no-profile", "--quiet"])
    assert code == 0
    d = json.loads((tmp_path / "o" / "report.json").read_text(encoding="utf-8"))
    assert not any("does not describe" in w for w in d["warnings"]) and not d["fits"]["no-slip"]["misfit"]
