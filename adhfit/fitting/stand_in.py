"""The exact membrane at the large-stretch model's speed: a checked stand-in for MCMC and least squares.

An exact-membrane history costs ~5 ms, a large-stretch one ~0.3 ms; an MCMC run needs ~10^4 of them, an
exact least-squares refit ~50.
Over the narrow region a posterior occupies, the difference between the two models' predictions is small
and smooth in the parameters (it is the approximation's error, which changes slowly with W_ad and μh).
So the sampler runs on a stand-in, :class:`CorrectedModel`: the large-stretch model plus that difference,
linear in q = (ln W_ad, ln μh, control offset) about the least-squares optimum q0,

    F_S(q) = F_L(q) + [F_E(q0) - F_L(q0)] + C (q - q0),    x_tp,S(q) likewise,

with C from central differences of the exact model (2·3 + 1 exact histories per curve), after the
large-stretch unloading branch is moved onto the exact fold (:class:`CorrectedModel`).  The force
offset and its drift enter both models identically and need no correction; the turning point (the
censored pull-off term's argument) is corrected as a value, not through the term, which is not linear.

Nothing is taken on trust (:func:`check`): on posterior draws of the stand-in, the exact model gives
the log-likelihood difference Δ = ln L_E - ln L_S.  Importance weights exp(Δ) turn the stand-in's
posterior into the exact one; when their spread is small (sd Δ ≤ :data:`MAX_SD`), the posterior means
move by at most sd Δ posterior standard deviations (Cauchy-Schwarz) and the stand-in's draws are the
exact posterior's to that precision; the evidence is corrected exactly, ln Z_E = ln Z_S + ln E_S[exp Δ].
Otherwise the exact posterior is sampled directly (and the report says why).  The largest force
deviation on the draws, in units of the noise σ, is reported either way.

Least squares (:func:`minimise_exact`, space mapping): the stand-in is minimised, rebuilt at its optimum
and minimised again while the optimum moves by more than :data:`REBUILD` standard errors; a last run on the exact
model itself starts there, so the reported optimum, χ² and covariance are the exact model's.
"""
from __future__ import annotations

import dataclasses
import math

import numpy as np

from .model import CurveModel, ModelDomainError
from .objective import Member, ObjectiveFit

__all__ = ["CorrectedModel", "stand_in", "check", "minimise_exact", "MAX_SD", "CHECK_DRAWS"]

#: the stand-in's draws are accepted as the exact posterior's when the log-likelihood difference
#: varies by at most this much (nats, standard deviation over the draws): means then move by at most
#: this many posterior standard deviations
MAX_SD = 0.05
#: posterior draws on which the stand-in is checked against the exact model
CHECK_DRAWS = 64
#: least squares: the stand-in is rebuilt at its optimum when that lies farther than this many standard
#: errors from where it was built (measured: one standard error away it is off by ~0.003 σ a row, so its
#: optimum is the exact one's to far better than the polish on the exact model needs)
REBUILD = 0.5


def _q(work_of_adhesion: float, mu_h: float, x_offset: float) -> np.ndarray:
    return np.array([math.log(work_of_adhesion), math.log(mu_h), float(x_offset)])


class CorrectedModel:
    """The large-stretch :class:`~.model.CurveModel` plus the exact model's difference, linear about q0.

    Answers what the residual asks of a model (:func:`.lsq.residual_function`: ``force``, ``jump``,
    :meth:`predict`, :meth:`turning_point`) for a fixed row split.

    The unloading branch has a kink (the onset of delamination) and ends in a fold (the force's slope is
    infinite at the turning point), and the two models' kinks sit at slightly different control values: a
    row next to them differs by an amount far from linear in the parameters (a square root at the fold).
    So the large-stretch branch is first read through the piecewise-linear map that puts its onset and its
    turning point onto the exact model's (``unloading_shift``: the two gaps, each linear about q0), and
    only the smooth remainder is corrected.

    Parameters
    ----------
    exact : CurveModel
        The exact-membrane model of the curve (fixed split), as fitted.
    si0 : dict
        The least-squares optimum (SI: ``work_of_adhesion``, ``mu_h``, ``x_offset``).
    steps : sequence of float
        Central-difference steps in q (ln W_ad, ln μh, offset in SI).
    """

    def __init__(self, exact: CurveModel, si0: dict, steps) -> None:
        self.exact = exact
        self.cheap = CurveModel(exact.curve, exact.scene, exact.slip, points=exact.points,
                                segments=exact.segments, fixed_split=exact.fixed_split, membrane="large-stretch")
        self.force, self.jump, self.segments = exact.force, exact.jump, exact.segments
        self.fixed_split, self.membrane, self.curve = exact.fixed_split, "exact (large-stretch + correction)", exact.curve
        self.q0 = _q(si0["work_of_adhesion"], si0["mu_h"], si0["x_offset"])
        self.steps = np.asarray(steps, float)
        stencil = [self.q0] + [self.q0 + sign * h * e for h, e in zip(self.steps, np.eye(3)) for sign in (1.0, -1.0)]
        kinks = np.array([self._kink_gaps(q) for q in stencil])  # (onset, turning point) gaps at each q
        self.delta0 = kinks[0]
        self.G = np.column_stack([(kinks[1 + 2 * i] - kinks[2 + 2 * i]) / (2 * h) for i, h in enumerate(self.steps)])
        diff = [self._difference(q) for q in stencil]
        self.c0 = diff[0]
        self.C = np.column_stack([(diff[1 + 2 * i] - diff[2 + 2 * i]) / (2 * h) for i, h in enumerate(self.steps)])

    @staticmethod
    def _wmo(q: np.ndarray) -> tuple[float, float, float]:
        return math.exp(q[0]), math.exp(q[1]), float(q[2])

    def _kink_gaps(self, q: np.ndarray) -> tuple[float, float]:
        """(x_onset,E - x_onset,L, x_tp,E - x_tp,L) in the control group (δ/b or p) at q."""
        w, mu, off = self._wmo(q)
        e, c = self.exact.pieces(w, mu, off), self.cheap.pieces(w, mu, off)
        return float(e.x_onset - c.x_onset), float(e.x_tp - c.x_tp)

    def _shift(self, q: np.ndarray) -> tuple[float, float]:
        d = self.delta0 + self.G @ (q - self.q0)
        return float(d[0]), float(d[1])

    def _difference(self, q: np.ndarray) -> np.ndarray:
        w, mu, off = self._wmo(q)
        return self.exact.predict(w, mu, off) - self.cheap.predict(w, mu, off, unloading_shift=self._shift(q))

    @property
    def n_evaluations(self) -> int:
        return self.cheap.n_evaluations

    @property
    def n_histories(self) -> int:
        return self.cheap.n_histories

    def predict(self, work_of_adhesion: float, mu_h: float, x_offset: float = 0.0,
                force_offset: float = 0.0, force_drift: float = 0.0) -> np.ndarray:
        """The stand-in's force at every row, N."""
        q = _q(work_of_adhesion, mu_h, x_offset)
        base = self.cheap.predict(work_of_adhesion, mu_h, x_offset, force_offset, force_drift,
                                  unloading_shift=self._shift(q))
        return base + self.c0 + self.C @ (q - self.q0)

    def turning_point(self, work_of_adhesion: float, mu_h: float, x_offset: float = 0.0) -> tuple[float, float]:
        """The stand-in's turning point: the large-stretch one moved by δ(q) (the force is the large-stretch one's)."""
        x, f = self.cheap.turning_point(work_of_adhesion, mu_h, x_offset)
        per_group = float(self.cheap.dimensionless_x(mu_h, 0.0, np.ones(1))[0])  # control group per measured unit
        return float(x + self._shift(_q(work_of_adhesion, mu_h, x_offset))[1] / per_group), f


def stand_in(fit: ObjectiveFit, stderr: dict | None = None) -> ObjectiveFit | None:
    """The objective ``fit`` with each exact-membrane curve model replaced by its :class:`CorrectedModel`.

    ``None`` where there is nothing to gain or the stand-in does not apply: no exact member, a free row
    split, a secondary observable (its prediction is not corrected), or an exact history that fails at
    a difference step.  ``stderr``: internal name -> standard error, for the steps (half of it).
    """
    members = fit.members
    if not any(m.model.membrane == "exact" for m in members):
        return None
    if any(m.blocks or not m.model.fixed_split for m in members):
        return None
    stderr = stderr or {}
    shared, offsets = fit.si()
    new = []
    for i, m in enumerate(members):
        si0 = {**shared, **offsets[i]}
        offset = fit.spar.name("x_offset", i) if fit.joint else "x_offset"
        try:
            model = CorrectedModel(m.model, si0, _steps(m.par, stderr, offset))
        except ModelDomainError:
            return None
        single = dataclasses.replace(m.single, model=model) if m.single is not None else None
        new.append(Member(model=model, par=m.par, sigma_f=m.sigma_f, blocks=[], label=m.label, single=single))
    return ObjectiveFit(fit.slip, new, fit.spar, fit.best, fit.given, fit.joint)


def check(exact_target, stand_target, flat: np.ndarray, sigma: float, scale: float,
          rng: np.random.Generator, n: int = CHECK_DRAWS) -> dict:
    """The stand-in against the exact model on ``n`` posterior draws of the stand-in (``flat``).

    Returns
    -------
    dict
        ``draws``; ``sd_log_ratio`` and ``max_log_ratio_spread`` (nats) of Δ = ln L_E - ln L_S;
        ``log_mean_ratio`` = ln mean exp(Δ) (the evidence correction); ``max_deviation_sigma``: the largest
        |r_E - r_S| over the draws and residuals, in units of the noise σ; ``passed``.
    """
    idx = rng.choice(len(flat), size=min(n, len(flat)), replace=False)
    deltas, dev = [], 0.0
    for theta in flat[idx]:
        le, ls = exact_target.log_likelihood(theta), stand_target.log_likelihood(theta)
        if not (math.isfinite(le) and math.isfinite(ls)):
            return {"draws": int(len(idx)), "passed": False, "reason": "a draw outside the exact model's domain"}
        deltas.append(le - ls)
        dev = max(dev, float(np.max(np.abs(exact_target.residual(theta) - stand_target.residual(theta)))))
    d = np.asarray(deltas)
    sd = float(np.std(d))
    top = float(np.max(d))
    out = {"draws": int(d.size), "sd_log_ratio": sd, "max_log_ratio_spread": float(np.max(d) - np.min(d)),
           "log_mean_ratio": top + math.log(float(np.mean(np.exp(d - top)))),
           "max_deviation_sigma": dev * scale / sigma if sigma > 0 else float("nan")}
    out["passed"] = bool(sd <= MAX_SD)
    if not out["passed"]:
        out["reason"] = (f"the log-likelihood ratio varies by {sd:.2g} nats (sd) over the draws, more than "
                         f"{MAX_SD:g}")
    return out


def _steps(par, stderr: dict, offset: str = "x_offset") -> list[float]:
    """Central-difference steps in q: half a standard error of ln W_ad, ln μh and the offset (internal
    names; the offset's is scaled by the control range), a small default where there is none."""
    def half(name: str, default: float) -> float:
        v = stderr.get(name)
        return 0.5 * float(v) if v is not None and math.isfinite(v) and v > 0 else default
    return [half("ln_work_of_adhesion", 1e-3), half("ln_mu_h", 1e-3), half(offset, 1e-4) * par.x_scale]


def minimise_exact(exact: CurveModel, par, scale: float, sigma: float, params, *, scale_covar: bool,
                   stderr: dict, tol: float, max_nfev: int, rounds: int = 3, at: dict | None = None,
                   polish: bool = True):
    """The exact model's least-squares optimum from ``params``, at a fraction of its cost (module docstring).

    Parameters
    ----------
    exact : CurveModel
        The exact-membrane model (fixed split; with a free split the exact model is minimised directly).
    par, scale, sigma
        As :func:`.lsq.residual_function`.
    params : lmfit.Parameters
        The start (internal values).
    stderr : dict
        Internal name -> standard error (of the large-stretch fit): the difference steps and the
        convergence scale.
    at : dict, optional
        Where to build the first stand-in (SI); default: the start.  The same point as an earlier build
        on a model sharing its histories (:meth:`~.model.CurveModel.split_before`) costs no new history.
    polish : bool
        Finish with a run on the exact model itself (its optimum, χ² and covariance).  Without it, the
        stand-in's optimum, close to the exact one, for comparing row splits.

    Returns
    -------
    (result, at) : (lmfit.minimizer.MinimizerResult, dict or None)
        The optimum, and where the last stand-in was built (None: the exact model was minimised directly).
    """
    from .lsq import minimise, residual_function  # noqa: PLC0415 - lsq is below this module
    cur, last = params, None
    if exact.fixed_split:
        scale_q = 2.0 * np.array(_steps(par, stderr))  # one standard error
        for _ in range(rounds):
            si = at if (last is None and at is not None) else par.si(cur)
            try:
                stand = CorrectedModel(exact, si, _steps(par, stderr))
            except ModelDomainError:
                break
            last = si
            res = minimise(residual_function(stand, par, scale, sigma), cur, scale_covar=scale_covar, tol=tol,
                           max_nfev=max_nfev)
            new = par.si(res.params)
            moved = np.abs(_q(new["work_of_adhesion"], new["mu_h"], new["x_offset"]) - stand.q0) / scale_q
            cur = res.params
            if float(np.max(moved)) < REBUILD:
                break
    if last is not None and not polish:
        return res, last
    return minimise(residual_function(exact, par, scale, sigma), cur, scale_covar=scale_covar, max_nfev=max_nfev,
                    tol=tol), None
