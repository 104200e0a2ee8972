"""The undecided hull's draws (adhfit.planning.hull): for linear models the linearisation is exact, so its
draws must reproduce a brute-force Monte Carlo that refits both models to explicit noise vectors.  The toy is
built so that the noise that leaves the verdict undecided also moves the estimates (the other model's residual
has a component the true model can absorb), i.e. the conditioning matters; the test fails if the draws
ignored it."""
from __future__ import annotations

import math

import numpy as np
import pytest

from adhfit.fitting.selection import DECISIVE
from adhfit.planning.hull import hull_model
from adhfit.planning.information import Z95

N, K = 120, 3


def _toy(lam: float = 12.0):
    rng = np.random.default_rng(7)
    J_t = rng.standard_normal((N, K))
    J_w = J_t + 0.6 * rng.standard_normal((N, K))  # similar models, not the same column space
    H_w = J_w @ np.linalg.pinv(J_w)
    v = J_t[:, 0] + 0.5 * rng.standard_normal(N)    # partly along the true model's ln W_ad column
    r_w = (np.eye(N) - H_w) @ v                     # the other model's optimum: J_w^T r_w = 0
    r_w *= math.sqrt(lam) / np.linalg.norm(r_w)
    return J_t, J_w, r_w


def _widths(se_w: float, se_mu: float) -> dict:
    return {"work_of_adhesion": {"relative_se": se_w}, "mu_h": {"relative_se": se_mu}}


def test_linear_models_match_a_brute_force_monte_carlo():
    lam = 12.0
    J_t, J_w, r_w = _toy(lam)
    values_t = {"work_of_adhesion": 0.3, "mu_h": 1.5}
    values_w = {"work_of_adhesion": 0.3 * math.exp(0.08), "mu_h": 1.5 * math.exp(-0.03)}
    wt, ww = _widths(0.02, 0.01), _widths(0.025, 0.012)
    hm = hull_model(np.zeros(N), J_t, values_t, wt, r_w, J_w, values_w, ww, lam, N, 0.0, N)

    rng = np.random.default_rng(11)
    draws = 20_000
    e = rng.standard_normal((draws, N))
    dt = -np.linalg.lstsq(J_t, e.T, rcond=None)[0].T          # the true model refitted to e
    dw = -np.linalg.lstsq(J_w, (r_w + e).T, rcond=None)[0].T  # the other, to its residual plus e
    rss_t = np.sum((e + dt @ J_t.T) ** 2, axis=1)
    rss_w = np.sum((r_w + e + dw @ J_w.T) ** 2, axis=1)
    dbic = N * np.log(rss_w / rss_t)
    und = np.abs(dbic) <= DECISIVE
    assert hm.p_undecided() == pytest.approx(und.mean(), abs=0.02)
    for i, name in enumerate(("work_of_adhesion", "mu_h")):
        ht, hw = Z95 * wt[name]["relative_se"], Z95 * ww[name]["relative_se"]
        ct = math.log(values_t[name]) + dt[:, i]
        cw = math.log(values_w[name]) + dw[:, i]
        hull = np.exp(np.maximum(ct + ht, cw + hw)) - np.exp(np.minimum(ct - ht, cw - hw))
        brute = float(np.median(hull[und]))
        assert float(np.median(hm.undecided_hulls(name))) == pytest.approx(brute, rel=0.02), name
        if name == "work_of_adhesion":  # the conditioning matters in this toy: the undecided hull is narrower
            assert brute < 0.95 * float(np.median(hull))
