"""One protocol's prediction: interval widths, slip-verdict probabilities, domain and membrane model.

For each true slip condition the noiseless curve (:mod:`.truth`) gives the Fisher widths
(:mod:`.information`) and the other condition's misfit (:mod:`.verdict`).  The membrane model is the
scene's; under ``auto`` it is the one the fit would choose at the truth (the fit's own rule,
:func:`adhfit.fitting.membrane.approximation_effect`: the exact membrane when the large-stretch
force is off by more than half σ at some row, or shifts W_ad or μh by more than half a standard error),
and the prediction is then made with that membrane's model.
"""
from __future__ import annotations

import math

import numpy as np

from ..errors import AdhfitError
from ..fitting.lsq import COARSE_TOL, RawFit, minimise, residual_function
from ..fitting.membrane import EXACT_POINTS, approximation_effect
from ..fitting.starts import Start
from .information import Z95, jacobian, log_widths, radius_jacobian, reduced_information
from .protocols import Protocol
from .truth import OutOfDomain, loading_end, noiseless_test
from .verdict import misfit, verdict_probabilities

__all__ = ["predict", "auto_membrane", "OTHER"]

OTHER = {"no-slip": "frictionless", "frictionless": "no-slip"}


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


def _interval(value: float, rel_se: float) -> tuple[float, float]:
    return value * math.exp(-Z95 * rel_se), value * math.exp(Z95 * rel_se)


def reported_widths(widths: dict, truth: dict, m, probs: dict) -> dict:
    """The width the fit reports, as a distribution over its verdict (:func:`adhfit.fitting.stage.reported`):
    the true condition's interval when it is selected, the other's when that is, and otherwise the hull of
    both (the two optima differ, so an undecided verdict widens the interval).

    Returns, per parameter, ``decided``, ``undecided`` (the hull), ``mean`` (over the verdict's
    probabilities: the expected width) and ``median`` widths (SI).
    """
    p_true, p_wrong = probs["decided"], probs["wrong"]
    p_und = max(1.0 - p_true - p_wrong, 0.0)
    out = {}
    for name, w in widths.items():
        own = w["width"]
        if m.widths is None or not math.isfinite(own):
            out[name] = {"decided": own, "undecided": own, "mean": own, "median": own}
            continue
        other = m.widths[name]["width"]
        lo_t, hi_t = _interval(truth[name], w["relative_se"])
        lo_w, hi_w = _interval(m.values[name], m.widths[name]["relative_se"])
        hull = max(hi_t, hi_w) - min(lo_t, lo_w)
        points = sorted([(own, p_true), (other, p_wrong), (hull, p_und)])
        cum, median = 0.0, points[-1][0]
        for value, p in points:
            cum += p
            if cum >= 0.5:
                median = value
                break
        out[name] = {"decided": own, "undecided": hull, "mean": p_true * own + p_wrong * other + p_und * hull,
                     "median": median}
    return out


def _one_slip(protocol, slip, w, mu, x_max, membrane, radius_noise=None) -> dict:
    truth = noiseless_test(protocol, slip, w, mu, x_max)
    chosen = membrane
    if membrane == "auto":
        chosen = auto_membrane(truth)
    if chosen != "large-stretch":
        truth = noiseless_test(protocol, slip, w, mu, x_max, membrane=chosen, points=EXACT_POINTS)
    try:
        r, J, _ = jacobian(truth.model, truth.par, truth.sigma, truth.values)
    except ValueError as err:
        raise OutOfDomain(f"the {slip} fit model at the truth: {err}") from None
    if radius_noise is not None:  # a filmed test: the fit's contact-radius block, in units of its own σ
        J = np.vstack([J, radius_jacobian(truth, radius_noise)])
    widths = log_widths(J, truth.values)
    m = misfit(truth, OTHER[slip], r, J)
    probs = verdict_probabilities(m)
    reported = reported_widths(widths, truth.values, m, probs)
    try:
        info = reduced_information(J).tolist()
    except np.linalg.LinAlgError:
        info = None
    return {"widths": widths, "reported": reported, "verdict": probs, "membrane": chosen, "sigma": truth.sigma, "information": info,
            "misfit": m.to_dict(),
            "a_max": truth.a_max, "nuisances": truth.par.names[2:], "n_residuals": int(r.size),
            "other_optimum": m.values}


def predict(protocol: Protocol, slips: tuple, w: float, mu: float, membrane: str = "auto",
            radius_noise: float | None = None) -> dict:
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
    """
    entry = {"settings": protocol.settings(), "ci95_width": {"work_of_adhesion": None, "mu_h": None},
             "p_slip_decided": {s: None for s in slips}, "p_wrong_slip": {s: None for s in slips},
             "in_domain": False, "membrane": None}
    try:
        if protocol.invalid:
            raise OutOfDomain(protocol.invalid[2])
        x_max = loading_end(protocol, slips[0], w, mu)
        per = {s: _one_slip(protocol, s, w, mu, x_max, membrane, radius_noise) for s in slips}
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
                            "nuisances": p["nuisances"], "membrane": p["membrane"],
                            "information": p["information"], "misfit": p["misfit"]}
                        for s, p in per.items()}
    if not all(math.isfinite(v) for v in entry["ci95_width"].values()):
        entry["why_not"] = "the data of this protocol cannot determine W_ad or μh (singular information)"
    return entry
