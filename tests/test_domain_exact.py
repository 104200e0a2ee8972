"""The exact membrane's domain (issue 24, items 1 and 6): no truncated history passed off as a branch
end, and its own domain check (a compressive adhesionless contact force).

Scenes come from the issue-24 audit (``benchmarks/stress.py``'s generator, lambda0 log-uniform in
[1.05, 3], the exact membrane at 200 rows). Before this fix each of them returned a history that
stopped early and was labelled ``delamination_ends_at_a``.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

import adhfit
from adhfit.errors import ConvergenceError, DomainError

TRUNCATED = [
    dict(control="displacement", slip="no-slip", p=0.6618944252161427, w=9.898093532833881,
         rs=5.814209483283326, a_max=0.9048493428688851, lambda0=1.7989803601293977),
    dict(control="displacement", slip="frictionless", p=0.4691367340872521, w=7.113438608345322,
         rs=2.6214100096613753, a_max=0.6454509101002188, lambda0=1.421616338822521),
    dict(control="displacement", slip="frictionless", p=0.9225987432188596, w=0.16995795450966567,
         rs=6.169983249504339, a_max=0.3893790952782369, lambda0=1.2690597311880274),
]


@pytest.mark.parametrize("scene", TRUNCATED, ids=["no-slip", "frictionless-w7", "frictionless-w0.17"])
def test_a_delamination_march_that_stops_raises_or_finishes(scene):
    try:
        r = adhfit.simulate(**scene, points=200, membrane="exact")
    except ConvergenceError as err:
        assert "before detachment" in str(err) and "\n" not in str(err)
        return
    f = r.frame
    ends = r.inputs.get("delamination_ends_at_a")
    if ends is None:  # finished: it runs on toward detachment (A2)
        assert f["a"].iloc[-1] <= 1e-2 * r.inputs["a_max"]
    else:  # a no-slip branch end: alpha is 0 there (docs/numerics.md B5), never a frictionless history
        assert scene["slip"] == "no-slip" and abs(f["alpha"].iloc[-1]) < 1e-6


def _apex_curvature(p, lambda0):
    """Free-membrane apex curvature (over 1/b) of the exact membrane: P = 2 T kappa with the
    equibiaxial neo-Hookean tension T = mu h (1 - lambda_c^-6); lambda_c from the engine's free state."""
    from adhfit.exact.control import _free_at_p
    lc = _free_at_p(p, lambda0, 8).lc
    return p / (1.0 - lc ** -6)


@pytest.mark.parametrize("slip", ["frictionless", "no-slip"])
def test_tensile_adhesionless_contact_is_a_domain_error(slip):
    # audit: p just above -1/rs at small lambda0 gave f_max < 0 without complaint
    rs, lambda0 = 2.0, 1.1
    with pytest.raises(DomainError) as info:
        adhfit.simulate("displacement", slip, p=-0.49, w=0.1, rs=rs, a_max=0.3, lambda0=lambda0,
                        membrane="exact", points=40)
    text = str(info.value)
    assert "tensile" in text and "did not converge" not in text and "\n" not in text
    # independent truth: the exact free apex is more concave than the substrate
    assert _apex_curvature(-0.49, lambda0) < -1.0 / rs


def test_compressive_scene_near_the_bound_still_runs():
    # large pre-stretch: the exact apex curvature is close to p, above -1/rs = -0.5
    assert _apex_curvature(-0.45, 3.0) > -0.5
    r = adhfit.simulate("displacement", "frictionless", p=-0.45, w=0.1, rs=2.0, a_max=0.3, lambda0=3.0,
                        membrane="exact", points=40)
    assert r.summary["f_max"] > 0.0 and math.isfinite(r.summary["f_min"]["f"])


@pytest.mark.parametrize("scene", [
    dict(control="displacement", slip="no-slip", p=0.6, w=0.2, rs=0.5, a_max=0.25, lambda0=1.5),
    dict(control="pressure", slip="frictionless", d=0.2, w=0.2, rs=0.5, a_max=0.25, lambda0=1.2),
], ids=["displacement-no-slip", "pressure-frictionless"])
def test_exact_summary_does_not_depend_on_points(scene):
    # audit: up to 80 % at 10-11 rows; the README promises extrema located to 1e-8
    ref = adhfit.simulate(**scene, points=1001, membrane="exact").summary
    for n in (10, 11, 50):
        s = adhfit.simulate(**scene, points=n, membrane="exact").summary
        assert s["f_max"] == pytest.approx(ref["f_max"], abs=1e-8)
        for key in ("onset", "f_min", "turning_point"):
            for q in ("f", "p", "a"):
                assert s[key][q] == pytest.approx(ref[key][q], abs=1e-8), (n, key, q)


def test_exact_f_min_is_the_least_force_of_the_history():
    # audit: f_min reported above a pinning row's force (the search looked at delamination only).  The audit's
    # scene (w = 1.717) is now a proven end (its pinning branch turns past vertical at the clamp at G = 0.4245,
    # before G reaches w). At w = 0.4 the same scene's history was the branch retracting d through pinning
    # states with alpha < 0 (the membrane inside the substrate); it is now the branch that presses on, whose
    # force rises from the end of loading: the least force is a pinning row's in a seed-7 stress scene
    sc = dict(control="displacement", slip="no-slip", p=-0.7699527810979117, w=1.7168078585792619,
              rs=0.35115934066785875, a_max=0.2800773190109454, lambda0=1.937789535932881)
    with pytest.raises(DomainError, match="turns past vertical at the clamp"):
        adhfit.simulate(**sc, membrane="exact")
    r = adhfit.simulate(control="displacement", slip="no-slip", p=0.6326762076381514, w=7.829597237075857,
                        rs=3.460309376048547, a_max=0.1440978301907819, lambda0=1.3502499338914362,
                        membrane="exact")
    f = r.frame
    pinning, delamination = f.f[f.stage == "pinning"].min(), f.f[f.stage == "delamination"].min()
    assert pinning < delamination  # the case the audit found: the least force lies in pinning
    assert r.summary["f_min"]["f"] == pytest.approx(pinning, abs=1e-12)
    assert r.summary["f_min"]["f"] <= f.f[f.stage != "making_contact"].min() + 1e-12


# --------------------------------------------------------------------------------------------------
# making contact past the exact membrane's Case I limit (stress run, seed 24: 82 of 1000 exact scenes
# were "the free membrane turns past vertical at the clamp ... did not converge")

PAST_VERTICAL = dict(control="pressure", slip="frictionless", d=0.64296375436047, w=0.0693702693121474,
                     rs=math.inf, a_max=0.677602256799158, lambda0=1.926539)


def test_making_contact_past_the_case_one_limit_names_the_largest_a_max():
    from adhfit.errors import InputError
    with pytest.raises(InputError) as info:
        adhfit.simulate(**PAST_VERTICAL, points=60, membrane="exact")
    text = str(info.value)
    assert info.value.name == "a_max" and "Case I exact membrane" in text
    bound = float(text.split("[0.001, ")[1].split("]")[0])
    # second method: the exact engine's own making-contact states either side of the bound, each solved
    # on its own from the free inflation: Case I just below, past vertical at the clamp just above
    from adhfit.exact.control import prepare
    from adhfit.exact.history import march
    from adhfit.exact.stages import PastVertical, making_contact
    from adhfit.exact.state import Config
    kw = {k: PAST_VERTICAL[k] for k in ("control", "slip", "d", "w", "rs", "lambda0")}
    c = prepare(kw["control"], kw["slip"], None, kw["d"], kw["w"], kw["rs"], kw["lambda0"], 0.5 * bound,
                None, None, 60, 8)
    stage = making_contact(Config(c.lambda0, c.crv, c.n), c.control, c.p, c.d)
    x0 = [c.free.lc, 1e-3 / c.free.lc, c.free.p]
    grid = bound * (1 - 1e-4) * (0.05 + 0.95 * (1 - (1 - np.linspace(0, 1, 40)) ** 2))  # dense at the end
    below = march(stage, list(grid), x0)
    assert below[-1].theta_end < 0.5 * math.pi
    with pytest.raises(PastVertical):
        stage.solve(bound * (1 + 1e-4), stage.x(below[-1]))
    # and a history runs just inside it
    r = adhfit.simulate(**{**PAST_VERTICAL, "a_max": 0.999 * bound}, points=60, membrane="exact")
    assert r.inputs["a_max"] == pytest.approx(0.999 * bound)


#: exact pinning that turns past vertical at the clamp before G reaches w (stress run, seed 24: one of
#: the 68 "G does not reach w before the pinning branch ends ... did not converge")
PIN_PAST_VERTICAL = dict(control="displacement", slip="frictionless", p=0.9622870083761739,
                         w=1.5748326323546618, rs=math.inf, a_max=0.6954599904542166,
                         lambda0=1.2667544447593715)


def test_exact_pinning_past_the_case_one_limit_is_a_domain_error_between_solved_states():
    with pytest.raises(DomainError) as info:
        adhfit.simulate(**PIN_PAST_VERTICAL, points=60, membrane="exact")
    assert "turns past vertical at the clamp" in str(info.value) and "did not converge" not in str(info.value)
    alpha_end = info.value.inputs["locator"]
    # second method: the engine's pinning states solved one by one along alpha up to just below the
    # reported limit stay Case I, the clamp angle closing on pi/2; just above it they are past vertical
    from adhfit.exact.control import prepare
    from adhfit.exact.history import _loading, march
    from adhfit.exact.stages import PastVertical, pinning
    from adhfit.exact.state import Config
    sc = PIN_PAST_VERTICAL
    c = prepare(sc["control"], sc["slip"], sc["p"], None, sc["w"], sc["rs"], sc["lambda0"], sc["a_max"],
                None, None, 60, 8)
    cfg = Config(c.lambda0, c.crv, c.n)
    _, m = _loading(cfg, c)
    pin = pinning(cfg, c.control, c.slip, m, c.p, c.d)
    alphas = alpha_end * (1 - np.geomspace(0.5, 1e-7, 60))
    states = march(pin, list(alphas), pin.x(m))
    theta = [s.theta_end for s in states]
    assert all(t < 0.5 * math.pi for t in theta) and 0.5 * math.pi - theta[-1] < 1e-3
    assert states[-1].G < sc["w"]
    with pytest.raises(PastVertical):
        pin.solve(alpha_end * (1 + 1e-6), pin.x(states[-1]))
