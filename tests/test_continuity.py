"""Continuity of the history: across stage boundaries, across theta_a = pi/2 in no-slip pinning, and
smoothness of the rows within each stage (issue 2).

State values at a boundary are computed from both sides with ``state_at`` (each side solves its own
stage's equations), so a mismatch in the constants the stages hand over (a_m, rho_am, the onset) shows
up as a jump.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

import adhfit
from adhfit.loading import state_at

INF = math.inf
SLIPS = ("no-slip", "frictionless")
KEYS = ("a", "p", "d", "f", "delta")

#: control x (curved, flat) base cases, plus starts at p <= 0 and d < 0
CASES = [("displacement", dict(p=0.6, rs=0.5)), ("displacement", dict(p=0.6, rs=INF)),
         ("pressure", dict(d=0.0, rs=0.5)), ("pressure", dict(d=0.2, rs=INF)),
         ("displacement", dict(p=0.0, rs=0.5)), ("displacement", dict(p=-0.3, rs=0.5)),
         ("pressure", dict(d=-0.2, rs=0.5))]
IDS = [f"{c}-{'-'.join(f'{k}{v}' for k, v in kw.items())}" for c, kw in CASES]


def _kw(kw):
    return {"w": 0.2, "a_max": 0.25, **kw}


def _close(x: dict, y: dict, keys, tol):
    bad = {k: (x[k], y[k]) for k in keys if not abs(x[k] - y[k]) <= tol}
    assert not bad, bad


@pytest.mark.parametrize("slip", SLIPS)
@pytest.mark.parametrize("control,kw", CASES, ids=IDS)
def test_making_contact_to_pinning(control, kw, slip):
    kw = _kw(kw)
    mc = state_at(control, slip, "making_contact", a=kw["a_max"], **kw)
    pin = state_at(control, slip, "pinning", alpha=0.0, **kw)
    _close(mc, pin, KEYS, 1e-11)
    assert pin["G"] == pytest.approx(0.0, abs=1e-13)
    # one step into pinning moves the state by a small amount only (no jump right after the boundary)
    pin2 = state_at(control, slip, "pinning", alpha=1e-6, **kw)
    _close(pin, pin2, ("a", "p", "d", "f"), 1e-4)


@pytest.mark.parametrize("slip", SLIPS)
@pytest.mark.parametrize("control,kw", CASES, ids=IDS)
def test_pinning_to_delamination_at_onset(control, kw, slip):
    kw = _kw(kw)
    r = adhfit.simulate(control, slip, **kw)
    on = r.summary["onset"]
    w = kw["w"]
    pin_rows = r.frame[r.frame.stage == "pinning"]
    # locator of the onset: eq. (63) for frictionless; for no slip the pinned angle where G = w
    alpha_on = math.atan(math.sqrt(2 * w)) if slip == "frictionless" else float(pin_rows.alpha.iloc[-1])
    assert pin_rows.G.iloc[-1] == pytest.approx(w, rel=1e-12)
    pin = state_at(control, slip, "pinning", alpha=alpha_on, **kw)
    dl = state_at(control, slip, "delamination", a=on["a"], **kw)
    _close(pin, dl, ("a", "alpha", "p", "d", "f", "G"), 1e-9)
    assert pin["G"] == pytest.approx(w, rel=1e-10) and dl["G"] == pytest.approx(w, rel=1e-12)
    # the summary's onset is that state
    for k in ("f", "p", "a"):
        assert on[k] == pytest.approx(dl[k], abs=1e-9), k
    # frame: last pinning row is the onset, and the first delamination row is a short step away
    first_dl = r.frame[r.frame.stage == "delamination"].iloc[0]
    last_pin = pin_rows.iloc[-1]
    assert last_pin.f == pytest.approx(on["f"], abs=1e-9) and last_pin.a == pytest.approx(on["a"], abs=1e-12)
    assert abs(first_dl.a - on["a"]) < 0.01 * kw["a_max"]
    assert abs(first_dl.f - on["f"]) < 0.02 * r.summary["f_max"]


# ---------------------------------------------------------------------------------------------
# theta_a = pi/2 in no-slip pinning (eq. 41 -> eq. 42), reached under pressure control
# ---------------------------------------------------------------------------------------------
PI2 = dict(d=0.3, rs=INF, a_max=0.3, w=3.0)


def test_no_slip_pinning_reaches_theta_a_beyond_half_pi():
    r = adhfit.simulate("pressure", "no-slip", **PI2)
    pin = r.frame[r.frame.stage == "pinning"]
    theta_a = pin.alpha - np.arcsin(pin.a / PI2["rs"])
    assert (theta_a > math.pi / 2 + 0.05).sum() >= 3 and (theta_a < math.pi / 2).sum() >= 10
    assert (pin.p < -1).any()           # strongly negative pressure (docs/numerics.md C)
    # delta is undefined there (|p| > 1) and left NaN, and only there
    assert pin.delta.isna().equals(pin.p.abs() > 1)


def test_no_slip_pinning_continuous_across_theta_a_half_pi():
    at = lambda al: state_at("pressure", "no-slip", "pinning", alpha=al, **PI2)  # noqa: E731
    mid = at(math.pi / 2)
    assert mid["alpha"] == pytest.approx(math.pi / 2, abs=1e-12)
    coarse = {k: abs(at(math.pi / 2 + 1e-2)[k] - at(math.pi / 2 - 1e-2)[k]) / 2e-2 for k in ("f", "p", "G")}
    for h in (1e-4, 1e-6, 1e-8):
        lo, hi = at(math.pi / 2 - h), at(math.pi / 2 + h)
        for k in ("f", "p", "G"):
            # bounded difference quotient across the switch (Lipschitz with the coarse slope)
            q = abs(hi[k] - lo[k]) / (2 * h)
            assert q <= 2 * coarse[k] + 1e-6, (k, h, q, coarse[k])
            # and no kink: the one-sided slopes agree (C1), up to O(h) and rounding / h
            left = (mid[k] - lo[k]) / h
            right = (hi[k] - mid[k]) / h
            assert abs(left - right) <= 10 * coarse[k] * h + 1e-13 / h, (k, h, left, right)


# ---------------------------------------------------------------------------------------------
# rows within each stage lie on a smooth curve
# ---------------------------------------------------------------------------------------------
SMOOTH = [(c, s, kw) for c, kw in CASES[:4] for s in SLIPS] + [("pressure", "no-slip", PI2)]

def _smooth_params():
    out = []
    for c, s, kw in SMOOTH:
        out.append(pytest.param(c, s, kw, 1000, id=f"{c}-{s}-{kw}"))
    # a row count whose first pinning locator once stalled the pressure-control continuation
    out.append(pytest.param("pressure", "no-slip", dict(d=0.0, rs=0.5), 1500, id="pressure-no-slip-d0-1500"))
    return out


@pytest.mark.parametrize("control,slip,kw,points", _smooth_params())
def test_rows_within_a_stage_are_a_smooth_curve(control, slip, kw, points):
    """Second differences over the rows of a stage stay small relative to the stage's largest first
    difference. Rows are placed by smooth maps of the row index (cosine clustering), so for a smooth
    branch the ratio is O(1/n) (~0.03 at 1000 points); one row off the curve by a fraction e of a
    typical step gives ~e, a jump gives ~1. The solved extrema rows (inserted between grid rows) are
    taken out first."""
    r = adhfit.simulate(control, slip, points=points, **_kw(kw))
    fr = r.frame
    extra = {(r.summary[k]["a"], r.summary[k]["f"]) for k in ("f_min", "turning_point")}
    for stage in ("making_contact", "pinning", "delamination"):
        g = fr[fr.stage == stage]
        g = g[[(a, f) not in extra for a, f in zip(g.a, g.f)]]
        assert len(g) >= 0.1 * points
        for col in ("a", "alpha", "p", "d", "f", "G"):
            y = g[col].to_numpy()
            d1 = np.diff(y)
            big = np.max(np.abs(d1))
            if big == 0.0:
                continue
            ratio = np.max(np.abs(np.diff(d1))) / big
            assert ratio < 0.1, (stage, col, ratio, int(np.argmax(np.abs(np.diff(d1)))))


def test_pressure_no_slip_history_at_1000_points():
    r = adhfit.simulate("pressure", "no-slip", d=0.0, w=0.2, rs=0.5, a_max=0.25, points=1000)
    assert 1000 <= len(r.frame) <= 1005
