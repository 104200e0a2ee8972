"""Every bad input of ``adhfit.simulate`` is an InputError naming the parameter, the value and the
valid range (issue 2; STYLE.md habit 3). Cases are driven from the parameter table
``adhfit.params.DIMENSIONLESS`` so a change of a bound is tested where it is made."""
from __future__ import annotations

import math

import numpy as np
import pytest

import adhfit
from adhfit.errors import InputError
from adhfit.loading import state_at
from adhfit.params import DIMENSIONLESS, _fmt, check_scene

INF = math.inf
NAN = math.nan

#: a valid scene for each parameter to be spoiled in (curved substrate: every p, d in (-1, 1) is allowed)
DC = dict(control="displacement", slip="no-slip", p=0.6, w=0.2, rs=0.5, a_max=0.25)
PC = dict(control="pressure", slip="frictionless", d=0.2, w=0.2, rs=0.5, a_max=0.25)
BASE = {"p": DC, "d": PC, "w": DC, "rs": {**DC, "a_max": 0.01}, "a_max": {**DC, "rs": INF},
        "delta_max": {**{k: v for k, v in DC.items() if k != "a_max"}, "delta_max": 0.1},
        "p_max": {**{k: v for k, v in PC.items() if k != "a_max"}, "p_max": 0.7},
        "lambda0": DC, "points": DC}
CHECK_KW = dict(p=None, d=None, a_max=None, delta_max=None, p_max=None, lambda0=2.0, points=200)


def _scene(name, value):
    kw = dict(BASE[name])
    kw[name] = value
    return kw


def _outside(name):
    """Values just outside the table's bounds (the bound itself where it is open), plus the
    kinds of value that are never numbers in range."""
    row = DIMENSIONLESS[name]
    out = []
    for bound, is_open, step in ((row.lower, row.lower_open, -1), (row.upper, row.upper_open, +1)):
        if math.isinf(bound):
            continue
        if is_open:
            out.append(bound)
        eps = 1 if name == "points" else max(1e-9, 1e-9 * abs(bound))
        out.append(bound + step * eps)
        out.append(bound + step * (1 if name == "points" else 0.5 + abs(bound)))
    out += [NAN, -INF, True, False, "0.5", None if name not in ("lambda0", "points") else "x"]
    if not (math.isinf(row.upper) and not row.upper_open):
        out.append(INF)
    if name == "points":
        out += [10.5, 200.0, NAN]
    return [(name, v) for v in out if not (name in ("p", "d", "a_max", "delta_max", "p_max") and v is None)]


TABLE_CASES = [c for name in DIMENSIONLESS for c in _outside(name)]


def _assert_names(err: InputError, name: str, value, valid_hint: str | None = None):
    msg = str(err)
    assert isinstance(err, ValueError) and isinstance(err, adhfit.AdhfitError)
    assert err.name == name
    if isinstance(value, float) and math.isnan(value):
        assert isinstance(err.value, float) and math.isnan(err.value)
    else:
        assert err.value is value or err.value == value
    assert f"'{name}'" in msg, msg
    assert repr(value) in msg, msg
    if valid_hint is not None:
        assert valid_hint in msg, msg
    assert "\n" not in msg


@pytest.mark.parametrize("name,value", TABLE_CASES, ids=[f"{n}={v!r}" for n, v in TABLE_CASES])
def test_out_of_table_range_is_named_input_error(name, value):
    row = DIMENSIONLESS[name]
    with pytest.raises(InputError) as info:
        adhfit.simulate(**_scene(name, value))
    # the valid range as the table states it: both bounds, with their open/closed brackets
    lo = "(" if row.lower_open else "["
    hi = ")" if row.upper_open else "]"
    _assert_names(info.value, name, value)
    msg = str(info.value)
    assert f"{_fmt(row.lower)}, {_fmt(row.upper)}{hi}" in msg and f"{lo}{_fmt(row.lower)}," in msg, msg


def _inside(name):
    row = DIMENSIONLESS[name]
    vals = []
    for bound, is_open, step in ((row.lower, row.lower_open, +1), (row.upper, row.upper_open, -1)):
        if math.isinf(bound):
            vals.append(bound)
            continue
        vals.append(bound + step * (1 if name == "points" else 1e-9 * max(1.0, abs(bound))) if is_open else bound)
    return [(name, v) for v in vals]


INSIDE = [c for name in DIMENSIONLESS for c in _inside(name)]


@pytest.mark.parametrize("name,value", INSIDE, ids=[f"{n}={v!r}" for n, v in INSIDE])
def test_values_at_and_just_inside_the_bounds_pass_validation(name, value):
    kw = _scene(name, value)
    if name == "rs" and value < 1:
        kw["a_max"] = 0.9 * 0.95 * value
    if name == "points":
        value = int(value)
        kw["points"] = value
    out = check_scene(**{**CHECK_KW, **kw})
    assert out[name] == value


def test_numpy_and_int_numbers_are_accepted():
    r = adhfit.simulate("displacement", "no-slip", p=np.float64(0.6), w=1, rs=np.float32(0.5),
                        a_max=0.25, points=np.int64(50))
    assert 50 <= len(r.frame) <= 55


# ---------------------------------------------------------------------------------------------
# words, missing and conflicting inputs, cross-parameter constraints
# ---------------------------------------------------------------------------------------------
@pytest.mark.parametrize("name,value", [("control", "force"), ("control", None), ("control", "Displacement"),
                                        ("slip", "sticky"), ("slip", None), ("slip", "no_slip")])
def test_bad_words(name, value):
    with pytest.raises(InputError) as info:
        adhfit.simulate(**{**DC, name: value})
    _assert_names(info.value, name, value)
    choices = ("'displacement'", "'pressure'") if name == "control" else ("'no-slip'", "'frictionless'")
    assert all(c in str(info.value) for c in choices)


def test_missing_fixed_pressure_under_displacement_control():
    with pytest.raises(InputError) as info:
        adhfit.simulate(**{**DC, "p": None})
    _assert_names(info.value, "p", None, "(-1, 1)")


def test_missing_fixed_gap_under_pressure_control():
    with pytest.raises(InputError) as info:
        adhfit.simulate(**{**PC, "d": None})
    _assert_names(info.value, "d", None, "(-1, 1)")


def test_fixed_value_of_the_other_control_is_rejected():
    with pytest.raises(InputError) as info:
        adhfit.simulate(**{**DC, "d": 0.1})
    _assert_names(info.value, "d", 0.1)
    with pytest.raises(InputError) as info:
        adhfit.simulate(**{**PC, "p": 0.1})
    _assert_names(info.value, "p", 0.1)


@pytest.mark.parametrize("ends", [{}, {"a_max": 0.2, "delta_max": 0.1}, {"a_max": 0.2, "p_max": 0.7},
                                  {"delta_max": 0.1, "p_max": 0.7}, {"a_max": 0.2, "delta_max": 0.1, "p_max": 0.7}])
def test_exactly_one_loading_end(ends):
    kw = {k: v for k, v in DC.items() if k != "a_max"}
    with pytest.raises(InputError) as info:
        adhfit.simulate(**kw, **ends)
    err = info.value
    assert err.name in ("a_max", "delta_max", "p_max")
    assert all(k in str(err) for k in ("a_max", "delta_max", "p_max")), str(err)


def test_loading_end_of_the_wrong_control():
    kw = {k: v for k, v in PC.items() if k != "a_max"}
    with pytest.raises(InputError) as info:
        adhfit.simulate(**kw, delta_max=0.1)
    _assert_names(info.value, "delta_max", 0.1, "displacement control")
    kw = {k: v for k, v in DC.items() if k != "a_max"}
    with pytest.raises(InputError) as info:
        adhfit.simulate(**kw, p_max=0.7)
    _assert_names(info.value, "p_max", 0.7, "pressure control")


@pytest.mark.parametrize("rs,a_max", [(0.2, 0.19), (0.2, 0.2), (0.5, 0.9), (0.02, 0.019)])
def test_contact_radius_on_the_upper_hemisphere(rs, a_max):
    with pytest.raises(InputError) as info:
        adhfit.simulate(**{**DC, "rs": rs, "a_max": a_max})
    _assert_names(info.value, "a_max", a_max, f"{0.95 * rs:g}")


@pytest.mark.parametrize("rs,p", [(2.0, -0.5), (2.0, -0.6), (INF, 0.0), (INF, -0.3), (1.1, -0.95)])
def test_membrane_less_concave_than_substrate(rs, p):
    with pytest.raises(InputError) as info:
        adhfit.simulate(**{**DC, "rs": rs, "p": p})
    _assert_names(info.value, "p", p, f"({_fmt(0.0 - (0.0 if math.isinf(rs) else 1 / rs))}, 1)")


@pytest.mark.parametrize("rs,d", [(2.0, -2 + math.sqrt(3) - 1e-9), (2.0, -0.3), (INF, 0.0), (INF, -0.1), (1.5, -0.6)])
def test_gap_must_let_contact_start_at_the_apex(rs, d):
    assert 2 * d / (1 + d * d) <= -(0.0 if math.isinf(rs) else 1 / rs)     # the case is invalid
    with pytest.raises(InputError) as info:
        adhfit.simulate(**{**PC, "rs": rs, "d": d})
    _assert_names(info.value, "d", d, "2d/(1+d^2)")


def test_gap_just_valid_is_accepted():
    d = -2 + math.sqrt(3) + 1e-6                                      # p_cr just above -1/rs = -0.5
    out = check_scene(**{**CHECK_KW, **PC, "rs": 2.0, "d": d})
    assert out["d"] == d


def test_unreachable_displacement_is_named():
    # the most displacement reachable on the upper hemisphere (a_max -> 0.95 rs) is below 1.9
    with pytest.raises(InputError) as info:
        adhfit.simulate("displacement", "no-slip", p=0.6, w=0.2, rs=0.5, delta_max=1.9)
    _assert_names(info.value, "delta_max", 1.9, "(0, ")


@pytest.mark.parametrize("p_max", [0.3, 0.384615384615, -0.5])
def test_pressure_below_contact_is_named(p_max):
    # p_cr(0.2) = 0.4/1.04 = 0.3846...: contact has not started below it
    with pytest.raises(InputError) as info:
        adhfit.simulate("pressure", "no-slip", d=0.2, w=0.2, rs=0.5, p_max=p_max)
    _assert_names(info.value, "p_max", p_max, "0.384615")


def test_state_at_rejects_a_bad_stage_and_locator():
    with pytest.raises(InputError) as info:
        state_at("displacement", "no-slip", "peeling", p=0.6, w=0.2, rs=0.5, a_max=0.25, a=0.1)
    _assert_names(info.value, "stage", "peeling", "making_contact")
    with pytest.raises(InputError) as info:
        state_at("displacement", "no-slip", "pinning", p=0.6, w=0.2, rs=0.5, a_max=0.25, alpha=NAN)
    assert info.value.name == "alpha"
    with pytest.raises(InputError) as info:
        state_at("displacement", "no-slip", "pinning", p=0.6, w=0.2, rs=0.5, a_max=0.25, alpha=3.0)
    assert info.value.name == "alpha" and "onset" in str(info.value)
