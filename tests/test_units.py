"""Tests of adhfit.units: parsing physical values and the dimensionless scales (docs/contracts.md A1)."""
from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from adhfit.errors import DataError, InputError
from adhfit.units import DIMENSIONS, GROUPS, Scales, parse_quantity, unit_factor, ureg


# ---------------------------------------------------------------------------------------------
# parse_quantity
@pytest.mark.parametrize("value, dimension, expected", [
    ("2 mm", "length", 2e-3),
    ("1.2 kPa", "pressure", 1200.0),
    ("0.4 J/m^2", "energy_per_area", 0.4),
    ("2 N/m", "force_per_length", 2.0),
    ("2 N/m", "energy_per_area", 2.0),  # same dimension as J/m^2
    ("400 mJ/m^2", "energy_per_area", 0.4),
    ("3 mN", "force", 3e-3),
    ("150 um", "length", 150e-6),
    ("150 µm", "length", 150e-6),
    ("150 μm", "length", 150e-6),
    ("-0.5 kPa", "pressure", -500.0),
    ("1e-3 m", "length", 1e-3),
    (".5 mm", "length", 5e-4),
    ("2 s", "time", 2.0),
    ("2.5", "dimensionless", 2.5),
    (0.002, "length", 0.002),          # plain numbers are SI
    (3, "pressure", 3.0),
    (np.float64(1.5), "force", 1.5),
])
def test_parse_quantity_si(value, dimension, expected):
    got = parse_quantity(value, dimension, name="x")
    assert isinstance(got, float)
    assert got == pytest.approx(expected, rel=1e-12)


@pytest.mark.parametrize("value", ["inf", "Inf", "inf mm", "infinity", math.inf])
def test_parse_quantity_inf_allowed(value):
    assert parse_quantity(value, "length", name="[substrate] radius", allow_inf=True) == math.inf


@pytest.mark.parametrize("value", ["inf", math.inf, "-inf mm"])
def test_parse_quantity_inf_refused(value):
    with pytest.raises(InputError, match=r"'\[membrane\] radius'.*Infinite"):
        parse_quantity(value, "length", name="[membrane] radius")


def test_parse_quantity_negative_inf_refused_even_when_inf_allowed():
    with pytest.raises(InputError, match="Infinite"):
        parse_quantity("-inf", "length", name="r", allow_inf=True)


@pytest.mark.parametrize("value, fragment", [
    ("3 mm", "Unit 'mm' is not a pressure"),
    ("kPa", "must start with a number"),
    ("abc", "must start with a number"),
    ("1,2 kPa", "decimal point"),
    ("2 foo", "Unit 'foo' is not understood"),
    ("2 kPa)", "not understood"),
    ("2 kPa # note", "not understood"),
    ("nan kPa", "must start with a number"),
    (float("nan"), ""),
    (True, ""),
    (None, ""),
    ([1.0], ""),
    ("1200", "no unit"),
])
def test_parse_quantity_errors_name_key_value_and_expectation(value, fragment):
    with pytest.raises(InputError) as info:
        parse_quantity(value, "pressure", name="pressure")
    msg = str(info.value)
    assert "The 'pressure' parameter must be a pressure (e.g. '1.2 kPa')" in msg
    assert f"Got {value!r} instead." in msg
    assert fragment in msg
    assert info.value.name == "pressure"


def test_parse_quantity_in_file_raises_data_error_with_path():
    with pytest.raises(DataError) as info:
        parse_quantity("3 mm", "pressure", name="[test] pressure", where="scene.toml")
    msg = str(info.value)
    assert info.value.path == "scene.toml"
    assert msg.startswith("scene.toml: [test] pressure must be a pressure (e.g. '1.2 kPa'), got '3 mm'")


def test_parse_quantity_unknown_dimension():
    with pytest.raises(InputError, match="'dimension'"):
        parse_quantity("1 m", "volume", name="x")


def test_every_dimension_parses_its_own_example():
    for key, (_, _, example) in DIMENSIONS.items():
        assert math.isfinite(parse_quantity(example, key, name=key))


# ---------------------------------------------------------------------------------------------
# unit_factor
@pytest.mark.parametrize("unit, dimension, factor", [
    ("um", "length", 1e-6), ("mm", "length", 1e-3), ("m", "length", 1.0),
    ("mN", "force", 1e-3), ("uN", "force", 1e-6), ("N", "force", 1.0), ("1e-3 N", "force", 1e-3),
    ("kPa", "pressure", 1e3), ("Pa", "pressure", 1.0), ("psi", "pressure", 6894.757293168361),
    ("ms", "time", 1e-3), ("min", "time", 60.0),
])
def test_unit_factor(unit, dimension, factor):
    assert unit_factor(unit, dimension, name="col") == pytest.approx(factor, rel=1e-12)


def test_unit_factor_wrong_dimension_message():
    with pytest.raises(DataError) as info:
        unit_factor("kPa", "force", name="force [kPa]", where="curve.csv")
    assert str(info.value) == "curve.csv, column 'force [kPa]': unit kPa is not a force (e.g. 'mN')"
    assert info.value.column == "force [kPa]"
    with pytest.raises(InputError, match="unit kPa is not a force"):
        unit_factor("kPa", "force", name="force")


@pytest.mark.parametrize("unit", ["foo", "", "mm)", "m,m"])
def test_unit_factor_not_understood(unit):
    with pytest.raises(DataError, match="not understood"):
        unit_factor(unit, "length", name="displacement [x]", where="curve.csv")


# ---------------------------------------------------------------------------------------------
# Scales
def test_fea_case_scales():
    """Paper section 4 / docs/numerics.md C: b = 2 mm, mu h = 2 N/m -> 8 mN and 2 kPa, computed by hand."""
    mu, h, beta, lam0 = 2e6, 1e-6, 1e-3, 2.0
    s = Scales(b=lam0 * beta, mu_h=mu * h)
    assert s.length == pytest.approx(2e-3)
    assert s.force == pytest.approx(8e-3)       # 2 * 2 N/m * 2 mm
    assert s.pressure == pytest.approx(2e3)     # 2 * 2 N/m / 2 mm
    assert s.energy == pytest.approx(2.0)
    # W_ad = 0.4 J/m^2 -> w = 0.2; R_s = 1 mm -> rs = 0.5; 1.2 kPa -> p = 0.6; 4 mN -> f = 0.5
    assert s.to_w(0.4) == pytest.approx(0.2)
    assert s.to_rs(1e-3) == pytest.approx(0.5)
    assert s.to_p(parse_quantity("1.2 kPa", "pressure", name="P")) == pytest.approx(0.6)
    assert s.to_f(parse_quantity("4 mN", "force", name="F")) == pytest.approx(0.5)
    assert s.to_delta(parse_quantity("200 um", "length", name="x")) == pytest.approx(0.1)


def test_scales_match_pint_independently():
    """The scales as pint computes them from the formulas of docs/contracts.md A1."""
    b, mu_h = ureg.Quantity(3.7, "mm"), ureg.Quantity(0.85, "N/m")
    s = Scales(b.to("m").magnitude, mu_h.to("N/m").magnitude)
    assert s.force == pytest.approx((2 * mu_h * b).to("N").magnitude, rel=1e-14)
    assert s.pressure == pytest.approx((2 * mu_h / b).to("Pa").magnitude, rel=1e-14)
    assert s.energy == pytest.approx(mu_h.to("J/m^2").magnitude, rel=1e-14)


PAIRS = [("f", "to_f", "from_f"), ("p", "to_p", "from_p"), ("d", "to_d", "from_d"),
         ("delta", "to_delta", "from_delta"), ("a", "to_a", "from_a"), ("rs", "to_rs", "from_rs"),
         ("w", "to_w", "from_w"), ("G", "to_G", "from_G")]


def test_every_group_has_named_helpers():
    assert {g for g, _, _ in PAIRS} <= set(GROUPS)


finite = st.floats(min_value=-1e6, max_value=1e6, allow_nan=False)
positive = st.floats(min_value=1e-6, max_value=1e3)


@pytest.mark.parametrize("group, to, back", PAIRS)
@given(b=positive, mu_h=positive, x=finite)
def test_round_trip_every_group(group, to, back, b, mu_h, x):
    s = Scales(b, mu_h)
    y = getattr(s, to)(x)
    assert isinstance(y, float)
    assert getattr(s, back)(y) == pytest.approx(x, rel=1e-12, abs=1e-300)
    assert s.to_si(group, s.to_dimensionless(group, x)) == pytest.approx(x, rel=1e-12, abs=1e-300)


@pytest.mark.parametrize("group, to, back", PAIRS)
def test_helpers_use_the_right_scale(group, to, back):
    s = Scales(b=2e-3, mu_h=2.0)
    expected = {"f": 8e-3, "p": 2e3, "d": 2e-3, "delta": 2e-3, "a": 2e-3, "rs": 2e-3,
                "w": 2.0, "G": 2.0}[group]
    assert getattr(s, back)(1.0) == pytest.approx(expected)
    assert getattr(s, to)(expected) == pytest.approx(1.0)


def test_arrays_stay_arrays_and_inf_passes():
    s = Scales(2e-3, 2.0)
    out = s.to_f(np.array([8e-3, -4e-3]))
    assert isinstance(out, np.ndarray)
    np.testing.assert_allclose(out, [1.0, -0.5])
    assert s.to_rs(math.inf) == math.inf
    assert s.from_rs(math.inf) == math.inf


@pytest.mark.parametrize("b, mu_h, bad", [(0.0, 1.0, "b"), (-1.0, 1.0, "b"), (math.inf, 1.0, "b"),
                                          (1.0, 0.0, "mu_h"), (1.0, math.nan, "mu_h"),
                                          (1.0, "2 N/m", "mu_h"), (True, 1.0, "b")])
def test_scales_reject_bad_values(b, mu_h, bad):
    with pytest.raises(InputError, match=f"The '{bad}' parameter must be a finite positive number"):
        Scales(b, mu_h)


def test_scales_frozen_and_unknown_group():
    s = Scales(1.0, 1.0)
    with pytest.raises(AttributeError):
        s.b = 2.0  # type: ignore[misc]
    with pytest.raises(InputError, match="'group'"):
        s.to_si("lambda0", 1.0)


def test_edge_modules_import_no_plotting_or_fitting_libraries():
    """units, scene and data sit below fitting/report (STYLE.md layout): no matplotlib, lmfit, emcee."""
    import subprocess
    import sys
    code = ("import sys, adhfit.units, adhfit.scene, adhfit.data; "
            "print(sorted(m for m in ('matplotlib', 'lmfit', 'emcee') if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"
