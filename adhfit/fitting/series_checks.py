"""Per-curve checks of a global fit and the assembled :class:`~.result.FitResult` (issue 13).

What a reviewer asks of a series fit, per curve:

* **its own reduced χ²** against the joint fit, in units of the curve's row-to-row noise (the robust
  second-difference estimate, :func:`.starts.noise_estimate`, or the given σ): independent of the
  fitted σ_i, so a curve the shared values cannot follow shows χ²/ν well above 1.  Flagged above
  :data:`REDCHI_FLAG` (at ~200 rows the noise estimate itself scatters by ~15 % in σ²; 2 is > 5 of those);
* **its pull on the shared values**: the leave-one-out shift of ln W_ad and ln μh, from one
  Gauss–Newton step of the fit without the curve (J_{-k}ᵀJ_{-k})⁻¹ J_kᵀ r_k at the optimum, given in
  units of the joint standard errors; and the Hausman statistic Δᵀ(C_{-k} - C)⁻¹Δ, which is χ²(2) when
  the curve agrees with the others.  Flagged when its p-value is below :data:`PULL_P` (0.1 %); with
  three or more curves only on the most discordant curve (:func:`_pull_flags`);
* what the curve contributes: the standard errors of the shared values without it, the share of the
  shared values' precision it brings (``contribution`` = 1 - se²/se²_without, linearised: 0 for a curve
  that adds nothing, near 1 for one that carries the fit alone), and its own single-curve estimates.
"""
from __future__ import annotations

import platform

import numpy as np
from scipy import stats

from .model import OFFSET_NAME
from .result import FitResult
from .series import radius_prediction
from .starts import noise_estimate

__all__ = ["PULL_P", "REDCHI_FLAG", "assemble", "curve_rows", "leave_one_out"]

REDCHI_FLAG = 2.0
PULL_P = 1e-3
_SHORT = {"x_offset": None, "force_offset": "force"}


def radius_noise(values: np.ndarray) -> float:
    """Row-to-row noise of a contact-radius column from its rows in contact only: the rows measured as 0
    (not in contact) have no noise, and their zero second differences would pull the robust estimate
    down (a 200-row curve with 22 such rows flagged its radius at χ²/n = 2 against its own model)."""
    v = np.asarray(values, float)
    return noise_estimate(v[v > 0])


def curve_rows(sf) -> list[dict]:
    """Per curve of one slip condition's joint fit: residuals, predictions and χ² (see module docstring)."""
    from .series import split_blocks  # noqa: PLC0415
    r = np.asarray(sf.best.residual)
    out = []
    for m, (rf, ra) in zip(sf.members, split_blocks(r, sf.members)):
        res_f = rf * m.sigma_f
        ref = m.sigma_f if sf.given["force"] else (noise_estimate(m.model.force) or m.sigma_f)
        nu_k = 2.0 / len(sf.members) + len(m.par.names) - 2
        chi_f = float(res_f @ res_f) / ref ** 2
        row = {"force_residual": res_f, "predicted": m.model.force - res_f, "chisqr": chi_f,
               "n_residuals": rf.size + ra.size, "redchi": chi_f / max(rf.size - nu_k, 1.0),
               "sigma_force": m.sigma_f, "noise_reference": ref}
        if m.radius is not None:
            res_a = ra * m.sigma_a
            ref_a = m.sigma_a if sf.given["contact_radius"] else (radius_noise(m.radius.values) or m.sigma_a)
            chi_a = float(res_a @ res_a) / ref_a ** 2
            row.update(chisqr=chi_f + chi_a, radius_residual=res_a, redchi_contact_radius=chi_a / max(ra.size, 1))
        out.append(row)
    return out


def _jacobian(residual, params, steps=None) -> tuple[np.ndarray, list[str], np.ndarray]:
    """Jacobian of the joint residual at ``params`` (varying parameters only): central secants over
    ± ``steps`` (the fit's secant steps, :mod:`.global_secant`) when given, else forward differences."""
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


def _reference_weights(sf, n: int) -> np.ndarray:
    """Per residual row: σ_fitted/σ_reference of its block (the reference is the row-to-row noise or
    the given σ), so that a curve the shared values cannot follow keeps its true weight (its fitted σ
    has grown to absorb the misfit)."""
    w = np.ones(n)
    for k, (m, row) in enumerate(zip(sf.members, curve_rows(sf))):
        lo = sf._start(k)
        nf = m.model.force.size + (m.model.jump is not None)
        w[lo:lo + nf] = m.sigma_f / row["noise_reference"]
        if m.radius is not None:
            ref = m.sigma_a if sf.given["contact_radius"] else (radius_noise(m.radius.values) or m.sigma_a)
            w[lo + nf:lo + nf + m.radius.rows.size] = m.sigma_a / ref
    return w


def _gn(jac, r, rows, cols):
    """Gauss–Newton step and covariance over ``cols`` from the residual rows ``rows``."""
    j = jac[np.ix_(rows, cols)]
    cov = np.linalg.pinv(j.T @ j)
    return -cov @ (j.T @ r[rows]), cov


def leave_one_out(sf) -> list[dict]:
    """Per curve: shift of the shared ln W_ad, ln μh without it (in joint standard errors), their
    standard errors without it, and the Hausman χ²(2) statistic Δᵀ(C_{-k} - C)⁻¹Δ with its p-value.

    Linearised at the optimum, with every block weighted by its reference noise
    (:func:`_reference_weights`): Δ is the difference of the Gauss–Newton steps with and without the
    curve's rows (and its offsets)."""
    jac, names, r = _jacobian(sf.residual, sf.best.params, getattr(sf, "secant_steps", None))
    w = _reference_weights(sf, r.size)
    jac, r = jac * w[:, None], r * w
    shared = [names.index("ln_work_of_adhesion"), names.index("ln_mu_h")]
    everything = np.ones(r.size, bool)
    step_full, cov_full = _gn(jac, r, everything, list(range(len(names))))
    c_full = cov_full[np.ix_(shared, shared)]
    se = np.sqrt(np.diag(c_full))
    out = []
    for k, m in enumerate(sf.members):
        lo = sf._start(k)
        n_k = m.model.force.size + (m.model.jump is not None) + (0 if m.radius is None else m.radius.rows.size)
        rows = everything.copy()
        rows[lo:lo + n_k] = False
        cols = [i for i, n in enumerate(names) if n.startswith("ln_") or n.rsplit("_", 1)[-1] != str(k)]
        step, cov = _gn(jac, r, rows, cols)
        s_idx = [cols.index(i) for i in shared]
        delta = step[s_idx] - step_full[shared]
        c_w = cov[np.ix_(s_idx, s_idx)]
        stat = float(delta @ np.linalg.pinv(c_w - c_full) @ delta)
        sw = np.sqrt(np.clip(np.diag(c_w), 0.0, None))
        out.append({"shift_in_stderr": {"work_of_adhesion": float(delta[0] / se[0]), "mu_h": float(delta[1] / se[1])},
                    "stderr_without": {"work_of_adhesion": float(sw[0]), "mu_h": float(sw[1])},
                    "stderr_joint": {"work_of_adhesion": float(se[0]), "mu_h": float(se[1])},
                    # the share of the shared value's precision (1/se²) that this curve brings
                    "contribution": {k: float(1.0 - (se[j] / sw[j]) ** 2) if sw[j] > 0 else None
                                     for j, k in enumerate(("work_of_adhesion", "mu_h"))},
                    "stderr_note": "of ln W_ad and ln μh (relative standard errors)",
                    "chi2": stat, "p_value": float(stats.chi2.sf(stat, 2))})
    return out


def _offsets(sf, k: int) -> dict:
    m = sf.members[k]
    out = {}
    for name in ("x_offset", "force_offset"):
        p = sf.best.params.get(f"{name}_{k}")
        if p is None:
            continue
        scale = m.par.x_scale if name == "x_offset" else m.par.f_scale
        short = OFFSET_NAME[m.model.control].removesuffix("_offset") if name == "x_offset" else "force"
        se = p.stderr * scale if p.stderr is not None and np.isfinite(p.stderr) else None
        out[short] = {"value": p.value * scale, "stderr": se, "unit": "m" if short == "displacement" else
                      ("Pa" if short == "pressure" else "N")}
    if "force" not in out:
        out["force"] = {"value": 0.0, "stderr": None, "unit": "N", "note": "fixed at 0"}
    return out


def _alone(single) -> dict:
    return {k: e.as_dict() for k, e in single.parameters.items() if k in ("work_of_adhesion", "mu_h")}


def _curve_entries(sf, singles, loo) -> list[dict]:
    rows = curve_rows(sf)
    out = []
    for k, (m, row, s) in enumerate(zip(sf.members, rows, singles)):
        sc = m.model.scene
        e = {"file": m.label, "offsets": _offsets(sf, k), "redchi": row["redchi"], "n_points": int(m.model.force.size),
             "sigma_force": row["sigma_force"], "noise_reference_force": row["noise_reference"],
             "scene": {"control": sc.control, "pressure": sc.pressure, "gap": sc.gap, "file": sc.source},
             "first_detached_row": m.model.segments.i_jump if m.model.fixed_split else None,
             "alone": _alone(s), "alone_redchi": s.redchi, "leave_one_out": loo[k], "contact_radius": None}
        if m.radius is not None:
            e["contact_radius"] = {"n_used": int(m.radius.rows.size), "n_missing": m.radius.n_missing,
                                   "n_zero_not_in_contact": m.radius.n_zero, "sigma": m.sigma_a,
                                   "redchi": row["redchi_contact_radius"]}
        e["flags"] = _flags(e)
        out.append(e)
    _pull_flags(out)
    return out


def _pull_flags(entries: list[dict]) -> None:
    """Flag the pull: with three or more curves only the most discordant one (leaving out a good curve
    leaves the odd one in, so the good curves' pulls are large too); with two curves, both (which
    one is odd cannot be told)."""
    p = [e["leave_one_out"]["p_value"] for e in entries]
    if min(p) >= PULL_P:
        return
    worst = [int(np.argmin(p))] if len(entries) > 2 else list(range(len(entries)))
    for k in worst:
        entries[k]["flags"].append("pull")


def _flags(e: dict) -> list[str]:
    out = []
    if e["redchi"] > REDCHI_FLAG:
        out.append("redchi")
    if e["contact_radius"] and e["contact_radius"]["redchi"] > REDCHI_FLAG:
        out.append("redchi_contact_radius")
    return out


def _curve_warnings(curves: list[dict]) -> list[str]:
    out = []
    for e in curves:
        name = e["file"]
        if "redchi" in e["flags"]:
            out.append(f"Curve {name} does not follow the shared fit: its reduced χ² is {e['redchi']:.3g} (alone "
                       f"{e['alone_redchi']:.3g}); a different membrane, a wrong scene or a bad run? Check it, or "
                       f"fit it on its own.")
        if "redchi_contact_radius" in e["flags"]:
            out.append(f"Curve {name}: the contact radius does not follow the shared fit (reduced χ² "
                       f"{e['contact_radius']['redchi']:.3g}).")
        if "pull" in e["flags"]:
            s = e["leave_one_out"]["shift_in_stderr"]
            out.append(f"Curve {name} disagrees with the others: without it W_ad moves by {s['work_of_adhesion']:+.2g} "
                       f"and μh by {s['mu_h']:+.2g} standard errors (p = {e['leave_one_out']['p_value']:.2g}).")
        cr = e["contact_radius"]
        if cr and cr["n_missing"]:
            out.append(f"Curve {name}: {cr['n_missing']} rows without a contact radius were skipped "
                       f"(the force rows are used).")
    return out


def _plot_data(sf) -> list[dict]:
    shared, offs = sf.spar.si(sf.best.params)
    out = []
    for m, row, off in zip(sf.members, curve_rows(sf), offs):
        d = {"label": m.label, "control": m.model.control, "x": m.model.x, "force": m.model.force,
             "predicted": row["predicted"], "sigma_force": m.sigma_f}
        if m.radius is not None:
            d.update(a_rows=m.radius.rows, a=m.radius.values, a_predicted=radius_prediction(
                m.model, shared["work_of_adhesion"], shared["mu_h"], off["x_offset"]), sigma_a=m.sigma_a)
        out.append(d)
    return out


def _status_warnings(params: dict) -> list[str]:
    out = []
    for name, e in params.items():
        label = {"work_of_adhesion": "W_ad", "mu_h": "μh"}[name]
        if e.status == "lower_bound":
            out.append(f"The series only bounds {label} from below: {label} ≥ {e.ci95[0]:.3g} {e.unit} (one-sided 95 %).")
        elif e.status == "upper_bound":
            out.append(f"The series only bounds {label} from above: {label} ≤ {e.ci95[1]:.3g} {e.unit} (one-sided 95 %).")
        elif e.status == "undetermined":
            out.append(f"The series does not determine {label}: no value or interval is reported.")
    return out


def assemble(curves, scenes, joint, fits, verdict, singles, *, options, seed, t0) -> FitResult:
    """The :class:`FitResult` of a global fit, with ``curves`` and the per-curve warnings."""
    import time  # noqa: PLC0415

    from .fit import _reported  # noqa: PLC0415
    from .prepare import provenance as _provenance  # noqa: PLC0415
    rep = verdict["parameters_from"]
    sf = joint[rep]
    entries = _curve_entries(sf, singles[rep], leave_one_out(sf))
    reported = _reported(fits, verdict)
    warnings = list(dict.fromkeys(w for sc in scenes for w in sc.warnings()))
    if verdict["selected"] is None and len(fits) > 1:
        warnings.append(f"The series cannot decide between no-slip and frictionless contact "
                        f"({verdict['explanation'].rstrip('.')}); the estimates are the {verdict['favoured']} fit's, "
                        f"and their 95 % intervals cover both conditions' intervals.")
    warnings += _status_warnings(reported)
    if fits[rep].widening > 1.0:
        warnings.append(f"The force noise of at least one curve is correlated from row to row (lag-1 autocorrelation "
                        f"{fits[rep].autocorrelation:.2f}): the intervals were widened {fits[rep].widening:.2g}-fold.")
    warnings += _curve_warnings(entries)
    prov = _provenance(curves[0], scenes[0], seed, "lsq", options)
    prov.update(input=[c.path for c in curves], input_sha256=[c.sha256 for c in curves],
                scene_file=[sc.source for sc in scenes], scene=None, python=platform.python_version(),
                fit="global")
    obs = ["force"] + (["contact_radius"] if any(m.radius is not None for m in sf.members) else [])
    diag = [f"[{s}] joint fit: {f.message} ({'converged' if f.success else 'not converged'})" for s, f in fits.items()]
    return FitResult(
        method="lsq", slip=verdict, parameters=reported, fits=fits, n_points=sum(len(c.x) for c in curves),
        n_excluded=sum(len(c.excluded) for c in curves), sigma=float("nan"),
        sigma_source="per curve (curves[].sigma_force): " + ("given" if options["sigma"] is not None else
                                                              "estimated from each curve's residuals"),
        warnings=tuple(warnings), diagnostics=tuple(diag),
        n_evaluations=sum(f.n_evaluations for f in fits.values()),
        n_histories=sum(f.n_histories for f in fits.values()), wall_time=time.perf_counter() - t0,
        provenance=prov, segments={}, excluded=(), curve=None,
        raw={**{s: j.best for s, j in joint.items()}, "series_plot": _plot_data(sf)},
        observables=tuple(obs), curves=tuple(entries))
