"""Per-curve checks of an objective's optimum, and each curve's entry in report.json ``curves`` (A7).

What a reviewer asks of a fit, per curve:

* **its own reduced χ²** against the shared fit, in units of the curve's row-to-row noise (the robust
  second-difference estimate, :func:`.starts.noise_estimate`, or the given σ): independent of the
  fitted σ_i, so a curve the shared values cannot follow shows χ²/ν well above 1.  Flagged above
  :data:`REDCHI_FLAG` (at ~200 rows the noise estimate itself scatters by ~15 % in σ²; 2 is > 5 of those);
* **its pull on the shared values** (several curves): the leave-one-out shift of ln W_ad and ln μh, from
  one Gauss–Newton step of the fit without the curve (J_{-k}ᵀJ_{-k})⁻¹ J_kᵀ r_k at the optimum, given in
  units of the joint standard errors; and the Hausman statistic Δᵀ(C_{-k} - C)⁻¹Δ, which is χ²(2) when
  the curve agrees with the others.  Flagged when its p-value is below :data:`PULL_P` (0.1 %); with
  three or more curves only on the most discordant curve;
* what the curve contributes: the standard errors of the shared values without it, the share of the
  shared values' precision it brings (``contribution`` = 1 - se²/se²_without), and its own estimates.

**Residual checks.** Checks on the residuals of a fit that the χ² alone cannot make (issue 9).

* **Serially correlated noise** (rows far denser than the noise correlation, e.g. an oversampled
  load cell with a low-pass filter): the lag-1 autocorrelation ρ of the residuals in row order.  For
  white noise ρ̂ ~ N(-1/n, 1/n), so ρ̂ > max(0.2, 3/√n) happens by chance with probability < 0.2 %.
  When it fires, the rows carry fewer independent observations: for AR(1) noise the effective
  number is n (1 - ρ)/(1 + ρ), so standard errors and interval half-widths grow by
  sqrt((1 + ρ)/(1 - ρ)) and ΔBIC shrinks by that factor squared.
* **Load-cell zero drift**: the rows the model predicts at zero force (before contact and after
  detachment) pin the load-cell zero; if the two groups disagree by more than 4 standard errors,
  the zero has drifted during the test.
"""
from __future__ import annotations

import dataclasses
import math

import numpy as np
from scipy import stats

from .model import OFFSET_NAME
from .objective import split_blocks
from .observables import PRIMARY
from .result import Estimate
from .starts import noise_estimate

__all__ = ["PULL_P", "REDCHI_FLAG", "curve_rows", "leave_one_out", "curve_entries", "curve_warnings", "plot_data",
           "lag1_autocorrelation", "correlation_factor", "widen", "zero_drift", "RHO_MIN"]

REDCHI_FLAG = 2.0
PULL_P = 1e-3


def curve_rows(fit) -> list[dict]:
    """Per member: force residuals (N), predictions, χ² in units of its reference noise, and each
    secondary block's χ² likewise."""
    r = np.asarray(fit.best.residual, float)
    out = []
    for i, (m, (rf, sec)) in enumerate(zip(fit.members, split_blocks(r, fit.members))):
        res_f = rf * m.sigma_f
        lo = fit.start(i)
        full = r[lo:lo + m.n_force] * m.sigma_f  # with the pull-off term
        sigma = m.sigma_f if fit.joint else fit.sigma
        ref = sigma if fit.given[PRIMARY] else (noise_estimate(m.model.force) or sigma)
        nu_k = 2.0 / len(fit.members) + len(m.par.names) - 2
        chi_f = float(res_f @ res_f) / ref ** 2  # the rows: what a curve's reduced χ² flags
        row = {"force_residual": res_f, "predicted": m.model.force - res_f, "chisqr": float(full @ full) / ref ** 2,
               "n_residuals": m.size, "redchi": chi_f / max(m.model.force.size - nu_k, 1.0), "sigma_force": sigma,
               "noise_reference": ref, "blocks": {}}
        for b, rb in zip(m.blocks, sec):
            res_b = rb * b.sigma
            ref_b = b.sigma if b.given else (b.observable.noise(b.data.values) or b.sigma)
            chi_b = float(res_b @ res_b) / ref_b ** 2
            row["chisqr"] += chi_b
            row["blocks"][b.observable.name] = {"residual": res_b, "redchi": chi_b / max(rb.size, 1),
                                                "reference": ref_b}
        out.append(row)
    return out


def _jacobian(residual, params, steps=None) -> tuple[np.ndarray, list[str], np.ndarray]:
    """Jacobian of the joint residual at ``params`` (varying parameters only): central secants over
    ± ``steps`` (the fit's secant steps) when given, else forward differences."""
    names = [n for n, p in params.items() if p.vary]
    r0 = residual(params)
    jac = np.empty((r0.size, len(names)))
    for k, n in enumerate(names):
        if steps is not None:
            hi, lo = params.copy(), params.copy()
            hi[n].value, lo[n].value = params[n].value + steps[k], params[n].value - steps[k]
            jac[:, k] = (residual(hi) - residual(lo)) / (2.0 * steps[k])
            continue
        p = params.copy()
        h = 1e-5 * max(1.0, abs(p[n].value))
        if p[n].value + h > p[n].max:
            h = -h
        p[n].value = p[n].value + h
        jac[:, k] = (residual(p) - r0) / h
    return jac, names, r0


def _reference_weights(fit, rows: list[dict], n: int) -> np.ndarray:
    """Per residual row: σ_fitted/σ_reference of its block, so that a curve the shared values cannot
    follow keeps its true weight (its fitted σ has grown to absorb the misfit)."""
    w = np.ones(n)
    for k, (m, row) in enumerate(zip(fit.members, rows)):
        lo = fit.start(k)
        w[lo:lo + m.n_force] = m.sigma_f / row["noise_reference"]
        lo += m.n_force
        for b in m.blocks:
            w[lo:lo + b.data.rows.size] = b.sigma / row["blocks"][b.observable.name]["reference"]
            lo += b.data.rows.size
    return w


def _gn(jac, r, rows, cols):
    """Gauss–Newton step and covariance over ``cols`` from the residual rows ``rows``."""
    j = jac[np.ix_(rows, cols)]
    cov = np.linalg.pinv(j.T @ j)
    return -cov @ (j.T @ r[rows]), cov


def leave_one_out(fit, rows: list[dict]) -> list[dict]:
    """Per curve: shift of the shared ln W_ad, ln μh without it (in joint standard errors), their
    standard errors without it, and the Hausman χ²(2) statistic with its p-value (module docstring)."""
    jac, names, r = _jacobian(fit.residual, fit.best.params, fit.secant_steps)
    w = _reference_weights(fit, rows, r.size)
    jac, r = jac * w[:, None], r * w
    shared = [names.index("ln_work_of_adhesion"), names.index("ln_mu_h")]
    everything = np.ones(r.size, bool)
    step_full, cov_full = _gn(jac, r, everything, list(range(len(names))))
    c_full = cov_full[np.ix_(shared, shared)]
    se = np.sqrt(np.diag(c_full))
    out = []
    for k, m in enumerate(fit.members):
        keep = everything.copy()
        keep[fit.start(k):fit.start(k) + m.size] = False
        cols = [i for i, n in enumerate(names) if n.startswith("ln_") or n.rsplit("_", 1)[-1] != str(k)]
        step, cov = _gn(jac, r, keep, cols)
        s_idx = [cols.index(i) for i in shared]
        delta = step[s_idx] - step_full[shared]
        c_w = cov[np.ix_(s_idx, s_idx)]
        stat = float(delta @ np.linalg.pinv(c_w - c_full) @ delta)
        sw = np.sqrt(np.clip(np.diag(c_w), 0.0, None))
        out.append({"shift_in_stderr": {"work_of_adhesion": float(delta[0] / se[0]), "mu_h": float(delta[1] / se[1])},
                    "stderr_without": {"work_of_adhesion": float(sw[0]), "mu_h": float(sw[1])},
                    "stderr_joint": {"work_of_adhesion": float(se[0]), "mu_h": float(se[1])},
                    "contribution": {key: float(1.0 - (se[j] / sw[j]) ** 2) if sw[j] > 0 else None
                                     for j, key in enumerate(("work_of_adhesion", "mu_h"))},
                    "stderr_note": "of ln W_ad and ln μh (relative standard errors)",
                    "chi2": stat, "p_value": float(stats.chi2.sf(stat, 2))})
    return out


def _offsets(fit, k: int) -> dict:
    m = fit.members[k]
    out = {}
    for base in ("x_offset", "force_offset", "force_drift"):
        p = fit.best.params.get(fit.spar.name(base, k))
        if p is None:
            continue
        scale = m.par.x_scale if base == "x_offset" else m.par.f_scale
        short = {"x_offset": OFFSET_NAME[m.model.control].removesuffix("_offset"), "force_offset": "force",
                 "force_drift": "force_drift"}[base]
        se = p.stderr * scale if p.stderr is not None and np.isfinite(p.stderr) else None
        out[short] = {"value": p.value * scale, "stderr": se, "unit": "m" if short == "displacement" else
                      ("Pa" if short == "pressure" else "N")}
    if "force" not in out:
        out["force"] = {"value": 0.0, "stderr": None, "unit": "N", "note": "fixed at 0"}
    return out


def curve_entries(fit, alone: list) -> list[dict]:
    """report.json ``curves`` (docs/contracts.md A7): per curve its file, offsets, reduced χ², rows, the
    checks of the module docstring, and its own estimates (``alone``: each curve's own SlipFit)."""
    rows = curve_rows(fit)
    loo = leave_one_out(fit, rows) if len(fit.members) > 1 else [None] * len(fit.members)
    out = []
    for k, (m, row, s) in enumerate(zip(fit.members, rows, alone)):
        sc = m.model.scene
        e = {"file": m.label, "offsets": _offsets(fit, k), "redchi": row["redchi"], "n_points": int(m.model.force.size),
             "sigma_force": row["sigma_force"], "noise_reference_force": row["noise_reference"],
             "scene": {"control": sc.control, "pressure": sc.pressure, "gap": sc.gap, "file": sc.source},
             "first_detached_row": m.model.segments.i_jump if m.model.fixed_split else None,
             "alone": {n: e.as_dict() for n, e in s.parameters.items() if n in ("work_of_adhesion", "mu_h")},
             "alone_redchi": s.redchi, "leave_one_out": loo[k], "contact_radius": None, "flags": []}
        for b in m.blocks:
            e[b.observable.name] = {"n_used": int(b.data.rows.size), "n_missing": b.data.n_missing,
                                    "n_zero_not_in_contact": b.data.n_zero, "sigma": b.sigma,
                                    "redchi": row["blocks"][b.observable.name]["redchi"]}
        if e["redchi"] > REDCHI_FLAG:
            e["flags"].append("redchi")
        e["flags"] += [f"redchi_{b.observable.name}" for b in m.blocks if e[b.observable.name]["redchi"] > REDCHI_FLAG]
        out.append(e)
    _pull_flags(out)
    return out


def _pull_flags(entries: list[dict]) -> None:
    """Flag the pull: with three or more curves only the most discordant one (leaving out a good curve
    leaves the odd one in, so the good curves' pulls are large too); with two curves, both."""
    p = [e["leave_one_out"]["p_value"] for e in entries if e["leave_one_out"]]
    if len(p) < 2 or min(p) >= PULL_P:
        return
    # ranked by the statistic, not the p-value: two discordant curves can both have p = 0.0 in floating point
    stat = [e["leave_one_out"]["chi2"] for e in entries]
    worst = [int(np.argmax(stat))] if len(entries) > 2 else list(range(len(entries)))
    for k in worst:
        entries[k]["flags"].append("pull")


def curve_warnings(curves: list[dict], fit) -> list[str]:
    """Plain sentences about the curves the checks flagged."""
    out = []
    several = len(curves) > 1
    for e, m in zip(curves, fit.members):
        name = e["file"]
        if "redchi" in e["flags"] and several:
            out.append(f"Curve {name} does not follow the shared fit: its reduced χ² is {e['redchi']:.3g} (alone "
                       f"{e['alone_redchi']:.3g}); a different membrane, a wrong scene or a bad run? Check it, or "
                       f"fit it on its own.")
        for b in m.blocks:
            obs = b.observable
            if f"redchi_{obs.name}" in e["flags"]:
                where = "the shared fit" if several else "the fitted model"
                out.append(f"Curve {name}: the {obs.label} does not follow {where} (reduced χ² "
                           f"{e[obs.name]['redchi']:.3g}).")
            if e[obs.name]["n_missing"]:
                out.append(f"Curve {name}: {e[obs.name]['n_missing']} rows without a {obs.label} were skipped "
                           f"(the force rows are used).")
        if "pull" in e["flags"]:
            s = e["leave_one_out"]["shift_in_stderr"]
            out.append(f"Curve {name} disagrees with the others: without it W_ad moves by {s['work_of_adhesion']:+.2g} "
                       f"and μh by {s['mu_h']:+.2g} standard errors (p = {e['leave_one_out']['p_value']:.2g}).")
    return out


def plot_data(fit) -> list[dict]:
    """Per curve: data, fitted force and each secondary observable, for the series figure."""
    shared, offs = fit.si()
    out = []
    for m, row, off in zip(fit.members, curve_rows(fit), offs):
        d = {"label": m.label, "control": m.model.control, "x": m.model.x, "force": m.model.force,
             "predicted": row["predicted"], "sigma_force": row["sigma_force"]}
        for b in m.blocks:  # the figure knows the contact radius by these keys
            d.update(a_rows=b.data.rows, a=b.data.values, sigma_a=b.sigma, a_predicted=b.observable.model(
                m.model, shared["work_of_adhesion"], shared["mu_h"], off["x_offset"]))
        out.append(d)
    return out


#: smallest lag-1 autocorrelation that counts as correlated noise (with 3/sqrt(n))
RHO_MIN = 0.2
#: ρ used at most in the widening (the AR(1) factor diverges at 1)
RHO_CAP = 0.95
#: a zero drift below this fraction of the peak force is never reported (noise-free curves: the residuals
#: are the model's interpolation error, and a 4-standard-error test of that is meaningless)
DRIFT_FLOOR = 1e-4
#: rows per group needed before the zero-drift check speaks
MIN_ZERO_ROWS = 4


def lag1_autocorrelation(r: np.ndarray) -> float:
    """Lag-1 autocorrelation of a residual vector in row order (0 for fewer than 3 rows)."""
    r = np.asarray(r, float)
    r = r[np.isfinite(r)]
    if r.size < 3:
        return 0.0
    d = r - r.mean()
    den = float(d @ d)
    return float(d[1:] @ d[:-1]) / den if den > 0 else 0.0


def correlation_factor(r: np.ndarray, floor: float = 0.0) -> tuple[float, float]:
    """(ρ, factor): the lag-1 autocorrelation and the interval widening sqrt((1 + ρ)/(1 - ρ));
    factor is 1 unless ρ exceeds max(:data:`RHO_MIN`, 3/√n), and when the residuals' RMS is below
    ``floor`` (the model's own precision: noise-free data, whose smooth interpolation error is not noise)."""
    rho = lag1_autocorrelation(r)
    n = max(int(np.size(r)), 1)
    if rho <= max(RHO_MIN, 3.0 / math.sqrt(n)) or float(np.sqrt(np.mean(np.square(r)))) < floor:
        return rho, 1.0
    rc = min(rho, RHO_CAP)
    return rho, math.sqrt((1.0 + rc) / (1.0 - rc))


def _stretch(value: float, bound: float | None, factor: float, log: bool) -> float | None:
    if bound is None:
        return None
    if log and value > 0 and bound > 0:
        return math.exp(math.log(value) + factor * (math.log(bound) - math.log(value)))
    return value + factor * (bound - value)


def widen(e: Estimate, factor: float) -> Estimate:
    """The estimate with its standard error and interval widened by ``factor`` about its value
    (in ln for W_ad and μh, where the intervals are computed)."""
    if factor == 1.0:
        return e
    log = e.name in ("work_of_adhesion", "mu_h")
    ci = None if e.ci95 is None else tuple(_stretch(e.value, b, factor, log) for b in e.ci95)
    cov = None if e.ci95_covariance is None else tuple(_stretch(e.value, b, factor, log)
                                                       for b in e.ci95_covariance)
    return dataclasses.replace(e, stderr=None if e.stderr is None else e.stderr * factor, ci95=ci,
                               ci95_covariance=cov,
                               ci_method=f"{e.ci_method} (widened x{factor:.2g} for correlated noise)")


def zero_drift(resid: np.ndarray, before: np.ndarray, after: np.ndarray, sigma: float,
               f_peak: float) -> str | None:
    """A plain warning when the force before contact and after detachment disagree.

    Parameters
    ----------
    resid : ndarray
        Measured minus fitted force at every row, N.
    before, after : ndarray of bool
        Rows the model puts at zero force before contact and after detachment.
    sigma : float
        Force noise, N.
    f_peak : float
        Largest measured force, N (for the percentage).
    """
    if before.sum() < MIN_ZERO_ROWS or after.sum() < MIN_ZERO_ROWS or not sigma > 0:
        return None
    m1, m2 = float(np.mean(resid[before])), float(np.mean(resid[after]))
    se = sigma * math.sqrt(1.0 / before.sum() + 1.0 / after.sum())
    d = m2 - m1
    if abs(d) <= max(4.0 * se, DRIFT_FLOOR * f_peak):  # below 0.01 % of the peak: the model's own precision
        return None
    return (f"The load-cell zero drifted during the test: the force after detachment differs from the force "
            f"before contact by {d * 1e3:.3g} mN ({100 * abs(d) / f_peak:.2g} % of the peak force). The fit uses "
            f"one zero for the whole test; re-tare the load cell or remove the drift before fitting.")
