"""Exact membrane against a complete independent solve (slow: adaptive scipy integration inside
scipy root finders, ~1 min): end of loading and onset of delamination, frictionless, lambda0 = 1.5."""
from __future__ import annotations

import pytest
from scipy.optimize import brentq, fsolve

from adhfit.exact.history import exact_history
from tests import exact_reference as ref

P, W, RS, A_MAX, LAM0 = 0.6, 0.2, 0.5, 0.25, 1.5


@pytest.mark.slow
def test_loading_end_and_onset_against_independent_solve():
    h = exact_history("displacement", "frictionless", p=P, w=W, rs=RS, a_max=A_MAX, lambda0=LAM0, points=20)
    # end of loading: the reference finds the material point of the contact edge with a = a_max
    rho_m = brentq(lambda r: ref.making_contact(P, LAM0, RS, r)[0] - A_MAX, 0.1, 0.2, xtol=1e-14)
    a, d_m, f_m = ref.making_contact(P, LAM0, RS, rho_m)
    assert h.summary["f_max"] == pytest.approx(f_m, abs=1e-7)
    d0, _ = ref.free_inflation(P, LAM0)
    # onset: (lc, alpha) with the clamp condition and G = w at the pinned edge rho_m
    on = [s for s, st in zip(h.states, h.columns["stage"]) if st == "pinning"][-1]

    def eqs(x):
        r_end, _, _, g = ref.edge_state(P, LAM0, RS, x[0], rho_m, x[1], "frictionless")
        return [r_end - 1, g - W]

    lc, alpha = fsolve(eqs, [on.lc * 1.001, on.alpha * 0.99], xtol=1e-13)
    _, d_on, f_on, _ = ref.edge_state(P, LAM0, RS, lc, rho_m, alpha, "frictionless")
    assert h.summary["onset"]["f"] == pytest.approx(f_on, abs=1e-7)
    assert h.summary["onset"]["delta"] == pytest.approx(d0 - d_on, abs=1e-7)
