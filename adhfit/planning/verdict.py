"""The slip verdict a protocol can be expected to reach (:mod:`adhfit.fitting.selection`).

**Expected ΔBIC.** Both slip conditions are fitted with the same parameters, so ΔBIC is the difference
of -2 ln L, with σ profiled out: ΔBIC = n ln(RSS_wrong / RSS_true), n the residuals of the force block
(every row and the pull-off term).  On the noiseless curve the true condition fits exactly (up to the
pull-off term's small constant) and the other condition's best fit (the fit's own least squares,
:func:`adhfit.fitting.lsq.minimise`, started from the truth on the same row split) leaves a misfit λ =
χ²_wrong − χ²_true, in units of σ².  With noise e (units of σ), linearising both fits about their noiseless
optima (Jacobians J_t, J_w, hat matrices H_t, H_w):

    RSS_true/σ² ≈ χ²_true + e^T (I − H_t) e              (≈ χ² with n − k degrees of freedom)
    D = (RSS_wrong − RSS_true)/σ² ≈ λ + 2 (r_w − r_t)^T e + e^T (H_t − H_w) e

so D is a noncentral-χ²-type difference: mean λ, variance 4 ||r_w − r_t||² (≈ 4λ) from the linear term plus
2 tr((H_t − H_w)²) from the quadratic one (treated as normal).  Then ΔBIC = n ln(1 + D / (RSS_true/σ²)).
Its distribution is sampled (a fixed number of draws with a fixed seed, so a plan is reproducible), and
the probabilities of the evidence words follow from the fit's own thresholds
(:data:`adhfit.fitting.selection.SCALE`): only ΔBIC > 10 selects a condition.

Not modelled: the fit's widening of ΔBIC for correlated residuals (white noise: none) and its cap for
a misfit the noise does not explain (the true model always describes its own curve).
"""
from __future__ import annotations

import math

import numpy as np

from ..fitting.lsq import COARSE_TOL, minimise, residual_function
from ..fitting.selection import DECISIVE, POSITIVE, STRONG
from ..fitting.starts import Start
from .information import jacobian, log_widths, pull_off_curvature, pull_off_slopes

__all__ = ["misfit", "Misfit", "profile_other", "UNDECIDED_MIN", "verdict_probabilities", "sample_delta_bic", "word_probabilities", "DRAWS", "SEED",
           "WORDS"]

#: draws of the ΔBIC distribution, and their fixed seed (a plan is reproducible)
DRAWS = 20_000
SEED = 20261204
#: the evidence words, for the true condition (favoured) and for the wrong one
WORDS = ("very strong", "strong", "positive", "cannot tell", "wrong: positive", "wrong: strong",
         "wrong: very strong")


class Misfit:
    """The other slip condition's best fit to a noiseless curve.

    Attributes
    ----------
    lam : float
        χ²_wrong − χ²_true at the noiseless optima (units of σ²).
    linear_var : float
        4 ||r_w − r_t||²: the variance of D's term linear in the noise.
    quadratic_var : float
        2 tr((H_t − H_w)²).
    n, k : int
        Residuals and fitted parameters.
    chisqr_true : float
        The true condition's χ² on the noiseless curve (the pull-off term's constant).
    values : dict
        The other condition's optimum (SI).
    widths : dict or None
        The other condition's expected interval widths (:func:`~.information.log_widths`), None when its
        optimum sits at the model's edge.
    """

    widths = None
    #: the other condition's residual and Jacobian at its optimum (:func:`.information.jacobian`), when known
    r = J = None

    def __init__(self, lam: float, linear_var: float, quadratic_var: float, n: int, k: int, chisqr_true: float,
                 values: dict | None = None) -> None:
        self.lam, self.linear_var, self.quadratic_var = float(lam), float(linear_var), float(quadratic_var)
        self.n, self.k, self.chisqr_true, self.values = int(n), int(k), float(chisqr_true), dict(values or {})

    def to_dict(self) -> dict:
        """The numbers that define the ΔBIC distribution (plan.json ``by_slip``; :mod:`.series` sums them)."""
        return {"lam": self.lam, "linear_var": self.linear_var, "quadratic_var": self.quadratic_var, "n": self.n,
                "k": self.k, "chisqr_true": self.chisqr_true}


def _hat_overlap(J1: np.ndarray, J2: np.ndarray) -> float:
    """tr(H1 H2) of the column spaces of J1 and J2 (= ||Q1^T Q2||_F²)."""
    q1, _ = np.linalg.qr(J1)
    q2, _ = np.linalg.qr(J2)
    return float(np.sum((q1.T @ q2) ** 2))


def _covariance_widths(model, par, sigma: float, values: dict, inflate: float, J: np.ndarray | None = None) -> dict:
    """The other condition's covariance interval widths: the median over where its turning point falls in the
    pull-off gap (the pull-off row's slope goes from ~0 in the middle to its largest at the edges, and the
    W_ad interval with it).

    ``J``: :func:`.information.jacobian` at ``values`` (its pull-off row the quadratic one), reused: only the
    pull-off row differs from the raw Jacobian, by the factor sqrt(k) (:func:`.information.pull_off_curvature`)."""
    if J is None:
        J = jacobian(model, par, sigma, values, raw_pull_off=True)[1] / inflate
    else:
        J = J / inflate
        if model.jump is not None:
            J[-1] /= math.sqrt(pull_off_curvature(model.jump))
    gap = model.jump
    if gap is None:
        return log_widths(J, values)
    runs = []
    for slope in pull_off_slopes(gap):
        Jt = J.copy()
        Jt[-1] *= slope
        runs.append(log_widths(Jt, values))
    out = {}
    for name in ("work_of_adhesion", "mu_h"):
        k = int(np.argsort([r[name]["width"] for r in runs])[len(runs) // 2])
        out[name] = runs[k][name]
    return out


def misfit(truth, other_slip: str, r_true: np.ndarray, J_true: np.ndarray) -> Misfit:
    """Fit ``other_slip`` to the noiseless curve of ``truth`` (:class:`~.truth.Truth`) by the fit's least squares."""
    model = truth.model_of(other_slip)
    par, sigma = truth.par, truth.sigma
    best = minimise(residual_function(model, par, sigma, sigma), par.params(Start(truth.values)),
                    scale_covar=False, tol=COARSE_TOL)
    values = par.si(best.params)
    chi_t = float(r_true @ r_true)
    lam = max(float(best.chisqr) - chi_t, 0.0)
    k = J_true.shape[1]
    try:
        r_w, J_w, _ = jacobian(model, par, sigma, values)
        # the other condition's own interval as the fit reports it for the condition it does not favour (from
        # the covariance: the pull-off row's own derivative), its σ estimate inflated by the misfit; the hull of
        # an undecided verdict takes it in (:func:`adhfit.fitting.stage.reported`)
        inflate = math.sqrt(1.0 + lam / max(r_true.size - k, 1))
        other_widths = _covariance_widths(model, par, sigma, values, inflate, J_w)
        # the noise enters the force rows only (not the pull-off term, the last row when there is one)
        g = r_true.size - (truth.model.jump is not None)
        lin = 4.0 * float(np.sum((r_w[:g] - r_true[:g]) ** 2))
        quad = 2.0 * max(2 * k - 2 * _hat_overlap(J_true, J_w), 0.0)
    except ValueError:  # the other condition's optimum sits at the model's edge: the linear term only
        lin, quad, other_widths = 4.0 * lam, 0.0, None
    out = Misfit(lam, lin, quad, r_true.size, k, chi_t, values)
    out.widths = other_widths
    if other_widths is not None:  # the linearised fit of the other condition (:mod:`.hull`)
        out.r, out.J = r_w, J_w
    return out


#: the other condition's W_ad profile is computed when the verdict is undecided at least this often
UNDECIDED_MIN = 0.02


def profile_other(truth, other_slip: str, m: "Misfit") -> None:
    """Replace the other condition's W_ad width in ``m`` by its likelihood profile on the noiseless curve.

    An undecided fit reports the hull of both conditions' intervals, each from its profile
    (:func:`adhfit.fitting.stage.least_squares`); the other condition's covariance interval is fragile at the
    pull-off's kink, so the plan takes its profile too (:func:`.information.profile_widths_fit`, with σ
    inflated by the misfit as the fit's estimate of σ is).  Left as it is when the profile does not close."""
    from .information import profile_widths_fit  # noqa: PLC0415
    model = truth.model_of(other_slip)
    inflate = math.sqrt(1.0 + m.lam / max(m.n - m.k, 1))
    try:
        _, J_w, _ = jacobian(model, truth.par, truth.sigma, m.values)
        prof = profile_widths_fit(model, truth.par, truth.sigma * inflate, m.values, J_w, ("work_of_adhesion",))
    except (ValueError, np.linalg.LinAlgError, ArithmeticError):
        prof = None
    if prof is not None:
        m.widths = {**m.widths, "work_of_adhesion": {**prof["work_of_adhesion"], "method": "profile"}}


def sample_delta_bic(m: Misfit, rng: np.random.Generator, draws: int = DRAWS) -> np.ndarray:
    """Draws of the fit's ΔBIC (true condition's favour positive) for one curve (module docstring)."""
    u = m.chisqr_true + rng.chisquare(max(m.n - m.k, 1), draws)
    d = m.lam + math.sqrt(m.linear_var) * rng.standard_normal(draws) + \
        math.sqrt(m.quadratic_var) * rng.standard_normal(draws)
    d = np.maximum(d, -u * (1.0 - 1e-12))
    return m.n * np.log1p(d / u)


def word_probabilities(dbic: np.ndarray) -> dict:
    """P(each word of :data:`WORDS`) from ΔBIC draws."""
    p = {"very strong": np.mean(dbic > DECISIVE), "strong": np.mean((dbic > STRONG) & (dbic <= DECISIVE)),
         "positive": np.mean((dbic >= POSITIVE) & (dbic <= STRONG)), "cannot tell": np.mean(np.abs(dbic) < POSITIVE),
         "wrong: positive": np.mean((dbic <= -POSITIVE) & (dbic >= -STRONG)),
         "wrong: strong": np.mean((dbic < -STRONG) & (dbic >= -DECISIVE)),
         "wrong: very strong": np.mean(dbic < -DECISIVE)}
    return {k: float(v) for k, v in p.items()}


def verdict_probabilities(m, weights=None) -> dict:
    """P(each evidence word) for the true condition, from the sampled ΔBIC (module docstring).

    ``m`` is a :class:`Misfit`, or a list of them with ``weights``: the fit's nuisances differ between
    replicates (the drift, :func:`.truth.drift_probability`), so the ΔBIC is a mixture, each part sampled
    with its share of the draws.

    Returns
    -------
    dict
        ``words`` (word -> probability, :data:`WORDS`), ``decided`` (P(ΔBIC > 10 for the true
        condition)), ``wrong`` (P(ΔBIC > 10 for the other)), ``delta_bic`` (the median), ``delta_bic_range``
        (the 5 and 95 % quantiles; negative: the other condition favoured), ``misfit`` (λ).
    """
    rng = np.random.default_rng(SEED)
    if isinstance(m, Misfit):
        dbic = sample_delta_bic(m, rng)
        lam = m.lam
    else:
        counts = np.round(np.asarray(weights, float) / np.sum(weights) * DRAWS).astype(int)
        dbic = np.concatenate([sample_delta_bic(mi, rng, int(c)) for mi, c in zip(m, counts) if c > 0])
        lam = float(np.dot(weights, [mi.lam for mi in m]) / np.sum(weights))
    p = word_probabilities(dbic)
    q05, q50, q95 = np.quantile(dbic, [0.05, 0.5, 0.95])
    return {"words": p, "decided": float(p["very strong"]),
            "wrong": float(p["wrong: very strong"]), "delta_bic": float(q50),
            "delta_bic_range": [float(q05), float(q95)], "misfit": lam}
