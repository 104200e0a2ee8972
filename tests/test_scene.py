"""Tests of adhfit.scene: the Scene value object, the TOML scene file (docs/contracts.md A3), priors."""
from __future__ import annotations

import dataclasses
import math

import pytest

from adhfit.errors import DataError, InputError
from adhfit.params import DIMENSIONLESS
from adhfit.scene import Scene, load_scene, normalize_priors
from adhfit.units import Scales

A3 = """\
[membrane]
radius = "2 mm"              # b, clamped radius after pre-stretch
prestretch = 2.0             # λ0
mu_h = "2 N/m"               # optional when fitted

[substrate]
radius = "1 mm"              # R_s, or "inf"

[test]
control = "displacement"     # or "pressure"
pressure = "1.2 kPa"         # displacement control: the fixed pressure
# gap = "0 mm"               # pressure control: the fixed gap d

[interface]
slip = "auto"                # "no-slip", "frictionless", or "auto" (fit both, compare)
work_of_adhesion = "0.4 J/m^2"
"""

PRESSURE = """\
[membrane]
radius = 0.002
[substrate]
radius = "inf"
[test]
control = "pressure"
gap = "0.2 mm"
pressure_max = "3 kPa"
[interface]
slip = "frictionless"
"""


@pytest.fixture
def write(tmp_path):
    def _write(text: str, name: str = "scene.toml"):
        path = tmp_path / name
        path.write_text(text, encoding="utf-8")
        return path
    return _write


def edit(text: str, old: str, new: str) -> str:
    assert old in text, old
    return text.replace(old, new)


# ---------------------------------------------------------------------------------------------
# reading the A3 example; the FEA case of docs/numerics.md C
def test_load_a3_example_in_si(write):
    path = write(A3)
    s = load_scene(path)
    assert s.membrane_radius == pytest.approx(2e-3) and s.b == s.membrane_radius
    assert s.prestretch == 2.0 and s.lambda0 == 2.0
    assert s.mu_h == pytest.approx(2.0)
    assert s.substrate_radius == pytest.approx(1e-3)
    assert (s.control, s.slip) == ("displacement", "auto")
    assert s.pressure == pytest.approx(1200.0) and s.gap is None
    assert s.work_of_adhesion == pytest.approx(0.4)
    assert s.source == str(path)
    assert s.priors == {}
    assert s.warnings() == []


def test_fea_case_to_dimensionless_and_back(write):
    """b = 2 mm, mu h = 2 N/m: force scale 8 mN, pressure scale 2 kPa (paper section 4)."""
    s = load_scene(write(edit(A3, "[test]\n", "[test]\ncontact_radius_max = \"0.5 mm\"\n")))
    kw = s.to_dimensionless(slip="no-slip")
    assert kw == pytest.approx({"control": "displacement", "slip": "no-slip", "p": 0.6, "w": 0.2,
                                "rs": 0.5, "a_max": 0.25, "lambda0": 2.0})
    sc = s.scales()
    assert (sc.force, sc.pressure) == pytest.approx((8e-3, 2e3))
    assert sc.from_p(kw["p"]) == pytest.approx(s.pressure)
    assert sc.from_w(kw["w"]) == pytest.approx(s.work_of_adhesion)
    assert sc.from_rs(kw["rs"]) == pytest.approx(s.substrate_radius)
    assert sc.from_a(kw["a_max"]) == pytest.approx(s.contact_radius_max)


def test_to_dimensionless_keys_are_simulate_keywords(write):
    s = load_scene(write(PRESSURE))
    kw = s.to_dimensionless(mu_h="2 N/m", work_of_adhesion=0.4)
    assert set(kw) == {"control", "slip", "d", "w", "rs", "lambda0", "p_max"}
    assert kw["d"] == pytest.approx(0.1) and kw["rs"] == math.inf
    assert kw["p_max"] == pytest.approx(1.5) and kw["w"] == pytest.approx(0.2)
    for key in ("d", "w", "rs", "lambda0", "p_max"):
        assert DIMENSIONLESS[key].contains(kw[key])


def test_overrides_win_and_round_trip():
    s = Scene(membrane_radius="3 mm", substrate_radius="2 mm", control="displacement", pressure="0.5 kPa",
              mu_h=1.0, work_of_adhesion=0.1, slip="frictionless", displacement_max="0.6 mm")
    kw = s.to_dimensionless(mu_h=1.5, work_of_adhesion="0.3 J/m^2")
    sc = Scales(3e-3, 1.5)
    assert kw["p"] == pytest.approx(sc.to_p(500.0)) and kw["w"] == pytest.approx(0.2)
    assert kw["delta_max"] == pytest.approx(0.2)
    assert sc.from_delta(kw["delta_max"]) == pytest.approx(s.displacement_max)
    assert s.to_dimensionless()["w"] == pytest.approx(0.1)   # the scene's own values


def test_scene_is_frozen_and_hashable(write):
    s = load_scene(write(A3))
    with pytest.raises(dataclasses.FrozenInstanceError):
        s.pressure = 1.0  # type: ignore[misc]
    assert hash(s) == hash(dataclasses.replace(s))


@pytest.mark.parametrize("lam0, fragment", [(1.3, "-15 %"), (1.1, "-33 %"), (1.5, "-6.7 %"), (1.7, "λ0 = 1.7")])
def test_warning_for_small_prestretch(lam0, fragment):
    s = Scene(membrane_radius=2e-3, substrate_radius=1e-3, control="displacement", pressure=100.0,
              prestretch=lam0)
    (msg,) = s.warnings()
    assert "large-stretch" in msg and fragment in msg


# ---------------------------------------------------------------------------------------------
# priors
def test_priors_parsed_to_si(write):
    text = A3 + ('\n[priors]\nwork_of_adhesion = {dist="loguniform", min="0.01 J/m^2", max="10 J/m^2"}\n'
                 'mu_h = {dist = "normal", mean = "2 N/m", sd = 0.2}\n')
    s = load_scene(write(text))
    assert s.priors == {"work_of_adhesion": {"dist": "loguniform", "min": 0.01, "max": 10.0},
                        "mu_h": {"dist": "normal", "mean": 2.0, "sd": 0.2}}
    assert normalize_priors({"mu_h": {"dist": "uniform", "min": 0, "max": "5 N/m"}}) == \
        {"mu_h": {"dist": "uniform", "min": 0.0, "max": 5.0}}


@pytest.mark.parametrize("entry, fragment", [
    ('work_of_adhesio = {dist="uniform", min=0, max=1}', "did you mean 'work_of_adhesion'"),
    ('mu_h = {dist="gamma", min=0, max=1}', "dist = 'loguniform' | 'uniform' | 'normal'"),
    ('mu_h = 3', "dist = "),
    ('mu_h = {dist="uniform", min=0}', "Missing: ['max']"),
    ('mu_h = {dist="normal", mean=1, sd=1, min=0}', "unknown: ['min']"),
    ('mu_h = {dist="uniform", min="0 kPa", max=1}', "[priors] mu_h.min must be a force per length"),
    ('mu_h = {dist="uniform", min=2, max=1}', "min < max"),
    ('mu_h = {dist="uniform", min=-1, max=1}', "min >= 0"),
    ('mu_h = {dist="loguniform", min=0, max=1}', "min > 0"),
    ('mu_h = {dist="normal", mean=2, sd=0}', "[priors] mu_h.sd must be positive"),
])
def test_prior_errors(write, entry, fragment):
    with pytest.raises(DataError) as info:
        load_scene(write(A3 + "\n[priors]\n" + entry + "\n"))
    msg = str(info.value)
    assert fragment in msg
    assert info.value.path.endswith("scene.toml") and info.value.line == A3.count("\n") + 3


def test_prior_errors_in_python_are_input_errors():
    with pytest.raises(InputError, match=r"'priors\.mu_h\.sd' parameter"):
        normalize_priors({"mu_h": {"dist": "normal", "mean": 1.0, "sd": -1.0}})
    with pytest.raises(InputError, match="'priors'"):
        normalize_priors([1, 2])  # type: ignore[arg-type]


def test_prior_table_must_be_table(write):
    with pytest.raises(DataError, match=r"\[priors\] must be a table"):
        load_scene(write('priors = 3\n' + A3))


# ---------------------------------------------------------------------------------------------
# file-level errors
def test_missing_file(tmp_path):
    with pytest.raises(DataError, match="cannot read the scene file") as info:
        load_scene(tmp_path / "nope.toml")
    assert info.value.path.endswith("nope.toml")


def test_invalid_toml_names_line(write):
    with pytest.raises(DataError, match="not valid TOML") as info:
        load_scene(write(edit(A3, 'pressure = "1.2 kPa"', 'pressure = "1.2 kPa')))
    assert info.value.line == 11


def msg_of(write, text: str) -> DataError:
    with pytest.raises(DataError) as info:
        load_scene(write(text))
    assert info.value.path.endswith("scene.toml")
    assert str(info.value).startswith(info.value.path)
    return info.value


def test_brief_message_for_missing_pressure(write):
    err = msg_of(write, edit(A3, 'pressure = "1.2 kPa"', ""))
    assert str(err).endswith("scene.toml, line 9: [test] pressure is required for control = 'displacement' "
                             "(the fixed pressure, e.g. '1.2 kPa')")


@pytest.mark.parametrize("old, new, fragment, line", [
    ("[membrane]", "[membrame]", "unknown section [membrame]; did you mean 'membrane'?", 1),
    ("[membrane]", 'radius = "2 mm"\n[membrane]', "key 'radius' is outside any section; it belongs in [membrane] or [substrate]", 1),
    ('radius = "2 mm"  ', 'raduis = "2 mm"  ', "[membrane] unknown key 'raduis'; did you mean 'radius'?", 2),
    ('slip = "auto"', 'slip = "stick"', "[interface] slip must be one of 'auto', 'no-slip', 'frictionless', "
     "got 'stick'", 15),
    ('control = "displacement"', 'control = "force"', "[test] control must be one of 'displacement', "
     "'pressure', got 'force'", 10),
    ('radius = "2 mm"  ', '', "[membrane] radius is required (e.g. '2 mm')", 1),
    ('radius = "1 mm"', '', "[substrate] radius is required (e.g. '1 mm', or 'inf' for a flat substrate)", 6),
    ('control = "displacement"', '', "[test] control is required", 9),
    ('# gap = "0 mm"', 'gap = "0 mm"', "[test] gap is not used under control = 'displacement'", 12),
    ('pressure = "1.2 kPa"', 'pressure = "3 mm"', "[test] pressure must be a pressure (e.g. '1.2 kPa'), "
     "got '3 mm'. Unit 'mm' is not a pressure.", 11),
    ('radius = "1 mm"', 'radius = "1 kPa"', "[substrate] radius must be a length", 7),
    ('radius = "2 mm"  ', 'radius = "-2 mm"  ', "[membrane] radius must be a positive length (SI units), "
     "got '-2 mm'", 2),
    ('radius = "1 mm"', 'radius = 0', "[substrate] radius must be a positive length", 7),
    ('mu_h = "2 N/m"', 'mu_h = "0 N/m"', "[membrane] mu_h must be a positive force per length", 4),
    ('mu_h = "2 N/m"', 'mu_h = "2 kPa"', "[membrane] mu_h must be a force per length", 4),
    ('work_of_adhesion = "0.4 J/m^2"', 'work_of_adhesion = "-0.4 J/m^2"',
     "[interface] work_of_adhesion must be a positive energy per area", 16),
    ("prestretch = 2.0", "prestretch = 1.0", "[membrane] prestretch must be a number in (1, 100], got 1.0", 3),
    ("prestretch = 2.0", "prestretch = 0.5", "[membrane] prestretch must be a number in (1, 100]", 3),
    ("prestretch = 2.0", 'prestretch = "two"', "[membrane] prestretch must be a dimensionless number", 3),
    ("[test]", '[test]\ncontact_radius_max = "1 mm"', "[test] contact_radius_max must be a length in (0, "
     "0.00095) m, got '1 mm'. It must stay below 0.95 R_s", 10),
    ("[test]", '[test]\ncontact_radius_max = "1.5 mm"', "[test] contact_radius_max must be", 10),
    ("[test]", '[test]\npressure_max = "3 kPa"', "[test] pressure_max must be used with pressure control only", 10),
    ("[test]", '[test]\ndisplacement_max = "5 mm"', "[test] displacement_max must be a length in (0, 0.004) m", 10),
    ("[test]", '[test]\ndisplacement_max = "0.1 mm"\ncontact_radius_max = "0.1 mm"',
     "Give at most one of contact_radius_max, displacement_max, pressure_max", 10),
    ("[interface]", "[interface]\n[interface]", "not valid TOML", None),
])
def test_scene_errors_name_file_key_and_line(write, old, new, fragment, line):
    err = msg_of(write, edit(A3, old, new))
    assert fragment in str(err)
    if line is not None:
        assert err.line == line, str(err)


@pytest.mark.parametrize("old, new, fragment", [
    ('gap = "0.2 mm"', '', "[test] gap is required for control = 'pressure' (the fixed gap"),
    ('gap = "0.2 mm"', 'gap = "0.2 mm"\npressure = "1 kPa"', "[test] pressure is not used under control = 'pressure'"),
    ('gap = "0.2 mm"', 'gap = "2 mm"', "[test] gap must be a length in (-b, b)"),
    ('gap = "0.2 mm"', 'gap = "-0.2 mm"', "Contact must start at the substrate apex"),
    ('pressure_max = "3 kPa"', 'displacement_max = "0.1 mm"', "[test] displacement_max must be used with "
     "displacement control only"),
])
def test_pressure_control_errors(write, old, new, fragment):
    assert fragment in str(msg_of(write, edit(PRESSURE, old, new)))


# ---------------------------------------------------------------------------------------------
# Python-level errors
BASE = dict(membrane_radius=2e-3, substrate_radius=1e-3, control="displacement", pressure=1200.0)


@pytest.mark.parametrize("changes, name", [
    ({"control": "force"}, "control"), ({"slip": "stick"}, "slip"), ({"membrane_radius": 0.0}, "membrane_radius"),
    ({"membrane_radius": "2 kPa"}, "membrane_radius"), ({"substrate_radius": -1.0}, "substrate_radius"),
    ({"prestretch": 1.0}, "prestretch"), ({"prestretch": True}, "prestretch"), ({"mu_h": -2.0}, "mu_h"),
    ({"work_of_adhesion": 0.0}, "work_of_adhesion"), ({"pressure": None}, "pressure"),
    ({"gap": 0.0}, "gap"), ({"contact_radius_max": 1e-3}, "contact_radius_max"),
    ({"pressure_max": 1.0}, "pressure_max"), ({"membrane_radius": math.nan}, "membrane_radius"),
    ({"membrane_radius": math.inf}, "membrane_radius"),
])
def test_scene_construction_errors_name_the_field(changes, name):
    with pytest.raises(InputError) as info:
        Scene(**{**BASE, **changes})
    assert info.value.name == name
    assert str(info.value).startswith(f"The '{name}' parameter must be ")


def test_flat_substrate_and_strings():
    s = Scene(membrane_radius="2 mm", substrate_radius="inf", control="displacement", pressure="-0.2 kPa")
    assert s.substrate_radius == math.inf and s.pressure == -200.0
    with pytest.raises(InputError, match="'pressure' parameter must be above -2 mu_h / R_s"):
        Scene(**{**BASE, "substrate_radius": 4e-3, "pressure": -1500.0}).to_dimensionless(
            mu_h=2.0, work_of_adhesion=0.4, slip="no-slip")  # p = -0.75 < -1/rs = -0.5


@pytest.mark.parametrize("kwargs, name, fragment", [
    ({"work_of_adhesion": 0.4, "slip": "no-slip"}, "mu_h", "The scene has no mu_h"),
    ({"mu_h": 2.0, "slip": "no-slip"}, "work_of_adhesion", "The scene has no work_of_adhesion"),
    ({"mu_h": 2.0, "work_of_adhesion": 0.4}, "slip", "'auto' only means 'fit both'"),
    ({"mu_h": 0.5, "work_of_adhesion": 0.4, "slip": "no-slip"}, "pressure", "That is p = 2.4"),
    ({"mu_h": 2.0, "work_of_adhesion": 25.0, "slip": "no-slip"}, "work_of_adhesion", "That is w = 12.5"),
    ({"mu_h": "2 kPa", "work_of_adhesion": 0.4, "slip": "no-slip"}, "mu_h", "force per length"),
])
def test_to_dimensionless_errors(kwargs, name, fragment):
    with pytest.raises(InputError) as info:
        Scene(**BASE).to_dimensionless(**kwargs)
    assert info.value.name == name and fragment in str(info.value)


def test_out_of_domain_message_gives_si_range():
    with pytest.raises(InputError) as info:
        Scene(**{**BASE, "pressure": 4800.0}).to_dimensionless(mu_h=2.0, work_of_adhesion=0.4, slip="no-slip")
    assert "in (-2000, 2000) Pa for b = 0.002 m, mu_h = 2 N/m" in str(info.value)


def test_pressure_max_checked_against_table():
    s = Scene(membrane_radius=2e-3, substrate_radius=math.inf, control="pressure", gap=2e-4,
              pressure_max=20e3)
    with pytest.raises(InputError, match="That is p_max = 10"):
        s.to_dimensionless(mu_h=2.0, work_of_adhesion=0.4, slip="no-slip")


def test_to_dimensionless_feeds_simulate(write):
    """Contract check against adhfit.simulate (docs/contracts.md A2b): the keywords are accepted as given."""
    import adhfit
    simulate = getattr(adhfit, "simulate", None)
    if simulate is None:
        pytest.skip("adhfit.simulate not available yet")
    s = load_scene(write(edit(A3, "[test]\n", "[test]\ncontact_radius_max = \"0.5 mm\"\n")))
    result = simulate(**s.to_dimensionless(slip="frictionless"), points=40)
    f_max_si = s.scales().from_f(result.summary["f_max"])
    assert 0.0 < f_max_si < 0.1  # newtons: a few mN at the force scale 8 mN
    assert list(result.frame.columns) == ["stage", "a", "alpha", "p", "d", "delta", "f", "G", "stable"]
