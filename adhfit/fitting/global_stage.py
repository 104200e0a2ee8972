"""The least-squares stage of a series fit (:func:`joint_stage`): what :func:`.global_fit.fit_global`
reports, and where a global MCMC fit (:mod:`.global_mcmc`) starts.

One W_ad, one μh and one slip condition for every curve; offsets per curve; each curve its own scene.

Procedure, per slip condition:

1. **each curve alone** (:func:`~.lsq.fit_slip`): its start values, its row split (the pull-off row,
   found by likelihood) and its own estimates (reported per curve, for comparison);
2. **the joint least-squares fit** (:mod:`.series`) from the inverse-variance mean of the single
   estimates and from each curve's own optimum (best two minimised);
3. **noise levels**: each curve's force noise σ_i (and contact-radius noise σ_a,i) is unknown unless
   given; it is re-estimated from that block's residuals, σ² = RSS/(n - k), and the fit repeated until
   the σ's settle (iteratively reweighted least squares).  The fixed point maximises the likelihood
   with every σ profiled out, -2 ln L = Σ_g n_g ln(RSS_g/n_g), which is also what the slip comparison
   uses (:mod:`.selection`: same ΔBIC scale and verdict words as a single fit);
4. **the row split** is re-checked at the joint optimum (a curve whose pull-off row moves is refitted).

Intervals: the covariance from a secant Jacobian at the scale of each parameter's uncertainty
(:mod:`.global_secant`; residuals in units of σ, not rescaled) and, for the reported slip condition,
the likelihood profile (χ²(1) critical value) joined with the covariance interval (a curve's last
attached row meeting its fold stops a profile short: the recovery study's force-only profile intervals
held the truth in 32/40, the covariance ones in 38/40); the ``status`` rules of a single fit (A5b).
"""
from __future__ import annotations

import math

import numpy as np

from ..errors import InputError
from .global_secant import apply_secant
from .global_splits import check_splits
from .lsq import COARSE_TOL, FINE_TOL, fit_slip, minimise
from .model import CurveModel, segment
from .options import DEFAULT_POINTS, SLIP_CHOICES
from .profile import one_side, profile_interval
from .residual_checks import correlation_factor, widen
from .result import Estimate, SlipFit
from .series import (Member, SeriesParametrisation, noise_floor, radius_data, series_residual, split_blocks)
from .starts import noise_estimate
from .summary import Z95, _from_profile, summarize

__all__ = ["JointStage", "SeriesFit", "joint_stage"]

#: stop re-estimating the noise levels when none moves by more than this fraction
SIGMA_RTOL = 0.02
MAX_REWEIGHT = 4
#: least noise level, as a fraction of the largest force (or contact radius): noise-free data must not
#: get an unbounded weight
SIGMA_FLOOR = 1e-5
_LN = {"work_of_adhesion": "ln_work_of_adhesion", "mu_h": "ln_mu_h"}


class SeriesFit:
    """One slip condition's joint fit: members, parametrisation, lmfit optimum, single fits."""

    def __init__(self, slip, members, spar, best, singles, given):
        self.slip, self.members, self.spar, self.best = slip, members, spar, best
        self.singles, self.given = singles, given

    @property
    def residual(self):
        return series_residual(self.members, self.spar)

    def groups(self) -> list[dict]:
        """Per (curve, observable): n, RSS (physical units²), σ, σ given?"""
        blocks = split_blocks(np.asarray(self.best.residual), self.members)
        out = []
        for i, (m, (rf, ra)) in enumerate(zip(self.members, blocks)):
            nf = m.model.force.size + (m.model.jump is not None)
            rfull = np.asarray(self.best.residual)[self._start(i):self._start(i) + nf]
            out.append({"curve": i, "obs": "force", "n": nf, "rss": float(rfull @ rfull) * m.sigma_f ** 2,
                        "sigma": m.sigma_f, "given": self.given["force"]})
            if m.radius is not None:
                out.append({"curve": i, "obs": "contact_radius", "n": ra.size,
                            "rss": float(ra @ ra) * m.sigma_a ** 2, "sigma": m.sigma_a,
                            "given": self.given["contact_radius"]})
        return out

    def _start(self, i: int) -> int:
        k = 0
        for m in self.members[:i]:
            k += m.model.force.size + (m.model.jump is not None) + (0 if m.radius is None else m.radius.rows.size)
        return k

    def criteria(self) -> tuple[float, float]:
        """(AIC, BIC) with every estimated σ profiled out (module docstring)."""
        m2lnl, n = 0.0, 0
        for g in self.groups():
            n += g["n"]
            m2lnl += g["rss"] / g["sigma"] ** 2 if g["given"] else g["n"] * math.log(max(g["rss"], 1e-300) / g["n"])
        k = self.best.nvarys
        return m2lnl + 2 * k, m2lnl + k * math.log(n)


def _inputs(curves, scenes):
    from .prepare import read_inputs as one  # noqa: PLC0415
    curves = list(curves)
    if len(curves) < 2:
        raise InputError("curves", len(curves), "at least 2 curves for a global fit")
    if not isinstance(scenes, (list, tuple)):
        scenes = [scenes] * len(curves)
    if len(scenes) != len(curves):
        raise InputError("scenes", len(scenes), f"one scene, or one per curve ({len(curves)})")
    pairs = [one(c, s) for c, s in zip(curves, scenes)]
    return [p[0] for p in pairs], [p[1] for p in pairs]


def _positive(name, value):
    if value is not None and not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
        raise InputError(name, value, "a positive number in SI units (N for sigma, m for sigma_contact_radius)")


def _single(curve, scene, slip, seg, points, sigma, fit_x_offset, fit_force_offset, extra):
    model = CurveModel(curve, scene, slip, points=points, segments=seg)
    return fit_slip(model, sigma=sigma, fit_x_offset=fit_x_offset, fit_force_offset=fit_force_offset,
                    extra_starts=extra)


def _sigma_f(raw) -> float:
    return raw.scale if raw.sigma_given else raw.scale * math.sqrt(max(raw.best.redchi, 1e-300))


def _mean_start(singles) -> dict:
    """Inverse-variance mean of the single-curve ln W_ad and ln μh (equal weights without covariances)."""
    out = {}
    for name, ln in _LN.items():
        vals, wts = [], []
        for r in singles:
            p = r.best.params[ln]
            vals.append(p.value)
            wts.append(1.0 / p.stderr ** 2 if p.stderr and np.isfinite(p.stderr) and p.stderr > 0 else 0.0)
        w = np.array(wts) if sum(wts) > 0 else np.ones(len(vals))
        out[name] = math.exp(float(np.average(vals, weights=w)))
    return out


def _minimise_starts(residual, spar, starts, offsets):
    """Score every shared start by one evaluation, minimise the best two (second coarsely, refined
    only if it wins); returns the best lmfit result."""
    scored = []
    for s in starts:
        r = residual(spar.params(s, offsets))
        scored.append((float(r @ r), s))
    scored.sort(key=lambda t: t[0])
    best = None
    for i, (_, s) in enumerate(scored[:2]):
        res = minimise(residual, spar.params(s, offsets), scale_covar=False, tol=FINE_TOL if i == 0 else COARSE_TOL)
        if best is not None and res.chisqr < best.chisqr * (1 - 1e-6):
            res = minimise(residual, res.params, scale_covar=False, tol=FINE_TOL)
        if best is None or res.chisqr < best.chisqr:
            best = res
    return best


def _reweight(members, best, given) -> bool:
    """Re-estimate every non-given σ from its block's residuals; True when one moved by > SIGMA_RTOL."""
    blocks = split_blocks(np.asarray(best.residual), members)
    k_share = 2.0 / len(members)
    moved = False
    for m, (rf, ra) in zip(members, blocks):
        k = k_share + len(m.par.names) - 2
        if not given["force"] and rf.size > k + 1:
            new = m.sigma_f * math.sqrt(float(rf @ rf) / (rf.size - k))
            moved |= abs(new / m.sigma_f - 1.0) > SIGMA_RTOL
            m.sigma_f = max(new, SIGMA_FLOOR * m.par.f_scale)
        if m.radius is not None and not given["contact_radius"] and ra.size > 1:
            new = m.sigma_a * math.sqrt(float(ra @ ra) / ra.size)
            moved |= abs(new / m.sigma_a - 1.0) > SIGMA_RTOL
            m.sigma_a = max(new, SIGMA_FLOOR * float(np.max(m.radius.values)))
    return moved


def _joint(slip, curves, scenes, segs, singles, sigma, sigma_a, use_radius, points):
    """The joint fit of one slip condition (steps 2–4 of the module docstring)."""
    given = {"force": sigma is not None, "contact_radius": sigma_a is not None}
    members = []
    for c, r in zip(curves, singles):
        rad = radius_data(c) if use_radius else None
        sa = None
        if rad is not None:
            sa = sigma_a if sigma_a is not None else (noise_estimate(rad.values) or noise_floor(rad.values))
        members.append(Member(model=r.model, par=r.par, sigma_f=sigma if sigma is not None else _sigma_f(r),
                              radius=rad, sigma_a=sa, label=str(c.path)))
    spar = SeriesParametrisation(tuple(m.par for m in members))
    offsets = []
    for r in singles:
        si = r.par.si(r.best.params)
        offsets.append({"x_offset": si["x_offset"], "force_offset": si["force_offset"]})
    starts = [_mean_start(singles)] + [{k: r.par.si(r.best.params)[k] for k in _LN} for r in singles]
    best = _minimise_starts(series_residual(members, spar), spar, starts, offsets)
    for _ in range(MAX_REWEIGHT):
        moved = _reweight(members, best, given)
        moved |= check_splits(members, curves, scenes, segs, slip, points, spar, best.params)
        if not moved:
            break
        best = minimise(series_residual(members, spar), best.params, scale_covar=False, tol=FINE_TOL)
    sf = SeriesFit(slip, members, spar, best, singles, given)
    apply_secant(sf)  # standard errors at the scale of the data (a row at a curve's fold: global_secant)
    return sf


def _estimates(sf: SeriesFit, profile: bool) -> tuple[dict, dict]:
    """Estimates of W_ad and μh (covariance; profile when asked) and the profile bookkeeping."""
    out, info = {}, {}
    best = sf.best
    for name, ln in _LN.items():
        p = best.params[ln]
        se = p.stderr if (p.stderr is not None and np.isfinite(p.stderr) and p.stderr > 0) else None
        value = math.exp(p.value)
        cov_ci = (math.exp(p.value - Z95 * se), math.exp(p.value + Z95 * se)) if se else None
        ci, method, status = cov_ci, ("covariance" if cov_ci else None), ("determined" if cov_ci else "undetermined")
        if profile:
            lo, hi = profile_interval(sf.residual, best, ln, sigma_given=True)
            if hi.open != lo.open:
                side = one_side(sf.residual, best, ln, -1.0 if hi.open else 1.0, sigma_given=True)
                if side.converged:
                    lo, hi = (side, hi) if hi.open else (lo, side)
            ci, method, status = _from_profile((lo, hi), math.exp, ci, method, status)
            if status == "determined" and cov_ci and ci and None not in ci:  # a fold stops a profile short
                ci, method = (min(ci[0], cov_ci[0]), max(ci[1], cov_ci[1])), f"{method} ∪ covariance"
            info[name] = {"subfits": lo.n_subfits + hi.n_subfits, "converged": [lo.converged, hi.converged],
                          "open": [lo.open, hi.open]}
        out[name] = Estimate(name, value, se * value if se else None, ci, method, cov_ci, status)
    return out, info


def _slipfit(sf: SeriesFit, profile: bool) -> SlipFit:
    """The :class:`SlipFit` of one slip condition's joint fit."""
    from .series_checks import curve_rows  # noqa: PLC0415
    est, info = _estimates(sf, profile)
    rows = curve_rows(sf)
    factor = max(correlation_factor(r["force_residual"])[1] for r in rows)
    rho = max(correlation_factor(r["force_residual"])[0] for r in rows)
    est = {k: widen(e, factor) for k, e in est.items()}
    aic, bic = sf.criteria()
    chisqr = float(sum(r["chisqr"] for r in rows))
    ndata, nvarys = int(sum(r["n_residuals"] for r in rows)), int(sf.best.nvarys)
    c = sf.best.covar
    corr = float(c[0, 1] / math.sqrt(c[0, 0] * c[1, 1])) if c is not None and c[0, 0] > 0 and c[1, 1] > 0 else None
    hist = sum(m.model.n_histories for m in sf.members)
    return SlipFit(slip=sf.slip, parameters=est, chisqr=chisqr, redchi=chisqr / max(ndata - nvarys, 1),
                   aic=aic, bic=bic, ndata=ndata, nvarys=nvarys, sigma=float("nan"), correlation=corr,
                   predicted=np.concatenate([r["predicted"] for r in rows]), model_curve={},
                   profile=info, n_evaluations=sum(m.model.n_evaluations for m in sf.members), n_histories=hist,
                   success=bool(sf.best.success), message=str(sf.best.message), raw=sf,
                   diagnostics=(), autocorrelation=rho, widening=factor)


class JointStage:
    """What the least-squares stage of a global fit found (inputs, joint fits per slip, verdict)."""

    def __init__(self, curves, scenes, joint, fits, verdict, singles, options):
        self.curves, self.scenes, self.joint, self.fits = curves, scenes, joint, fits
        self.verdict, self.singles, self.options = verdict, singles, options


def joint_stage(curves, scenes, *, slip: str = "auto", sigma: float | None = None,
                sigma_contact_radius: float | None = None, contact_radius: bool = True,
                fit_x_offset: bool | None = None, fit_force_offset: bool = True,
                points: int = DEFAULT_POINTS, profile: bool = True) -> JointStage:
    """Steps 1–4 of the module docstring for every slip condition, and the ΔBIC verdict (the least-squares
    global fit, and the start of a global MCMC fit).  Arguments as for :func:`.global_fit.fit_global`."""
    from .fit import _decide  # noqa: PLC0415 - one verdict rule for single and global fits
    if slip not in SLIP_CHOICES:
        raise InputError("slip", slip, "one of " + ", ".join(map(repr, SLIP_CHOICES)))
    _positive("sigma", sigma)
    _positive("sigma_contact_radius", sigma_contact_radius)
    curves, scenes = _inputs(curves, scenes)
    slips = ("no-slip", "frictionless") if slip == "auto" else (slip,)
    segs = [segment(c) for c in curves]
    singles: dict = {}
    for s in slips:
        singles[s] = []
        for i, (c, sc) in enumerate(zip(curves, scenes)):
            extra = [singles[o][i].par.si(singles[o][i].best.params) for o in singles if o != s]
            singles[s].append(_single(c, sc, s, segs[i], points, sigma, fit_x_offset, fit_force_offset, extra))
    joint = {s: _joint(s, curves, scenes, segs, singles[s], sigma, sigma_contact_radius, contact_radius, points)
             for s in slips}
    fits = {s: _slipfit(j, profile=False) for s, j in joint.items()}
    verdict = _decide(fits)
    if profile:
        wanted = verdict["parameters_from"]
        fits[wanted] = _slipfit(joint[wanted], profile=True)
        verdict = dict(_decide(fits), parameters_from=wanted)
    singles_summary = {s: [summarize(r, profile=False) for r in singles[s]] for s in slips}
    options = {"slip": slip, "sigma": sigma, "sigma_contact_radius": sigma_contact_radius,
               "contact_radius": contact_radius, "fit_x_offset": fit_x_offset,
               "fit_force_offset": fit_force_offset, "points": points, "profile": profile}
    return JointStage(curves, scenes, joint, fits, verdict, singles_summary, options)
