"""The forward model's domain, told exactly (issue 24): loading ends, error classes, exit statuses.

Scenes come from the random-scene audit of issue 24 (``benchmarks/stress.py``'s generator). Each test
checks an independent truth: an analytic bound (Case I at the clamp), a history run just inside the
reported bound, or the class and exit status a script relies on.
"""
from __future__ import annotations

import math
import re

import pytest

import adhfit
from adhfit.errors import ConvergenceError, DomainError, InputError


def _number_after(text, words):
    return float(re.search(re.escape(words) + r"\s*([-0-9.e]+)", text).group(1).rstrip("."))


def test_domain_error_is_its_own_class_and_keeps_convergence_handlers_working():
    err = DomainError("free membrane past vertical at the clamp", "a_max <= 0.41 (the Case I limit)",
                      "lower a_max", {"p": 0.5})
    assert isinstance(err, ConvergenceError) and isinstance(err, RuntimeError)
    text = str(err)
    assert "did not converge" not in text and "no solution exists" in text
    assert "0.41" in text and "lower a_max" in text and "\n" not in text
    assert err.inputs == {"p": 0.5} and err.bound.startswith("a_max")


def test_unreachable_p_max_names_the_case_one_limit_of_the_branch():
    # audit: "contact radius for p_max did not converge" (a solver failure where no solution exists)
    kw = dict(control="pressure", slip="frictionless", d=0.42347403563735564, w=0.14413109818857606,
              rs=56.45332132079257, lambda0=2.075339562003722)
    with pytest.raises(InputError) as info:
        adhfit.simulate(**kw, p_max=3.932091161934954)
    text = str(info.value)
    assert info.value.name == "p_max" and "\n" not in text and "Case I" in text
    top = _number_after(text, ", ")  # the range's upper end: "(p_cr, top]"
    top = float(re.search(r"\(([-0-9.e]+), ([-0-9.e]+)\]", text).group(2))
    a_top = _number_after(text, "at contact radius")
    c = 1.0 / kw["rs"]
    # independent truth: where Case I ends, sin(theta) at the clamp = kappa (1 - a^2) - c a^2 = 1
    assert top == pytest.approx((1.0 + c * a_top ** 2) / (1.0 - a_top ** 2), rel=2e-3)
    # and the engine reaches a pressure just below the reported top
    r = adhfit.simulate(**kw, p_max=0.999 * top, points=60)
    assert r.summary["f_max"] > 0.0


def test_unreachable_delta_max_names_the_analytic_case_one_radius():
    # audit: "must be reachable with a contact radius below 0.3583" (wrong: the branch ends earlier)
    p, rs = -0.922516818651314, 0.37715816622315823
    kw = dict(control="displacement", slip="frictionless", p=p, w=0.16873764075608672, rs=rs)
    with pytest.raises(InputError) as info:
        adhfit.simulate(**kw, delta_max=1.9136461824845192)
    text = str(info.value)
    a_end = _number_after(text, "leaves the model at a =")
    # making contact at fixed p: sin(theta) at the clamp = p - (p + 1/rs) a^2 reaches -1 there
    assert a_end == pytest.approx(math.sqrt((1.0 + p) / (p + 1.0 / rs)), rel=1e-5)
    top = float(re.search(r"\(0, ([-0-9.e]+)\]", text).group(1))
    # just inside, loading reaches delta_max; the frictionless pinning branch that follows ends at the Case I
    # limit (followed on its own branch since the continuation checks each step against its predictor)
    with pytest.raises(DomainError, match=r"pinning branch \(frictionless\) reaches the Case I limit"):
        adhfit.simulate(**kw, delta_max=0.999 * top, points=60)


def test_reachable_p_max_past_one_is_solved():
    r = adhfit.simulate("pressure", "no-slip", d=0.2, w=0.2, rs=0.5, p_max=1.3, points=60)
    assert r.frame["p"].iloc[len(r.frame[r.frame.stage == "making_contact"]) - 1] == pytest.approx(1.3, abs=1e-9)


# --------------------------------------------------------------------------------------------------
# DomainError where the model's end is proven; other grids before giving up


def test_making_contact_past_case_one_is_a_domain_error_with_the_analytic_bound():
    # audit: "end of loading: state outside the model's domain ... did not converge"
    p, rs = -0.9677112760706967, 0.11803455152948787
    with pytest.raises(DomainError) as info:
        adhfit.simulate("displacement", "frictionless", p=p, w=3.323790393597303, rs=rs,
                        a_max=0.06647535853862992)
    bound = _number_after(str(info.value), "a_max must stay below")
    assert bound == pytest.approx(math.sqrt((1.0 + p) / (p + 1.0 / rs)), rel=1e-5)
    assert "did not converge" not in str(info.value)
    # just inside, loading is solved and the error is pinning's own end (tests/test_core_points_independence.py
    # checks it against the 30-digit reference)
    with pytest.raises(DomainError, match=r"pinning branch \(frictionless\) reaches the Case I limit"):
        adhfit.simulate("displacement", "frictionless", p=p, w=3.323790393597303, rs=rs, a_max=0.99 * bound,
                        points=60)


def test_frictionless_delamination_leaving_the_model_is_a_domain_error_a_state_check_confirms():
    kw = dict(p=0.7416890298211145, w=5.263504219473203, rs=1.7432676236873814, a_max=0.5134500216830367)
    with pytest.raises(DomainError) as info:
        adhfit.simulate("displacement", "frictionless", **kw)
    a_end = _number_after(str(info.value), "leave Case I below a =")
    # second method: single explicit states either side of the reported radius
    from adhfit.loading import state_at
    ok = state_at("displacement", "frictionless", "delamination", **kw, a=a_end * (1 + 1e-6))
    assert math.isfinite(ok["f"])
    with pytest.raises(ConvergenceError):
        state_at("displacement", "frictionless", "delamination", **kw, a=a_end * (1 - 1e-6))


# The two audit scenes once here ("failed at points=200, solved by another row grid") were histories
# cut short at the Case I limit and labelled a no-slip branch end: DomainErrors now, checked against
# the 30-digit reference in tests/test_domain_limit.py.


def test_cli_exit_status_tells_no_solution_from_bad_input(capsys):
    from adhfit.cli.main import main
    base = ["simulate", "--control", "displacement", "--slip", "frictionless", "--p", "-0.9677112760706967",
            "--w", "3.32", "--rs", "0.11803455152948787"]
    assert main(base + ["--a-max", "0.0664"]) == 4
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "no solution exists" in err and "a_max" in err
    assert main(base + ["--a-max", "2"]) == 2


# --------------------------------------------------------------------------------------------------
# the stability contract: the first turning point on the way out, whatever the row grid

# (the audit's scene, p=0.2601 w=7.141 rs=0.1077, turned out to follow frictionless pinning up to the sphere's
# equator: a DomainError now, tests/test_core_points_independence.py; this one's control rises at once too)
RISES = dict(control="displacement", slip="frictionless", p=0.03416276052322975, w=0.03364077488803105,
             rs=0.057320739977727096, delta_max=0.179290488359483)


def test_no_stable_row_has_the_control_above_its_loading_end_value():
    # audit: stable pinning rows reached the control above delta_max (force up to 3x f_max)
    r = adhfit.simulate(**RISES, points=200)
    f = r.frame
    end = f.index[f.stage == "making_contact"][-1]
    after = f.loc[end + 1:]
    assert (after.delta[after.stable] <= RISES["delta_max"] * (1 + 1e-9)).all()
    # second method: single pinning states just past the end of loading press further in, so a test
    # that pulls back from delta_max leaves the branch at once: the turning point is the end of loading
    from adhfit.loading import state_at
    kw = {k: v for k, v in RISES.items() if k not in ("control", "slip", "delta_max")}
    s = state_at("displacement", "frictionless", "pinning", **kw, a_max=r.inputs["a_max"], alpha=1e-3)
    assert s["delta"] > RISES["delta_max"]
    assert r.summary["turning_point"]["delta"] == pytest.approx(RISES["delta_max"], abs=1e-8)


@pytest.mark.parametrize("scene", [RISES, dict(control="displacement", slip="no-slip", p=0.6, w=0.2, rs=0.5,
                                               a_max=0.25),
                                   dict(control="pressure", slip="no-slip", d=0.2, w=0.2, rs=0.5, a_max=0.25)],
                         ids=["rises-at-once", "base-displacement", "base-pressure"])
def test_turning_point_and_f_min_do_not_depend_on_points(scene):
    ref = adhfit.simulate(**scene, points=1001).summary
    for n in (10, 13, 50, 200):
        s = adhfit.simulate(**scene, points=n).summary
        for key in ("turning_point", "f_min"):
            for q in ("f", "p", "a"):
                assert s[key][q] == pytest.approx(ref[key][q], abs=1e-8), (n, key, q)
