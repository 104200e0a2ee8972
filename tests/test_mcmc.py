"""MCMC fit (adhfit.fitting.bayes.posterior / mcmc / diagnostics / mcmc_fit): priors integrate to one, the
likelihood is the least-squares residual's, the sampler recovers a known Gaussian and follows its
stopping rule, runs are reproducible from the seed, chains land in HDF5, and the fit and the CLI
report what they should.  Kept small for CI: toy targets and tiny chains on the real model."""
from __future__ import annotations

import functools
import json
import math

import numpy as np
import pytest
from scipy import integrate, special

from adhfit.fitting.bayes.chains import diagnose
from adhfit.fitting.bayes.mcmc import sample_posterior
from adhfit.fitting.bayes.posterior import Prior


@pytest.mark.parametrize("prior", [Prior("work_of_adhesion", "loguniform", 0.01, 10.0, True),
                                   Prior("mu_h", "uniform", 0.5, 4.0, True),
                                   Prior("mu_h", "normal", 2.0, 1.5, True),
                                   Prior("displacement_offset", "uniform", -1e-4, 1e-4, False, 5e-4)])
def test_prior_density_integrates_to_one_in_theta(prior):
    if prior.log:
        lo, hi = (math.log(prior.a), math.log(prior.b)) if prior.dist != "normal" else (-20.0, math.log(20.0))
    else:
        lo, hi = prior.a / prior.factor, prior.b / prior.factor
    total, _ = integrate.quad(lambda t: math.exp(prior.logpdf(t)), lo, hi, limit=200, points=None)
    assert total == pytest.approx(1.0, rel=1e-6)
    assert prior.logpdf(hi + 1.0) == -math.inf or prior.dist == "normal"


class _Gauss:
    """A correlated 3-D Gaussian posterior (cheap stand-in for Target)."""

    names = ["a", "b", "c"]
    ndim = 3
    mean = np.array([1.0, -2.0, 0.5])
    cov = np.array([[1.0, 0.6, 0.0], [0.6, 2.0, -0.3], [0.0, -0.3, 0.5]])

    def __call__(self, t):
        d = np.asarray(t) - self.mean
        return float(-0.5 * d @ np.linalg.solve(self.cov, d))


def test_sampler_recovers_gaussian_and_stops_by_tau():
    g = _Gauss()
    ch = sample_posterior(g, g.mean + 0.3, g.cov * 0.5, seed=5, n_walkers=8, n_ensembles=4, max_steps=400,
                          check_every=5, progress=False)
    d = diagnose(ch, g.names)
    assert ch.converged and not ch.cap_hit and d["converged"]
    assert ch.n_production > 50 * max(d["tau"].values())
    flat = ch.flat
    np.testing.assert_allclose(flat.mean(0), g.mean, atol=0.1)
    np.testing.assert_allclose(np.cov(flat, rowvar=False), g.cov, atol=0.15)
    assert all(r < 1.01 for r in d["rhat"].values())
    assert ch.chain.shape[0] == 4 and ch.acceptance.shape == (4, 8)


class _SkewNormal:
    """An 8-D skewed posterior with known moments: θ = L z, z_0 skew-normal (shape α = 5), the other z_k
    standard normal; a stand-in for a series posterior, skewed near each curve's fold."""

    ndim = 8
    names = [f"p{k}" for k in range(8)]
    alpha = 5.0

    def __init__(self) -> None:
        a = np.random.default_rng(3).normal(size=(8, 8))
        self.L = np.linalg.cholesky(a @ a.T / 8 + 0.5 * np.eye(8))
        dl = self.alpha / math.sqrt(1 + self.alpha**2)  # skew-normal mean δ√(2/π), variance 1 - 2δ²/π
        self.mean = self.L[:, 0] * dl * math.sqrt(2 / math.pi)
        self.cov = self.L @ np.diag([1 - 2 * dl**2 / math.pi] + [1.0] * 7) @ self.L.T

    def __call__(self, t):
        z = np.linalg.solve(self.L, np.asarray(t, float))
        return float(-0.5 * z @ z + special.log_ndtr(self.alpha * z[0]))


def test_tuning_rounds_fix_a_skewed_posterior_with_a_poor_start():
    """A skewed 8-D posterior started at θ = 0 (z_0 = 0, off its mode and mean) with one start standard
    error 0.35 of the right one (as a series fit's start covariance can be): one refit of the proposal
    from the first 7 steps mixes slowly (acceptance ~0.25, τ ~30 steps: not converged at 800 steps with
    seeds 1-3), tuning rounds until the proposal settles converge.  Moments against the skew-normal's
    closed form; tolerances ≥ 3 Monte-Carlo standard errors at the converged run's ESS (> 1000)."""
    g = _SkewNormal()
    d = np.ones(8)
    d[2] = 0.35
    cov0 = g.L @ g.L.T * np.outer(d, d)
    kw = {"seed": 1, "n_walkers": 8, "n_ensembles": 2, "check_every": 5, "progress": False}
    ch = sample_posterior(g, np.zeros(8), cov0, tune_steps=20, tune_rounds=12, max_steps=800, **kw)
    dg = diagnose(ch, g.names)
    assert dg["converged"], dg["warnings"]
    # tuning stops once the proposal settles (at least 3 rounds), and every tuning step is discarded
    assert ch.tune_steps % 20 == 0 and 60 <= ch.tune_steps < 240 and ch.burn >= ch.tune_steps
    sd = np.sqrt(np.diag(g.cov))
    np.testing.assert_allclose(ch.flat.mean(0) / sd, g.mean / sd, atol=0.12)
    np.testing.assert_allclose(np.std(ch.flat, axis=0) / sd, 1.0, atol=0.08)
    one = sample_posterior(g, np.zeros(8), cov0, tune_steps=15, max_steps=100, **kw)
    assert dg["acceptance"]["mean"] > float(np.mean(one.acceptance)) + 0.15


def test_cap_hit_is_reported_not_converged():
    g = _Gauss()
    ch = sample_posterior(g, g.mean, g.cov, seed=1, n_walkers=8, n_ensembles=2, max_steps=20, progress=False)
    d = diagnose(ch, g.names)
    assert ch.cap_hit and not d["converged"]
    assert any("cap was hit" in w for w in d["warnings"])


@pytest.mark.parametrize("name, value", [("tune_rounds", 0), ("tune_rounds", 2.5), ("tune_steps", -1),
                                         ("max_steps", 0), ("n_walkers", True), ("check_every", "5")])
def test_sampler_settings_out_of_range_are_one_clear_error(name, value):
    from adhfit.errors import InputError
    g = _Gauss()
    with pytest.raises(InputError, match=name) as err:
        sample_posterior(g, g.mean, g.cov, seed=1, progress=False, **({"max_steps": 20} | {name: value}))
    assert "positive integer" in str(err.value) and str(value) in str(err.value)


def test_seeded_runs_repeat_and_hdf5(tmp_path):
    pytest.importorskip("h5py")
    from adhfit.fitting.bayes.mcmc import open_chain
    g = _Gauss()
    kw = dict(seed=42, n_walkers=8, n_ensembles=2, max_steps=20, progress=False)
    a = sample_posterior(g, g.mean, g.cov, path=tmp_path / "chain.h5", group="no-slip", **kw)
    b = sample_posterior(g, g.mean, g.cov, **kw)
    np.testing.assert_array_equal(a.chain, b.chain)
    assert a.groups == ["no-slip/ensemble_0", "no-slip/ensemble_1"]
    back = open_chain(tmp_path / "chain.h5", "no-slip/ensemble_1")
    np.testing.assert_array_equal(back.get_chain(), a.chain[1])
    np.testing.assert_array_equal(back.get_log_prob(), a.log_prob[1])
    assert back.iteration == a.chain.shape[1] and back.shape == (a.chain.shape[2], a.chain.shape[3])
    assert (back.accepted > 0).all() and back.random_state is not None
    with back.open() as f:
        assert f["no-slip/ensemble_1"].attrs["adhfit_burn"] == a.burn
    c = sample_posterior(g, g.mean, g.cov, path=tmp_path / "chain.h5", group="no-slip", **(kw | {"seed": 43}))
    assert not np.array_equal(a.chain, c.chain)
    # a new run to the same file replaces the group (no leftover steps of the old run)
    again = open_chain(tmp_path / "chain.h5", "no-slip/ensemble_1")
    np.testing.assert_array_equal(again.get_chain(), c.chain[1])


# --- the real model: one small synthetic curve, tiny chains --------------------------------------------------

@pytest.fixture(scope="module")
def small_fit(tmp_path_factory):
    from functools import partial  # noqa: PLC0415
    from adhfit.fitting.api import fit  # noqa: PLC0415
    fit_curve_mcmc = partial(fit, method="mcmc")
    from adhfit.synthetic import synthetic_curve
    from adhfit.scene import Scene
    LsScene = functools.partial(Scene, membrane_model="large-stretch")
    scene = LsScene(membrane_radius="2 mm", substrate_radius="1 mm", control="displacement", pressure="1.2 kPa",
                  slip="auto")
    curve, truth = synthetic_curve(scene, "no-slip", work_of_adhesion=0.4, mu_h=2.0, x_max=6e-4, rows=80,
                                   noise=0.005, x_offset=2e-5, rng=np.random.default_rng(3))
    out = tmp_path_factory.mktemp("mcmc")
    res = fit_curve_mcmc(curve, scene, seed=11, outdir=out, workers=1, progress=False, n_walkers=6,
                         n_ensembles=2, tune_steps=10, max_steps=15, evidence_draws=60, predictive_draws=8)
    return res, truth, out


def test_fit_reports_a5_keys_and_mcmc_sections(small_fit):
    from adhfit.report.json_report import report_dict
    res, truth, _ = small_fit
    d = json.loads(json.dumps(report_dict(res), allow_nan=False))
    assert d["method"] == "mcmc" and d["seed"] == 11
    for key in ("selected", "verdict", "delta_aic", "delta_bic", "probabilities"):
        assert key in d["slip"]
    for name in ("work_of_adhesion", "mu_h"):
        p = d["parameters"][name]
        assert p["ci95"][0] < p["value"] < p["ci95"][1] and p["stderr"] > 0
        assert abs(p["value"] / truth[name] - 1) < 0.05
    assert set(d["fits"]) == {"no-slip", "frictionless"} and all("bic" in f for f in d["fits"].values())
    assert set(d["diagnostics"]["no-slip"]) >= {"acceptance", "tau", "n_over_tau", "rhat", "ess_bulk", "cap_hit"}
    assert sum(d["model_probabilities"].values()) == pytest.approx(1.0)
    assert d["slip"]["selected"] in (None, "no-slip")  # the wrong condition is never selected
    assert d["mcmc"]["priors"]["work_of_adhesion"]["dist"] == "loguniform"


def test_same_residual_as_least_squares(small_fit):
    """ln L differs from -χ²/2 of the lsq residual only through σ: check the marginal-σ formula numerically."""
    from scipy import special
    res, _, _ = small_fit
    ch = res.raw["no-slip"]
    # rebuild the target exactly as the fit did and compare with a numerical integral over σ
    from adhfit.fitting.bayes.posterior import Target
    from adhfit.fitting.lsq import fit_slip
    from adhfit.fitting.model import CurveModel
    tg_names = res.mcmc["slips"]["no-slip"]["parameters"]
    assert tg_names[:2] == ["work_of_adhesion", "mu_h"]
    model = CurveModel(res.curve, _scene(), "no-slip")
    raw = fit_slip(model)
    from adhfit.fitting.objective import ObjectiveFit
    from adhfit.fitting.bayes.posterior import default_priors
    pri = default_priors(raw.par, [raw.par.si(raw.best.params)], {})
    tg = Target(ObjectiveFit.from_single(raw), list(raw.par.names), [pri[n] for n in raw.par.names])
    theta = ch.flat[0]
    r = tg.residual(theta) * raw.scale
    rss, n = float(r @ r), r.size
    num, _ = integrate.quad(lambda ls: math.exp(-n * ls - 0.5 * rss * math.exp(-2 * ls)
                                                - 0.5 * n * math.log(2 * math.pi) + 0.5 * n * math.log(rss)),
                            math.log(math.sqrt(rss / n)) - 3, math.log(math.sqrt(rss / n)) + 3, limit=200)
    assert tg.log_likelihood(theta) == pytest.approx(math.log(num) - 0.5 * n * math.log(rss), abs=1e-6)
    assert special.gammaln(1.0) == 0.0


def _scene():
    from adhfit.scene import Scene
    LsScene = functools.partial(Scene, membrane_model="large-stretch")
    return LsScene(membrane_radius="2 mm", substrate_radius="1 mm", control="displacement", pressure="1.2 kPa",
                 slip="auto")


def test_outputs_and_human_report(small_fit):
    from adhfit.report.markdown import render_markdown
    from adhfit.report.mcmc_plots import plot_corner, plot_predictive
    res, _, out = small_fit
    text = render_markdown(res)
    assert "### Convergence diagnostics" in text and "R-hat" in text and "N/τ" in text
    # tiny chains: the report must say plainly that the run has not converged, before anything else
    assert not res.converged and "NOT CONVERGED" in text
    assert text.index("NOT CONVERGED") < text.index("## Warnings")
    assert any("NOT CONVERGED" in w for w in res.warnings)
    plot_corner(res, path=out / "corner.png")
    plot_predictive(res, path=out / "fit_mcmc.png")
    assert (out / "corner.png").stat().st_size > 0 and (out / "fit_mcmc.png").stat().st_size > 0
    if res.mcmc["chain_file"]:
        from adhfit.fitting.bayes.mcmc import open_chain
        assert open_chain(res.mcmc["chain_file"], "frictionless/ensemble_1").iteration > 0


def test_two_processes_give_the_same_posterior(small_fit, tmp_path):
    """workers=2 samples each slip condition in its own forked process: same seeds, same chains."""
    from functools import partial  # noqa: PLC0415
    from adhfit.fitting.api import fit  # noqa: PLC0415
    fit_curve_mcmc = partial(fit, method="mcmc")
    res, _, _ = small_fit
    two = fit_curve_mcmc(res.curve, _scene(), seed=11, outdir=tmp_path, workers=2, progress=False, n_walkers=6,
                         n_ensembles=2, tune_steps=10, max_steps=15, evidence_draws=60, predictive_draws=8)
    assert two.mcmc["settings"]["workers"] == 2
    for slip in ("no-slip", "frictionless"):
        np.testing.assert_array_equal(two.raw[slip].chain, res.raw[slip].chain)
        np.testing.assert_array_equal(two.samples[slip], res.samples[slip])
    assert two.mcmc["model_probabilities"] == res.mcmc["model_probabilities"]
    assert two.mcmc["model_evaluations"] == res.mcmc["model_evaluations"]
    if two.mcmc["chain_file"]:
        from adhfit.fitting.bayes.mcmc import open_chain
        back = open_chain(two.mcmc["chain_file"], "frictionless/ensemble_1")
        np.testing.assert_array_equal(back.get_chain(), two.raw["frictionless"].chain[1])


def test_default_tuning_rounds_converge_where_one_round_stuck():
    """A 2 %-noise replicate of benchmarks/mcmc_linear_coverage.py (seed 20262228) on which one tuning round
    left 14 walkers stuck (acceptance 0.06, τ ~17 steps, unconverged at the 300-step cap); the default
    rounds (until the proposal settles) converge with τ < 5 steps."""
    import sys  # noqa: PLC0415
    from pathlib import Path  # noqa: PLC0415
    sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "benchmarks"))
    try:
        from mcmc_linear_coverage import replicate  # noqa: PLC0415
    finally:
        sys.path.pop(0)
    from adhfit.fitting import api  # noqa: PLC0415
    seen = {}
    fit = api.fit

    def spy(*a, **k):
        seen["r"] = fit(*a, **k)
        return seen["r"]
    api.fit = spy
    try:
        row = replicate((0.02, 20262228))
    finally:
        api.fit = fit
    d = seen["r"].mcmc["slips"]["no-slip"]["diagnostics"]
    assert row["converged"] and d["converged"], d["warnings"]
    assert max(d["tau"].values()) < 5.0 and d["acceptance"]["mean"] > 0.3
