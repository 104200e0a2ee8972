"""``fit_global``: a test series as one fit (issue 13, docs/contracts.md A7).

One W_ad, one μh and one slip condition for every curve; offsets per curve; each curve its own scene.
Least squares (the procedure and the intervals: :mod:`.global_stage`), or MCMC started from it
(:mod:`.global_mcmc`); either way a :class:`~.result.FitResult` with ``curves``.
"""
from __future__ import annotations

import time

from ..errors import InputError
from .global_stage import joint_stage
from .options import DEFAULT_POINTS
from .result import FitResult

__all__ = ["fit_global"]


def fit_global(curves, scenes, *, slip: str = "auto", method: str = "lsq", sigma: float | None = None,
               sigma_contact_radius: float | None = None, contact_radius: bool = True,
               fit_x_offset: bool | None = None, fit_force_offset: bool = True, seed: int | None = None,
               points: int = DEFAULT_POINTS, profile: bool = True, mcmc: dict | None = None) -> FitResult:
    """Fit one W_ad, one μh and one slip condition to a series of curves (offsets per curve).

    Parameters
    ----------
    curves : list of path or adhfit.data.Curve
        Two or more measured curves (CSV, docs/contracts.md A4).
    scenes : path, Scene, or a list of them (one per curve)
        Each curve's scene: geometry and its own fixed pressure or gap.
    slip : {"auto", "no-slip", "frictionless"}
        ``"auto"`` fits both and compares them on the joint fit.
    method : {"lsq", "mcmc"}
        Least squares, or the posterior sampled by MCMC (:func:`.global_mcmc.fit_global_mcmc`).
    sigma : float, optional
        Force noise, N, for every curve; default: estimated per curve.
    sigma_contact_radius : float, optional
        Contact-radius noise, m, for every curve; default: estimated per curve.
    contact_radius : bool
        Fit the ``contact_radius`` column where a curve has one.
    fit_x_offset, fit_force_offset : bool
        As in :func:`~.fit.fit_curve`, per curve.
    seed : int, optional
        Recorded (least squares); the root seed of every random number (MCMC).
    points : int
        Rows per computed history.
    profile : bool
        Profile-likelihood intervals of the shared W_ad and μh of the reported slip condition (least squares).
    mcmc : dict, optional
        With ``method="mcmc"``: ``outdir``, ``workers``, ``progress`` and sampler settings
        (:data:`.global_mcmc.DEFAULTS`).

    Returns
    -------
    FitResult
        With ``curves`` (one entry per curve: offsets, reduced χ², pull on the shared values, ...).
    """
    from .series_checks import assemble  # noqa: PLC0415
    t0 = time.perf_counter()
    if method not in ("lsq", "mcmc"):
        raise InputError("method", method, "'lsq' or 'mcmc'")
    if method == "mcmc":
        from .global_mcmc import fit_global_mcmc  # noqa: PLC0415
        return fit_global_mcmc(curves, scenes, slip=slip, sigma=sigma, sigma_contact_radius=sigma_contact_radius,
                               contact_radius=contact_radius, fit_x_offset=fit_x_offset,
                               fit_force_offset=fit_force_offset, seed=seed, points=points, **(mcmc or {}))
    stage = joint_stage(curves, scenes, slip=slip, sigma=sigma, sigma_contact_radius=sigma_contact_radius,
                        contact_radius=contact_radius, fit_x_offset=fit_x_offset,
                        fit_force_offset=fit_force_offset, points=points, profile=profile)
    return assemble(stage.curves, stage.scenes, stage.joint, stage.fits, stage.verdict, stage.singles,
                    options=stage.options, seed=seed, t0=t0)
