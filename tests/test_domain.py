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
    r = adhfit.simulate(**kw, delta_max=0.999 * top, points=60)
    assert r.inputs["a_max"] < a_end


def test_reachable_p_max_past_one_is_solved():
    r = adhfit.simulate("pressure", "no-slip", d=0.2, w=0.2, rs=0.5, p_max=1.3, points=60)
    assert r.frame["p"].iloc[len(r.frame[r.frame.stage == "making_contact"]) - 1] == pytest.approx(1.3, abs=1e-9)
