"""Expected interval widths from the Fisher information of the fit's own likelihood.

The fit minimises the residual vector of :func:`adhfit.fitting.lsq.residual_function`: (F_measured -
F_model)/σ at every row plus the pull-off term, over its internal parameters (ln W_ad, ln μh, the
control offset, the load-cell zero and its drift, :class:`~adhfit.fitting.lsq.Parametrisation`).  With
Gaussian noise of level σ, the Fisher information of those parameters is J^T J, J the Jacobian of that
vector at the noiseless truth; its inverse is the expected covariance, nuisances included (the
marginal variance of ln W_ad is the (0, 0) element of the inverse, which is what profiling the
nuisances out gives).  The reported 95 % interval of a log-parametrised value v is
v·exp(±1.96 se): its expected width is v·(e^{1.96 se} - e^{-1.96 se}).

**The pull-off term** is not a Gaussian residual: it is sqrt(-2 ln P), P the probability that the model's
turning point x_tp lies in the gap between the last attached and the first detached row
(:func:`adhfit.fitting.lsq.pull_off_term`), nearly flat inside the gap and rising outside.  Its
derivative at the truth depends on where in the gap the truth happens to fall, and says nothing about
what the fit's likelihood profile does, which is where -2 ln P has risen by 3.84 above its least value.
Its row of the Jacobian is therefore replaced by the quadratic with that same rise: sqrt(k)·(dx_tp/dθ)/s,
s the gap's soft edge and k = 3.84/t*², t* (in units of s) the distance from the middle of the gap at
which -2 ln P has risen by 3.84.  Under pressure control this term carries most of what the data say
about W_ad (the pull-off pressure); without it the predicted W_ad interval was 15x too wide.
"""
from __future__ import annotations

import math

import numpy as np

from scipy import optimize

from ..fitting.lsq import pull_off_term, residual_function
from ..fitting.objective import Values
from ..fitting.starts import Start

__all__ = ["internal", "residual_at", "jacobian", "radius_jacobian", "log_widths", "reduced_information", "widths_from_information",
           "pull_off_curvature", "pull_off_slopes", "with_drift_flipped", "profile_widths_fit", "Z95", "STEP"]

#: two-sided 95 % normal quantile
Z95 = 1.959963984540054
#: central-difference step of the internal parameters (ln W_ad, ln μh and the offsets over their scales
#: are O(1)); the history's solver noise is ~1e-12 of the force, so the truncation error (step², ~1e-8)
#: dominates and is negligible
STEP = 1e-4


def internal(par, values: dict) -> tuple[list[str], np.ndarray]:
    """The internal parameter names and values (:meth:`Parametrisation.params`) at SI ``values``."""
    p = par.params(Start(values))
    names = list(p.keys())
    return names, np.array([p[n].value for n in names], float)


def residual_at(model, par, sigma: float):
    """theta (internal, in the order of :func:`internal`) -> the fit's residual vector in units of σ."""
    res = residual_function(model, par, sigma, sigma)

    def at(names: list[str], theta: np.ndarray) -> np.ndarray:
        return np.asarray(res(Values(zip(names, map(float, theta)))), float)
    return at


def pull_off_curvature(gap: tuple[float, float, float]) -> float:
    """k = 3.84/t*² of the module docstring for a pull-off gap ``(x_attached, x_detached, soft)``."""
    lo, hi = sorted(gap[:2])
    s = gap[2]
    mid = 0.5 * (lo + hi)

    def rise(t: float) -> float:
        return pull_off_term(gap, mid + t * s) ** 2 - pull_off_term(gap, mid) ** 2 - Z95 ** 2
    t_star = optimize.brentq(rise, 1e-9, 1e3)
    return Z95 ** 2 / t_star ** 2


def pull_off_slopes(gap: tuple[float, float, float], n: int = 21) -> np.ndarray:
    """|d√(−2 ln P)/dt| at ``n`` turning points evenly across the gap (t in units of the soft edge s): the
    pull-off row the fit's covariance sees, which depends on where in the gap its optimum falls."""
    lo, hi = sorted(gap[:2])
    s = gap[2]
    h = 1e-4 * s
    return np.array([abs(pull_off_term(gap, x + h) - pull_off_term(gap, x - h)) / (2 * h / s)
                     for x in np.linspace(lo, hi, n)])


def _turning_point(model, par, names: list[str], theta: np.ndarray) -> float:
    si = par.si(Values(zip(names, map(float, theta))))
    return model.turning_point(si["work_of_adhesion"], si["mu_h"], si["x_offset"])[0]


def jacobian(model, par, sigma: float, values: dict, *, raw_pull_off: bool = False
             ) -> tuple[np.ndarray, np.ndarray, list[str]]:
    """(residual, Jacobian, internal names) of the fit's residual at SI ``values`` (central differences).

    The pull-off row is the quadratic of the profile's 3.84 rise (module docstring); with ``raw_pull_off`` it is
    (∂x_tp/∂θ)/s, to be scaled by the residual's own slope where the turning point falls
    (:func:`pull_off_slopes`): what the fit's covariance sees (it reports a covariance interval for the slip
    condition it does not favour).

    Raises
    ------
    ValueError
        A step leaves the model's domain (the residual is the fit's penalty there).
    """
    from ..fitting.lsq import PENALTY  # noqa: PLC0415
    names, theta = internal(par, values)
    at = residual_at(model, par, sigma)
    r0 = at(names, theta)
    cols = []
    for i in range(theta.size):
        up, down = theta.copy(), theta.copy()
        up[i] += STEP
        down[i] -= STEP
        ru, rd = at(names, up), at(names, down)
        if np.all(ru == PENALTY) or np.all(rd == PENALTY) or np.all(r0 == PENALTY):
            raise ValueError(f"a step of {names[i]} leaves the model's domain")
        cols.append((ru - rd) / (2.0 * STEP))
    J = np.column_stack(cols)
    gap = model.jump
    if gap is not None:  # the pull-off row: the quadratic of the profile's 3.84 rise (module docstring)
        k = 1.0 if raw_pull_off else pull_off_curvature(gap)
        g = []
        for i in range(theta.size):
            up, down = theta.copy(), theta.copy()
            up[i] += STEP
            down[i] -= STEP
            g.append((_turning_point(model, par, names, up) - _turning_point(model, par, names, down)) / (2 * STEP))
        J[-1] = math.sqrt(k) * np.array(g) / gap[2]
    return r0, J, names


def with_drift_flipped(model, par, sigma: float, values: dict, J: np.ndarray) -> np.ndarray:
    """:func:`jacobian` of the same residual with the load-cell drift's column added (``par`` without it) or
    dropped (``par`` with it), from ``J`` of ``par``: at the truth the drift is 0, so the residual and the
    other columns are the same, and the pull-off row's drift entry is 0 (the turning point does not depend on
    the load cell).  Only an added column costs two residual evaluations.  ``J`` may carry rows of a filmed
    radius below the force residual's (their drift entries are 0 too)."""
    import dataclasses  # noqa: PLC0415
    if par.fit_force_drift:  # the drift is the last parameter (Parametrisation.names)
        return J[:, :-1].copy()
    flipped = dataclasses.replace(par, fit_force_drift=True)
    names, theta = internal(flipped, values)
    at = residual_at(model, flipped, sigma)
    up, down = theta.copy(), theta.copy()
    up[-1] += STEP
    down[-1] -= STEP
    col = np.zeros(J.shape[0])
    ru, rd = at(names, up), at(names, down)
    col[: ru.size] = (ru - rd) / (2.0 * STEP)
    if model.jump is not None:
        col[ru.size - 1] = 0.0
    return np.column_stack([J, col])


def log_widths(J: np.ndarray, values: dict) -> dict:
    """Expected 95 % widths (SI) and relative standard errors of W_ad and μh from a Jacobian whose first two
    columns are ln W_ad and ln μh; ``inf`` where the information is singular."""
    info = J.T @ J
    try:
        cov = np.linalg.inv(info)
        ok = np.all(np.isfinite(cov)) and np.linalg.cond(info) < 1e14
    except np.linalg.LinAlgError:
        ok = False
    out = {}
    for i, name in enumerate(("work_of_adhesion", "mu_h")):
        se = math.sqrt(cov[i, i]) if ok and cov[i, i] > 0 else math.inf
        v = values[name]
        width = v * (math.exp(min(Z95 * se, 700)) - math.exp(-Z95 * se)) if math.isfinite(se) else math.inf
        out[name] = {"width": width, "relative_se": se}
    return out


def reduced_information(J: np.ndarray) -> np.ndarray:
    """The 2x2 information about (ln W_ad, ln μh) with the nuisances (the other columns) profiled out:
    I_aa − I_ab I_bb⁻¹ I_ba (a test series adds these over its curves, each with its own nuisances)."""
    info = J.T @ J
    a, b = info[:2, :2], info[:2, 2:]
    if info.shape[0] == 2:
        return a
    return a - b @ np.linalg.solve(info[2:, 2:], b.T)


def widths_from_information(info: np.ndarray, values: dict) -> dict:
    """:func:`log_widths` from a 2x2 information matrix about (ln W_ad, ln μh)."""
    try:
        cov = np.linalg.inv(info)
    except np.linalg.LinAlgError:
        cov = np.full((2, 2), np.inf)
    out = {}
    for i, name in enumerate(("work_of_adhesion", "mu_h")):
        se = math.sqrt(cov[i, i]) if np.isfinite(cov[i, i]) and cov[i, i] > 0 else math.inf
        v = values[name]
        out[name] = {"width": v * (math.exp(min(Z95 * se, 700)) - math.exp(-Z95 * se)) if math.isfinite(se) else math.inf,
                     "relative_se": se}
    return out


def radius_jacobian(truth, radius_noise: float) -> np.ndarray:
    """Jacobian rows of a filmed contact radius (the fit's second observable,
    :data:`adhfit.fitting.observables.OBSERVABLES`): (a_measured − a_model)/σ_a at every row in contact,
    σ_a = ``radius_noise`` × the largest contact radius; the columns of the force offsets are 0."""
    from ..fitting.observables import contact_radius_model  # noqa: PLC0415
    model, par = truth.model, truth.par
    names, theta = internal(par, truth.values)

    def radius(th):
        si = par.si(Values(zip(names, map(float, th))))
        return contact_radius_model(model, si["work_of_adhesion"], si["mu_h"], si["x_offset"])
    a0 = radius(theta)
    sigma_a = radius_noise * float(np.max(a0))
    rows = a0 > 0
    cols = []
    for i in range(theta.size):
        up, down = theta.copy(), theta.copy()
        up[i] += STEP
        down[i] -= STEP
        cols.append((radius(up) - radius(down))[rows] / (2.0 * STEP * sigma_a))
    return np.column_stack(cols)


def profile_widths_fit(model, par, sigma: float, values: dict, J: np.ndarray | None = None,
                       names: tuple = ("work_of_adhesion", "mu_h")) -> dict | None:
    """Expected 95 % widths of W_ad and μh from the fit's own likelihood profile on the noiseless curve.

    The fit's χ² with σ given, on the noiseless curve, is the expected χ² surface of a noisy replicate (up to
    the constant n − k): its profile interval (:func:`adhfit.fitting.profile.profile_interval`, the fit's own
    code) is the interval a replicate reports, typically.  Unlike the Fisher information it follows the two
    places where the fit's likelihood is not quadratic near pull-off: the censored pull-off term
    (:func:`adhfit.fitting.lsq.pull_off_term`) and the attached rows next to the turning point, whose force
    has an infinite slope there and is clamped beyond it (:class:`adhfit.fitting.model.CurveModel`): once
    the model's turning point passes the last attached row, that row's residual jumps.  In a shallow
    displacement-control test these make the W_ad profile asymmetric and 1.6x narrower than the Fisher
    information says; the noisy replicates' median agrees with this profile (docs/planning.md).

    ``J``: the Fisher Jacobian (:func:`jacobian`), whose covariance places the profile's first probes.
    ``names``: the parameters profiled.

    Returns :func:`log_widths`' dict plus ``interval`` (ln limits relative to the truth); ``None`` when the
    profile does not close (a side open or a sub-fit outside the model's domain): the caller keeps the
    Fisher widths then.
    """
    from types import SimpleNamespace  # noqa: PLC0415

    from ..fitting.profile import profile_interval  # noqa: PLC0415
    res = residual_function(model, par, sigma, sigma)
    params = par.params(Start(values))
    order = [k for k, p in params.items() if p.vary]
    r0 = np.asarray(res(params), float)
    cov = None
    if J is not None and order == internal(par, values)[0]:
        try:
            cov = np.linalg.inv(J.T @ J)
        except np.linalg.LinAlgError:
            cov = None
    # the optimum of the noiseless curve is the truth (up to the pull-off term's small constant, ~1e-3 of χ²
    # off): no least squares.  The profile's first probes and the other parameters' warm starts come from the
    # covariance, as the fit has one (the Fisher covariance of ``J``): the sub-fits are capped at 200
    # evaluations, and without a warm start they stop short and the interval comes out too narrow
    best = SimpleNamespace(params=params, var_names=order, chisqr=float(r0 @ r0), ndata=int(r0.size),
                           nvarys=len(order), covar=cov)
    out = {}
    for name in names:
        key = "ln_" + name
        lo, hi = profile_interval(res, best, key, sigma_given=True)
        # the limits as the fit takes them (adhfit.fitting.intervals.from_profile): the bracketed limit, or
        # the nearest probe beyond it where the χ² jumps (the clamp at the turning point)
        if lo.open or hi.open or lo.bound is None or hi.bound is None:
            return None
        a, b = lo.bound, hi.bound
        t0 = math.log(values[name])
        out[name] = {"width": math.exp(b) - math.exp(a), "relative_se": (b - a) / (2 * Z95),
                     "interval": (a - t0, b - t0)}
    return out
