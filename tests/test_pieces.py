"""The compiled PCHIP and the force's pieces along a history, against scipy's PchipInterpolator.

The fit evaluates the model through :mod:`adhfit.core.pieces` (no scipy object per history). The
reference here is scipy's own ``PchipInterpolator`` built from the history's rows the way the
model's docstring describes (making contact in x, retraction in u = sqrt(x - x_tp)), so the two
share no code.
"""
from __future__ import annotations

import numpy as np
import pytest
from scipy.interpolate import PchipInterpolator

from adhfit.core import pchip
from adhfit.fitting.model import pieces_from_columns, stage_counts
from adhfit.loading import history


@pytest.mark.parametrize("n", [2, 3, 4, 7, 60])
def test_pchip_matches_scipy_inside_and_outside(n):
    rng = np.random.default_rng(n)
    for _ in range(20):
        x = np.sort(rng.uniform(-1.0, 2.0, n))
        x = x[np.concatenate([[True], np.diff(x) > 0])]
        y = np.cumsum(rng.normal(size=x.size))
        y[rng.uniform(size=x.size) < 0.2] = 0.0  # flat and sign-changing secants
        q = np.linspace(x[0] - 0.5, x[-1] + 0.5, 501)
        ref = PchipInterpolator(x, y, extrapolate=True)(q)
        got = pchip.evaluate(x, y, pchip.slopes(x, y), q)
        assert np.max(np.abs(got - ref)) <= 1e-12 * (1 + np.max(np.abs(ref)))


def _reference_force(columns, key, xq_load, xq_unload, y="f"):
    """The model's force (or ``y``) from scipy interpolants over the history's rows (as model.py describes)."""
    stage, stable = np.asarray(columns["stage"]), np.asarray(columns["stable"], bool)
    x, f = np.asarray(columns[key], float), np.asarray(columns[y], float)
    mc = np.flatnonzero(stage == "making_contact")
    keep = np.concatenate([[True], np.diff(x[mc]) > 0])
    load = PchipInterpolator(x[mc][keep], f[mc][keep])
    x0, x1 = x[mc][keep][0], x[mc][keep][-1]
    f_load = np.where(xq_load <= x0, 0.0, load(np.clip(xq_load, x0, x1)))
    j_tp = np.flatnonzero(stable)[-1]
    x_tp, f_tp = x[j_tp], f[j_tp]
    pin = np.flatnonzero((stage == "pinning") & stable)
    dl = np.flatnonzero((stage == "delamination") & stable)
    onset = pin[-1] if pin.size else mc[-1]
    parts = []
    for rows in (np.concatenate([[mc[-1]], pin]), np.concatenate([[onset], dl]) if dl.size else None):
        if rows is None:
            continue
        u = np.sqrt(np.clip(x[rows] - x_tp, 0, None))[::-1]
        v = f[rows][::-1]
        k = np.concatenate([[True], np.diff(u) > 0])
        if k.sum() >= 2:
            parts.append((u[k][0], u[k][-1], PchipInterpolator(u[k], v[k])))
    parts.sort(key=lambda p: p[0])
    u = np.minimum(np.sqrt(np.clip(xq_unload - x_tp, 0, None)), parts[-1][1])
    out = np.full(u.shape, f_tp)
    for lo, hi, interp in parts:
        m = (u >= lo) & (u <= hi)
        out[m] = interp(u[m])
    return f_load, out


CASES = [("displacement", "no-slip", {"p": 0.6, "delta_max": 0.05}),
         ("displacement", "frictionless", {"p": 0.6, "delta_max": 0.05}),
         ("displacement", "frictionless", {"p": -0.2, "delta_max": 0.04}),
         ("pressure", "no-slip", {"d": 0.2, "p_max": 0.9}),
         ("pressure", "frictionless", {"d": 0.2, "p_max": 0.9})]


@pytest.mark.parametrize("control,slip,kw", CASES)
def test_force_pieces_match_scipy_interpolants(control, slip, kw):
    h = history(control, slip, w=0.2, rs=0.5, points=150, **kw)
    key = "delta" if control == "displacement" else "p"
    assert h.counts == stage_counts(h.columns)
    pcs = pieces_from_columns(h.columns, control, h.counts)
    x = np.asarray(h.columns[key], float)
    lo, hi = np.nanmin(x), np.nanmax(x)
    q = np.linspace(lo - 0.1 * (hi - lo), hi + 0.1 * (hi - lo), 2001)
    ref_load, ref_unload = _reference_force(h.columns, key, q, q)
    scale = np.max(np.abs(h.columns["f"]))
    assert np.max(np.abs(pcs.f_loading(q) - ref_load)) <= 1e-12 * scale
    assert np.max(np.abs(pcs.f_unloading(q) - ref_unload)) <= 1e-12 * scale
    # the pieces pass through the history's rows: the end of loading and the turning point
    assert pcs.f_tp == pytest.approx(h.summary["turning_point"]["f"], abs=1e-14)
    assert pcs.f_loading(np.array([pcs.x_max]))[0] == pytest.approx(h.summary["f_max"], abs=1e-14)


@pytest.mark.parametrize("control,slip,kw", CASES[::2])
def test_radius_pieces_match_scipy_interpolants(control, slip, kw):
    h = history(control, slip, w=0.2, rs=0.5, points=150, **kw)
    key = "delta" if control == "displacement" else "p"
    pcs = pieces_from_columns(h.columns, control, h.counts)
    x = np.asarray(h.columns[key], float)
    q = np.linspace(np.nanmin(x), np.nanmax(x), 1001)
    ref_load, ref_unload = _reference_force(h.columns, key, q, q, y="a")
    assert np.max(np.abs(pcs.a_loading(q) - np.clip(ref_load, 0, None))) <= 1e-12
    assert np.max(np.abs(pcs.a_unloading(q) - np.clip(ref_unload, 0, None))) <= 1e-12
