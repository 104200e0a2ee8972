"""MCMC of a test series (adhfit.fitting.global_mcmc; issue 13).

* the joint likelihood against an independent computation: every curve's force rows, its pull-off
  term and its contact-radius rows as Gaussian blocks with their own σ (scipy.stats.norm), and with σ
  unknown each block's σ integrated out numerically (scipy.integrate.quad of the likelihood times 1/σ);
* ``adhfit fit ... --global --method mcmc`` end to end with a reduced run (CI): report.json keys of the
  single-curve MCMC plus ``curves``, report.html/md, chain.h5;
* slow: recovery of a three-pressure series at 1 % force noise with the contact radius (issue 13's
  "done when" case) with the default run length.
"""
from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
from scipy import integrate, stats

from adhfit.fitting.bayes.posterior import Target as SeriesTarget
from adhfit.fitting.lsq import Parametrisation
from adhfit.fitting.model import CurveModel, Segments
from adhfit.fitting.objective import Block, Member, SharedParametrisation, objective_residual
from adhfit.fitting.observables import OBSERVABLES, contact_radius_model as radius_prediction
from adhfit.synthetic import synthetic_series
from adhfit.scene import load_scene

ROOT = Path(__file__).resolve().parents[1]
SCENE = ROOT / "sample_data" / "fea_displacement_no-slip" / "scene.toml"
TRUE = {"work_of_adhesion": 0.4, "mu_h": 2.0}


def _series(seed, *, rows, pressures, radius_noise=0.01, noise=0.01):
    return synthetic_series(load_scene(SCENE), "no-slip", pressures=pressures, **TRUE, x_max=6e-4, noise=noise,
                            radius_noise=radius_noise, rows=rows, rng=np.random.default_rng(seed))


class _Best:
    """The two attributes of an lmfit result that SeriesTarget reads."""

    def __init__(self, var_names):
        self.var_names = var_names
        self.params = {}


class _Fit:
    def __init__(self, members, given):
        self.members, self.given = members, given
        self.spar = SharedParametrisation(tuple(m.par for m in members))
        for m in members:
            for b in m.blocks:
                b.given = given["contact_radius"]
        names = ["ln_work_of_adhesion", "ln_mu_h"] + [f"{n}_{i}" for i in range(len(members))
                                                      for n in ("x_offset", "force_offset")]
        self.best = _Best(names)

    @property
    def residual(self):
        return objective_residual(self.members, self.spar)


def _members(series, sigma_a):
    out = []
    for curve, scene, truth in series:
        seg = Segments(n=len(curve.x), i_turn=curve.i_turn, i_jump=truth["i_jump"],
                       jump=float(abs(curve.force[truth["i_jump"]] - curve.force[truth["i_jump"] - 1])))
        model = CurveModel(curve, scene, "no-slip", segments=seg, fixed_split=True)
        par = Parametrisation(x_scale=float(np.ptp(curve.x)), f_scale=float(np.max(np.abs(curve.force))),
                              control="displacement", fit_x_offset=True, fit_force_offset=True)
        obs = OBSERVABLES["contact_radius"]
        out.append((Member(model=model, par=par, sigma_f=truth.get("sigma", 1e-5),
                           blocks=[Block(obs, obs.rows(curve), sigma_a)]), truth))
    return out


def _theta(members, shifts):
    th = [math.log(TRUE["work_of_adhesion"] * 1.01), math.log(TRUE["mu_h"] * 0.995)]
    for (m, truth), s in zip(members, shifts):
        th += [(truth["x_offset"] + s) / m.par.x_scale, 2e-6 / m.par.f_scale]
    return np.array(th)


def _independent_blocks(members, theta):
    """Per block: the raw residuals in SI (force rows; pull-off term in units of σ_f; radius rows)."""
    w, mu = math.exp(theta[0]), math.exp(theta[1])
    out = []
    for i, (m, _) in enumerate(members):
        x_off, f_off = theta[2 + 2 * i] * m.par.x_scale, theta[3 + 2 * i] * m.par.f_scale
        rf = m.model.force - m.model.predict(w, mu, x_off, f_off)
        x_tp = m.model.turning_point(w, mu, x_off)[0]
        lo, hi = sorted(m.model.jump[:2])
        p_in = stats.norm.cdf((hi - x_tp) / m.model.jump[2]) - stats.norm.cdf((lo - x_tp) / m.model.jump[2])
        jump = math.sqrt(-2.0 * math.log(p_in)) * m.sigma_f  # the censored pull-off term, in force units
        out.append((np.append(rf, jump), m.sigma_f))
        a = radius_prediction(m.model, w, mu, x_off)
        b = m.blocks[0]
        out.append((b.data.values - a[b.data.rows], b.sigma))
    return out


def test_likelihood_is_the_sum_of_independent_gaussian_blocks():
    """σ given: Σ over blocks of Σ ln N(r; 0, σ_block); σ unknown: per block ln ∫ Π N(r; 0, σ) / σ dσ
    (numerical quadrature, 1e-7 relative): the closed form the sampler uses must equal both."""
    series = _series(3, rows=50, pressures=(900.0, 1500.0))
    members = _members(series, sigma_a=4e-6)
    for m, truth in members:
        m.sigma_f = 0.01 * float(np.max(m.model.force))
    theta = _theta(members, shifts=(1e-6, -2e-6))
    blocks = _independent_blocks(members, theta)
    ms = [m for m, _ in members]
    names = ["work_of_adhesion", "mu_h", "displacement_offset_0", "force_offset_0", "displacement_offset_1",
             "force_offset_1"]
    given = SeriesTarget(_Fit(ms, {"force": True, "contact_radius": True}), names, [None] * 6)
    expected = sum(float(np.sum(stats.norm.logpdf(r, 0.0, s))) for r, s in blocks)
    assert given.log_likelihood(theta) == pytest.approx(expected, rel=1e-9)
    unknown = SeriesTarget(_Fit(ms, {"force": False, "contact_radius": False}), names, [None] * 6)
    total = 0.0
    for r, s in blocks:  # substitute σ = s·e^t: ∫ L(σ)/σ dσ = ∫ L(s e^t) dt
        ss, n = float(r @ r), r.size
        t_peak = 0.5 * math.log(ss / (n * s**2))  # the integrand's peak (σ² = ss/n)
        g = lambda t, ss=ss, s=s, n=n: -0.5 * ss / (s * math.exp(t)) ** 2 - n * (math.log(s) + t)
        m = g(t_peak)  # scale for stability
        val, _ = integrate.quad(lambda t, g=g, m=m: math.exp(g(t) - m), t_peak - 4.0, t_peak + 4.0, epsabs=0,
                                epsrel=1e-10, limit=200)
        total += math.log(val) + m - 0.5 * n * math.log(2 * math.pi)
    assert unknown.log_likelihood(theta) == pytest.approx(total, rel=1e-7)


def test_cli_global_mcmc_reduced_run(tmp_path, monkeypatch):
    """A short seeded run end to end (CI: 20 steps after tuning, one slip condition): the report carries
    the single-curve MCMC keys plus ``curves`` with posterior offsets, and the chains are saved."""
    import adhfit.fitting.bayes.sampling as gm
    from adhfit.cli import main
    from tests.test_global_fit import _write
    monkeypatch.setitem(gm.SERIES_DEFAULTS, "max_steps", 20)
    monkeypatch.setitem(gm.SERIES_DEFAULTS, "evidence_draws", 80)
    _write(_series(8, rows=50, pressures=(900.0, 1500.0), radius_noise=None), tmp_path / "data")
    out = tmp_path / "out"
    assert main(["fit", str(tmp_path / "data"), "--global", "--method", "mcmc", "--slip", "no-slip",
                 "--seed", "4", "-o", str(out), "-q"]) == 0
    d = json.loads((out / "report.json").read_text(encoding="utf-8"))
    assert d["method"] == "mcmc" and d["seed"] == 4 and d["slip"]["selected"] == "no-slip"
    assert {"converged", "model_probabilities", "diagnostics", "mcmc", "curves", "offsets"} <= set(d)
    assert d["mcmc"]["slips"]["no-slip"]["parameters"][:2] == ["work_of_adhesion", "mu_h"]
    for name, true in TRUE.items():
        e = d["parameters"][name]
        assert e["ci_method"].startswith("posterior") and e["status"] == "determined"
        # 1 % noise, two curves: the posterior sd is < 1 % of the value; 6 sd covers any seed of a short run
        assert abs(e["value"] - true) < 6 * e["stderr"] + 0.002 * true, (name, e)
    for c in d["curves"]:
        off = c["offsets"]["displacement"]
        assert off["ci95"][0] < off["value"] < off["ci95"][1] and off["method"].startswith("posterior")
    assert (out / "chain.h5").is_file() and (out / "report.html").is_file() and (out / "report.md").is_file()
    assert (out / "corner.png").stat().st_size > 0  # the shared W_ad and μh's posterior, as for one curve
    page = (out / "report.html").read_text(encoding="utf-8")
    assert "Bayesian fit (MCMC)" in page and "Convergence diagnostics" in page


@pytest.mark.slow
def test_global_mcmc_recovers_a_three_pressure_series():
    """Issue 13's case with the default run: 3 pressures, 1 % force noise, contact radius filmed; W_ad and
    μh within 2 % and inside their 95 % credible intervals, no-slip selected with P ≥ 0.95, converged,
    and the shared W_ad interval no wider than the best single-curve one.  (Before the proposal was
    refitted over several tuning rounds this run hit the 400-step cap unconverged, τ ~10 steps; now
    τ ~5 steps, ~40 s on the shared 2-core machine; the sampler part has a CI variant in
    tests/test_mcmc.py::test_tuning_rounds_fix_a_skewed_posterior_with_a_poor_start.)"""
    from adhfit.fitting.api import fit as fit_global
    series = _series(20261202, rows=160, pressures=(800.0, 1200.0, 1600.0))
    r = fit_global([c for c, _, _ in series], [s for _, s, _ in series], method="mcmc", seed=11,
                   progress=False)
    assert r.converged and r.slip["selected"] == "no-slip", (r.wall_time, {
        s: v["diagnostics"]["warnings"] for s, v in r.mcmc["slips"].items()})
    assert r.slip["probabilities"]["no-slip"] >= 0.95
    for name, true in TRUE.items():
        e = r.parameters[name]
        assert abs(e.value / true - 1) < 0.02 and e.ci95[0] <= true <= e.ci95[1], (name, e)
    w = r.parameters["work_of_adhesion"]
    best = min(c["alone"]["work_of_adhesion"]["ci95"][1] - c["alone"]["work_of_adhesion"]["ci95"][0]
               for c in r.curves)
    assert w.ci95[1] - w.ci95[0] <= best
    assert r.observables == ("force", "contact_radius")


def test_start_covariance_scale_is_corrected_against_the_posterior():
    """A least-squares standard error 30 times too small on one coordinate (a kink seen by a finite
    difference) is corrected from the log posterior itself: for a Gaussian target with a known
    covariance the corrected scales are within 15 % of the true ones, the right ones are left alone."""
    from adhfit.fitting.bayes.posterior import checked_covariance
    rng = np.random.default_rng(1)
    a = rng.normal(size=(4, 4))
    cov = a @ a.T + 4 * np.eye(4)
    inv = np.linalg.inv(cov)
    target = lambda th: -0.5 * float(th @ inv @ th)  # noqa: E731
    bad = cov.copy()
    d = np.ones(4)
    d[2] = 1.0 / 30.0
    bad = bad * np.outer(d, d)
    fixed, ratio = checked_covariance(target, np.zeros(4), bad)
    assert ratio[0] == ratio[1] == ratio[3] == 1.0
    assert np.allclose(np.sqrt(np.diag(fixed)), np.sqrt(np.diag(cov)), rtol=0.15), (np.diag(fixed), np.diag(cov))


def test_a_rejected_condition_need_not_converge_only_when_negligible():
    """The convergence rule of a series: a condition the least-squares fit rejects (ΔBIC > 100) may stay
    unconverged only while its probability, raised by 20 Monte-Carlo standard errors, stays < 1e-6."""
    from adhfit.fitting.bayes.sampling import _converged, _rejected
    from types import SimpleNamespace as NS
    assert _rejected({"no-slip": NS(bic=-1000.0), "frictionless": NS(bic=-850.0)}) == {"frictionless"}
    assert _rejected({"no-slip": NS(bic=-1000.0), "frictionless": NS(bic=-950.0)}) == set()
    diags = {"no-slip": {"converged": True}, "frictionless": {"converged": False}}
    tiny = {"probabilities": {"no-slip": 1.0, "frictionless": 1e-40}, "log_bayes_factor_stderr": 0.5}
    assert _converged(diags, tiny, {"frictionless"})
    assert not _converged(diags, tiny, set())  # not rejected by least squares: it must converge
    close = {"probabilities": {"no-slip": 1.0 - 1e-7, "frictionless": 1e-7}, "log_bayes_factor_stderr": 0.5}
    assert not _converged(diags, close, {"frictionless"})  # e^10 x 1e-7 > 1e-6
    assert not _converged({"no-slip": {"converged": False}, "frictionless": {"converged": True}}, tiny,
                          {"frictionless"})
