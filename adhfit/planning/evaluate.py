"""One protocol's prediction: interval widths, slip-verdict probabilities, domain and membrane model.

For each true slip condition the noiseless curve (:mod:`.truth`) gives the Fisher widths
(:mod:`.information`; W_ad's from the fit's own profile where the rows at pull-off carry its information)
and the other condition's misfit (:mod:`.verdict`), for the nuisance set the fit uses on it and, weighted by
how often the fit uses each (:func:`.truth.drift_probability`), for the other one.  The membrane model is the
scene's; under ``auto`` it is the one the fit would choose at the truth (the fit's own rule,
:func:`adhfit.fitting.membrane.approximation_effect`: the exact membrane when the large-stretch
force is off by more than half σ at some row, or shifts W_ad or μh by more than half a standard error),
and the prediction is then made with that membrane's model.
"""
from __future__ import annotations

import dataclasses
import math

import numpy as np

from ..errors import AdhfitError
from ..fitting.lsq import COARSE_TOL, RawFit, minimise, residual_function
from ..fitting.membrane import EXACT_POINTS, approximation_effect
from ..fitting.starts import Start
from .information import (Z95, jacobian, log_widths, profile_widths_fit, radius_jacobian, reduced_information,
                          with_drift_flipped)
from .hull import hull_model
from .protocols import Protocol
from .truth import OutOfDomain, drift_probability, loading_end, noiseless_test
from .verdict import UNDECIDED_MIN, misfit, profile_other, verdict_probabilities

__all__ = ["predict", "auto_membrane", "OTHER"]

OTHER = {"no-slip": "frictionless", "frictionless": "no-slip"}
#: a nuisance set the fit uses in fewer replicates than this is left out of the prediction
MIXTURE_FLOOR = 0.02


def auto_membrane(truth) -> str:
    """The membrane model ``auto`` would fit to this noiseless curve at its noise level."""
    par, sigma = truth.par, truth.sigma
    best = minimise(residual_function(truth.model, par, sigma, sigma), par.params(Start(truth.values)),
                    scale_covar=False, tol=COARSE_TOL)
    raw = RawFit(slip=truth.model.slip, best=best, model=truth.model, par=par, scale=sigma, sigma_given=True,
                 starts=[])
    try:
        effect = approximation_effect(raw, sigma)
    except AdhfitError:  # no exact history at the truth: the fit then takes the exact membrane
        return "exact"
    return "exact" if effect.resolved() else "large-stretch"


def _interval(value: float, rel_se: float, limits: tuple | None = None) -> tuple[float, float]:
    if limits is not None:  # a profile's (asymmetric) ln limits relative to the value
        return value * math.exp(limits[0]), value * math.exp(limits[1])
    return value * math.exp(-Z95 * rel_se), value * math.exp(Z95 * rel_se)


def _weighted_median(values: np.ndarray, weights: np.ndarray) -> float:
    order = np.argsort(values)
    cum = np.cumsum(weights[order])
    return float(values[order][min(np.searchsorted(cum, 0.5 * cum[-1]), values.size - 1)])


def reported_widths(parts: list) -> dict:
    """The width the fit reports, as a distribution over its verdict (:func:`adhfit.fitting.stage.reported`):
    the true condition's interval when it is selected, the other's when that is, and otherwise the hull of
    both (the two optima differ, so an undecided verdict widens the interval).

    ``parts``: ``(weight, widths, truth values, misfit, verdict probabilities, hull model)`` of each nuisance
    set the fit may use (with and without the drift, :func:`.truth.drift_probability`), weights summing to 1;
    the hull model (:func:`.hull.hull_model`, or None) gives the undecided hull's distribution under the
    noise that leaves the verdict undecided; without it (or with too few undecided draws) the hull of the
    two noiseless intervals stands for it.

    Returns, per parameter: ``decided`` (the true condition's width, over the sets in proportion to how often
    each decides), ``undecided`` (the median hull of the undecided fits, the sets in proportion to how often
    each is undecided), ``undecided_noiseless`` (the hull of the noiseless intervals, what was predicted
    before the hull model), ``mean`` (the expected width over the verdict's probabilities) and ``median`` (the
    median of that mixture distribution: the decided and wrong widths as points, the hull as its draws).
    """
    out = {}
    for name in parts[0][1]:
        vals, wts = [], []  # the mixture distribution of the reported width
        dec_w, dec_p, und_vals, und_wts, noiseless, noiseless_p = 0.0, 0.0, [], [], 0.0, 0.0
        for weight, widths, truth, m, probs, hull in parts:
            w = widths[name]
            own = w["width"]
            p_true, p_wrong = probs["decided"], probs["wrong"]
            p_und = max(1.0 - p_true - p_wrong, 0.0)
            if m is None or m.widths is None or not math.isfinite(own):
                vals.append(np.array([own]))
                wts.append(np.array([weight]))
                dec_w, dec_p = dec_w + weight * own, dec_p + weight
                und_vals.append(np.array([own]))
                und_wts.append(np.array([weight * max(p_und, 1e-12)]))
                noiseless, noiseless_p = noiseless + weight * own, noiseless_p + weight
                continue
            other = m.widths[name]["width"]
            lo_t, hi_t = _interval(truth[name], w["relative_se"], w.get("interval"))
            lo_w, hi_w = _interval(m.values[name], m.widths[name]["relative_se"], m.widths[name].get("interval"))
            flat = max(hi_t, hi_w) - min(lo_t, lo_w)
            draws = hull.undecided_hulls(name) if hull is not None and name in hull.hulls else None
            if draws is None:
                draws = np.array([flat])
            vals += [np.array([own]), np.array([other]), draws]
            wts += [np.array([weight * p_true]), np.array([weight * p_wrong]),
                    np.full(draws.size, weight * p_und / draws.size)]
            dec_w, dec_p = dec_w + weight * max(p_true, 1e-12) * own, dec_p + weight * max(p_true, 1e-12)
            und_vals.append(draws)
            und_wts.append(np.full(draws.size, weight * max(p_und, 1e-12) / draws.size))
            noiseless, noiseless_p = noiseless + weight * max(p_und, 1e-12) * flat, noiseless_p + weight * max(p_und, 1e-12)
        v, wt = np.concatenate(vals), np.concatenate(wts)
        finite = np.all(np.isfinite(v[wt > 0]))
        mean = float(np.sum(v * wt) / np.sum(wt)) if finite else math.inf
        median = _weighted_median(v, wt) if np.sum(wt) > 0 else float(v[0])
        uv, uw = np.concatenate(und_vals), np.concatenate(und_wts)
        out[name] = {"decided": dec_w / dec_p, "undecided": _weighted_median(uv, uw), "mean": mean,
                     "median": median, "undecided_noiseless": noiseless / noiseless_p}
    return out


def _other_widths_flipped(m_main, m_alt) -> dict | None:
    """The other condition's widths under the other nuisance set: its covariance widths, W_ad's profile limits
    (where the main set has them) scaled by the ratio of the two sets' Fisher standard errors of ln W_ad at
    the other condition's optimum, as the true condition's are."""
    if m_alt.widths is None or m_main.widths is None or m_alt.J is None or m_main.J is None:
        return m_alt.widths
    wm = m_main.widths["work_of_adhesion"]
    if wm.get("method") != "profile":
        return m_alt.widths
    se_main = log_widths(m_main.J, m_main.values)["work_of_adhesion"]["relative_se"]
    se_alt = log_widths(m_alt.J, m_alt.values)["work_of_adhesion"]["relative_se"]
    if not (se_main > 0 and math.isfinite(se_main) and math.isfinite(se_alt)):
        return m_alt.widths
    scale = se_alt / se_main
    lo, hi = scale * wm["interval"][0], scale * wm["interval"][1]
    v = m_alt.values["work_of_adhesion"]
    return {**m_alt.widths, "work_of_adhesion": {"width": v * (math.exp(hi) - math.exp(lo)), "relative_se":
                                                 (hi - lo) / (2 * Z95), "interval": (lo, hi), "method": "profile"}}


def _hull(v: dict, main: dict):
    """:func:`.hull.hull_model` of one nuisance set's variant (None without the other condition's fit); a set
    whose misfit is the main set's (its verdict not marginal) takes the main set's draws."""
    m, probs = v.get("m"), v.get("probs")
    if m is None or m.J is None or m.widths is None or probs is None:
        return None
    if v is not main and m is main.get("m"):
        return main.get("hull")
    if 1.0 - probs["decided"] - probs["wrong"] < UNDECIDED_MIN:  # hardly ever undecided: the noiseless hull
        return None
    t = v["truth"]
    try:
        return hull_model(v["r"], v["J_force"], t.values, v["widths"], m.r, m.J, m.values, m.widths, m.lam, m.n,
                          m.chisqr_true, t.model.curve.force.size)
    except (np.linalg.LinAlgError, ValueError):
        return None


def _variant(truth, slip, chosen, radius_noise, *, verdict: bool = True, profile: bool = True,
             flip_of: dict | None = None) -> dict:
    """One nuisance set's prediction on the noiseless test ``truth`` (:func:`.truth.noiseless_test`; the
    nuisances are its ``par``).  ``verdict``: fit the other slip condition (its misfit); ``profile``: W_ad's
    width from the fit's profile where the pull-off rows carry its information; ``flip_of``: the other nuisance set's variant on the same curve, whose Jacobian
    gives this one's by the drift's column (:func:`.information.with_drift_flipped`)."""
    if flip_of is not None:
        r = flip_of["r"]
        J_force = with_drift_flipped(truth.model, flip_of["truth"].par, truth.sigma, truth.values, flip_of["J_force"])
        J = J_force
        if radius_noise is not None:
            J = with_drift_flipped(truth.model, flip_of["truth"].par, truth.sigma, truth.values, flip_of["J"])
    else:
        try:
            r, J, _ = jacobian(truth.model, truth.par, truth.sigma, truth.values)
        except ValueError as err:
            raise OutOfDomain(f"the {slip} fit model at the truth: {err}") from None
        J_force = J
        if radius_noise is not None:  # a filmed test: the fit's contact-radius block, in units of its own σ
            J = np.vstack([J, radius_jacobian(truth, radius_noise)])
    widths = log_widths(J, truth.values)
    widths["work_of_adhesion"]["method"] = "fisher"
    if profile and radius_noise is None and chosen == "large-stretch" and _near_pull_off(truth, J, widths):
        # W_ad: the fit's own profile on the noiseless curve (the pull-off term and the clamp at the turning
        # point are not quadratic: :func:`.information.profile_widths_fit`); μh: its Fisher width agrees with
        # its profile to 3 % and costs nothing more
        fisher = widths["work_of_adhesion"]
        try:
            prof = profile_widths_fit(truth.model, truth.par, truth.sigma, truth.values, J, ("work_of_adhesion",))
        except (AdhfitError, ValueError, np.linalg.LinAlgError):
            prof = None
        if prof is not None:
            widths["work_of_adhesion"] = {**prof["work_of_adhesion"], "method": "profile",
                                          "fisher_width": fisher["width"], "fisher_relative_se": fisher["relative_se"]}
    out = {"truth": truth, "J": J, "J_force": J_force, "r": r, "widths": widths}
    if verdict:  # the verdict is the force's alone (a filmed radius only narrows the widths)
        out["m"] = misfit(truth, OTHER[slip], r, J_force)
        out["probs"] = verdict_probabilities(out["m"])
        undecided = 1.0 - out["probs"]["decided"] - out["probs"]["wrong"]
        if profile and radius_noise is None and chosen == "large-stretch" and out["m"].widths is not None \
                and undecided >= UNDECIDED_MIN:
            profile_other(truth, OTHER[slip], out["m"])  # the hull an undecided fit reports: both profiles
    return out


#: the W_ad profile is computed when the rows at the pull-off (its censored term and the last attached row, next
#: to the turning point's clamp) carry this much of the Fisher information: without them the width grows by
#: more than this factor (a deep displacement-control test: 1.01, its profile agrees with the Fisher width to
#: 0.3 %; a shallow one: 17-80; pressure control: 60-200)
PULL_OFF_SHARE = 1.1


def profile_factors(widths: dict) -> tuple | None:
    """W_ad's profile limits over its Fisher half-width 1.96 se (lower, upper; both positive), or None when its
    width is the Fisher one (plan.json ``by_slip``: how far the profile departs from the Fisher interval)."""
    w = widths["work_of_adhesion"]
    if w.get("method") != "profile" or not w.get("fisher_relative_se"):
        return None
    h = Z95 * w["fisher_relative_se"]
    return -w["interval"][0] / h, w["interval"][1] / h


def _near_pull_off(truth, J, widths) -> bool:
    """Whether W_ad's information comes from the rows at the pull-off, where the likelihood is not quadratic."""
    j = truth.model.segments.i_jump
    if truth.model.jump is None or j is None:
        return False
    keep = np.ones(J.shape[0], bool)
    keep[truth.model.curve.force.size] = False  # the pull-off term (after the force rows)
    keep[j - 1] = False
    without = log_widths(J[keep], truth.values)["work_of_adhesion"]["width"]
    return not without <= PULL_OFF_SHARE * widths["work_of_adhesion"]["width"]


def _one_slip(protocol, slip, w, mu, x_max, membrane, radius_noise=None, hint: dict | None = None) -> dict:
    truth = noiseless_test(protocol, slip, w, mu, x_max)
    chosen = membrane
    if membrane == "auto":
        chosen = auto_membrane(truth)
    if chosen != "large-stretch":
        truth = noiseless_test(protocol, slip, w, mu, x_max, membrane=chosen, points=EXACT_POINTS)
    hint = hint or {}
    main = _variant(truth, slip, chosen, radius_noise)
    if hint.get("p_drift") is not None:
        p_drift, drift_method = float(hint["p_drift"]), "interpolated"
    else:
        p_drift, drift_method = drift_probability(truth), "noisy copies"
    has = "force_drift" in truth.par.names
    # the share of replicates whose fit uses the noiseless curve's nuisance set; the other set's prediction
    # where it is not rare.  Its verdict needs its own misfit only where the main one is marginal (else both
    # decide, or neither); its W_ad width is its Fisher width scaled as the main set's profile scales its own
    share = p_drift if has else 1.0 - p_drift
    parts = [(1.0, main)]
    if share < 1.0 - MIXTURE_FLOOR:
        marginal = MIXTURE_FLOOR < main["probs"]["decided"] < 1.0 - MIXTURE_FLOOR
        try:  # the same curve and model, the other nuisance set
            flipped = dataclasses.replace(truth, par=dataclasses.replace(truth.par, fit_force_drift=not has))
            alt = _variant(flipped, slip, chosen, radius_noise, verdict=marginal, profile=False, flip_of=main)
        except OutOfDomain:
            alt = None
        if alt is not None:
            if not marginal:
                alt["m"], alt["probs"] = main["m"], main["probs"]
            wm = main["widths"]["work_of_adhesion"]
            if "fisher_width" in wm and wm["fisher_width"] > 0:
                ratio = wm["width"] / wm["fisher_width"]
                wa = alt["widths"]["work_of_adhesion"]
                # the profile's limits, scaled from the main set's Fisher half-width to this set's
                scale = wa["relative_se"] / wm["fisher_relative_se"]
                alt["widths"]["work_of_adhesion"] = {**wa, "width": wa["width"] * ratio,
                                                     "relative_se": wa["relative_se"] * ratio,
                                                     "interval": tuple(scale * np.asarray(wm["interval"]))}
            if marginal:
                alt["m"].widths = _other_widths_flipped(main["m"], alt["m"])
            parts = [(share, main), (1.0 - share, alt)]
    for _, v in parts:  # the hull an undecided fit reports, under the noise that leaves it undecided
        v["hull"] = _hull(v, main)
    if len(parts) == 1:
        probs = main["probs"]
    else:
        probs = verdict_probabilities([v["m"] for _, v in parts], [wt for wt, _ in parts])
    reported = reported_widths([(wt, v["widths"], v["truth"].values, v["m"], v["probs"], v["hull"])
                                for wt, v in parts])
    widths = {name: dict(main["widths"][name], width=sum(wt * v["widths"][name]["width"] for wt, v in parts))
              for name in main["widths"]}
    m, J = main["m"], main["J"]
    try:
        info = reduced_information(J).tolist()
    except np.linalg.LinAlgError:
        info = None
    return {"widths": widths, "reported": reported, "verdict": probs, "membrane": chosen, "sigma": truth.sigma,
            "information": info, "misfit": m.to_dict(), "p_drift": p_drift, "p_drift_method": drift_method,
            "w_method": main["widths"]["work_of_adhesion"]["method"], "profile_factors": profile_factors(main["widths"]),
            "a_max": truth.a_max, "nuisances": truth.par.names[2:], "n_residuals": int(main["r"].size),
            "other_optimum": m.values}


def predict(protocol: Protocol, slips: tuple, w: float, mu: float, membrane: str = "auto",
            radius_noise: float | None = None, hints: dict | None = None) -> dict:
    """The plan.json entry of one protocol (docs/contracts.md A8) plus the details behind it.

    Parameters
    ----------
    protocol : Protocol
    slips : tuple of str
        The true slip conditions considered.
    w, mu : float
        The guessed W_ad (J/m²) and μh (N/m).
    membrane : {"auto", "large-stretch", "exact"}
    radius_noise : float, optional
        A filmed contact radius with this noise (a fraction of the largest contact radius): its block joins
        the widths' information (the slip verdict stays force-only: a lower bound on its P).
    hints : dict, optional
        slip -> ``{"p_drift": P or None}``: P(drift fitted) interpolated from a map's sub-grid
        (:func:`.api.plan`), used instead of its noisy copies.  ``by_slip`` says
        which method each cell used (``w_ad_width_method``, ``p_drift_method``).
    """
    entry = {"settings": protocol.settings(), "ci95_width": {"work_of_adhesion": None, "mu_h": None},
             "p_slip_decided": {s: None for s in slips}, "p_wrong_slip": {s: None for s in slips},
             "in_domain": False, "membrane": None}
    try:
        if protocol.invalid:
            raise OutOfDomain(protocol.invalid[2])
        x_max = loading_end(protocol, slips[0], w, mu)
        per = {s: _one_slip(protocol, s, w, mu, x_max, membrane, radius_noise, (hints or {}).get(s)) for s in slips}
    except OutOfDomain as err:
        entry["why_not"] = str(err)
        return entry
    entry["in_domain"] = True
    entry["settings"]["control_max"] = x_max
    for name in ("work_of_adhesion", "mu_h"):  # the worse of the true conditions: what the lab can count on
        entry["ci95_width"][name] = max(p["reported"][name]["mean"] for p in per.values())
    for s, p in per.items():
        entry["p_slip_decided"][s] = p["verdict"]["decided"]
        entry["p_wrong_slip"][s] = p["verdict"]["wrong"]
    membranes = {p["membrane"] for p in per.values()}
    entry["membrane"] = "exact" if "exact" in membranes else membranes.pop()
    entry["sigma_force"] = max(p["sigma"] for p in per.values())
    entry["by_slip"] = {s: {"ci95_width": {k: v["mean"] for k, v in p["reported"].items()},
                            "ci95_width_median": {k: v["median"] for k, v in p["reported"].items()},
                            "ci95_width_decided": {k: v["decided"] for k, v in p["reported"].items()},
                            "ci95_width_undecided": {k: v["undecided"] for k, v in p["reported"].items()},
                            "relative_se": {k: v["relative_se"] for k, v in p["widths"].items()},
                            "evidence": p["verdict"]["words"], "delta_bic_median": p["verdict"]["delta_bic"],
                            "delta_bic_90": p["verdict"]["delta_bic_range"], "misfit_chi2": p["verdict"]["misfit"],
                            "sigma_force": p["sigma"], "contact_radius_max": p["a_max"] * protocol.scene.membrane_radius,
                            "nuisances": p["nuisances"], "p_drift_fitted": p["p_drift"], "p_drift_method": p["p_drift_method"],
                            "w_ad_width_method": p["w_method"], "w_ad_profile_factors": p["profile_factors"],
                            "membrane": p["membrane"], "other_optimum": p["other_optimum"],
                            "information": p["information"], "misfit": p["misfit"]}
                        for s, p in per.items()}
    if not all(math.isfinite(v) for v in entry["ci95_width"].values()):
        entry["why_not"] = "the data of this protocol cannot determine W_ad or μh (singular information)"
    return entry
