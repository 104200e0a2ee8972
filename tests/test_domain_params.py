"""One validation of ``points`` and every shared setting for both engines (issue 24, item 6).

The exact membrane's own checks (``adhfit.exact.control.prepare``, which may not import the table)
must accept and reject exactly what the parameter table (``adhfit.params.check_scene``) does; and
``adhfit.simulate`` gives the same InputError for either engine.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

import adhfit
from adhfit.errors import InputError
from adhfit.params import DIMENSIONLESS, check_scene

BASE = dict(control="displacement", slip="no-slip", p=0.6, d=None, w=0.2, rs=0.5, a_max=0.25,
            delta_max=None, p_max=None, lambda0=1.5, points=20)

PROBES = {
    "points": [10, 9, 10.5, 50_000, 50_001, np.int64(20), np.int32(20), True, 20.0, "20", None],
    "w": [1e-6, 0.99e-6, 10.0, 10.01, np.float64(0.2), np.int64(1), math.nan, math.inf],
    "rs": [0.02, 0.0199, math.inf, np.float64(0.5), -1.0],
    "lambda0": [1.0, 1.0001, 100.0, 100.1, np.int64(2)],
    "a_max": [1e-3, 0.9e-3, 0.95 * 0.5, 0.4749, np.float64(0.25)],
    "p": [-1.0, 0.9999, 1.0, -2.0 + 1e-9, -1.999, np.float32(0.6)],
}


def _table_accepts(kw):
    try:
        check_scene(**kw)
        return True
    except InputError:
        return False


def _exact_accepts(kw):
    from adhfit.exact.control import prepare
    try:
        prepare(kw["control"], kw["slip"], kw["p"], kw["d"], kw["w"], kw["rs"], kw["lambda0"], kw["a_max"],
                kw["delta_max"], kw["p_max"], kw["points"], 4)
        return True
    except InputError as err:  # the exact membrane's own domain (Case I free inflation) is not the table's
        return "Case I free inflation" in str(err)


@pytest.mark.parametrize("name,value", [(k, v) for k, vs in PROBES.items() for v in vs],
                         ids=lambda x: repr(x))
def test_exact_engine_validates_as_the_table_does(name, value):
    kw = {**BASE, name: value}
    if name == "p":
        kw["rs"] = 0.5  # -1/rs = -2: below the table's own p bound, so only (-1, 1) matters
    assert _exact_accepts(kw) == _table_accepts(kw), (name, value)


@pytest.mark.parametrize("points", [10.5, 50_001, 9, "200"])
def test_simulate_rejects_the_same_points_for_both_engines(points):
    msgs = []
    for membrane in ("large-stretch", "exact"):
        with pytest.raises(InputError) as info:
            adhfit.simulate("displacement", "no-slip", p=0.6, w=0.2, rs=0.5, a_max=0.25, lambda0=1.5,
                            points=points, membrane=membrane)
        msgs.append(str(info.value))
    assert msgs[0] == msgs[1] and "'points'" in msgs[0] and "50000" in msgs[0]


def test_numpy_integer_points_run_on_the_exact_membrane():
    r = adhfit.simulate("displacement", "no-slip", p=0.6, w=0.2, rs=0.5, a_max=0.25, lambda0=1.5,
                        points=np.int64(20), membrane="exact")
    assert len(r.frame) > 10


def test_table_bounds_of_points_are_the_documented_ones():
    row = DIMENSIONLESS["points"]
    assert (row.lower, row.upper, row.lower_open, row.upper_open) == (10, 50_000, False, False)
