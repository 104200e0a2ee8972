"""``adhfit.fit``: the one entry point of every fit, whatever the method and however many curves.

One curve goes to :func:`.fit.fit_curve` (least squares, or MCMC started from it); a sequence of
curves of one membrane is one global fit (:func:`.global_fit.fit_global`: shared W_ad, μh and slip
condition).  Every path returns the same frozen :class:`~.result.FitResult`; an MCMC fit carries its
run in ``sampling``, a series its curves in ``curves``.
"""
from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

from .result import FitResult

__all__ = ["fit"]


def fit(data: Any, scene: Any, *, method: str = "lsq", **options: Any) -> FitResult:
    """Fit the work of adhesion W_ad, the stiffness μh and the slip condition.

    Parameters
    ----------
    data : path, adhfit.data.Curve, or a sequence of them
        One measured curve (docs/contracts.md A4), or the curves of a test series (A7).
    scene : path, adhfit.scene.Scene, or a sequence of them
        The scene (A3); for a series one per curve, or one for all.
    method : {"lsq", "mcmc"}
        Least squares (lmfit) or posterior sampling (emcee, started from the least-squares fits).
    **options
        One curve: the keywords of :func:`adhfit.fitting.fit.fit_curve` (``slip``, ``sigma``,
        ``fit_x_offset``, ``fit_force_offset``, ``seed``, ``points``, ``profile``, ``membrane``,
        ``read_options``; with MCMC also ``outdir``, ``workers``, ``progress`` and sampler settings).
        A series: those of :func:`adhfit.fitting.global_fit.fit_global` (``sigma_contact_radius``,
        ``contact_radius``, ...).

    Returns
    -------
    FitResult

    Examples
    --------
    >>> import adhfit
    >>> r = adhfit.fit("curve.csv", "scene.toml")                      # doctest: +SKIP
    >>> r = adhfit.fit("curve.csv", "scene.toml", method="mcmc", seed=1)  # doctest: +SKIP
    >>> r = adhfit.fit(["p1.csv", "p2.csv", "p3.csv"], ["p1.toml", "p2.toml", "p3.toml"])  # doctest: +SKIP
    """
    if isinstance(data, Sequence) and not isinstance(data, (str, bytes, Path)):
        from .global_fit import fit_global  # noqa: PLC0415
        return fit_global(list(data), scene, method=method, **options)
    from .fit import fit_curve  # noqa: PLC0415
    return fit_curve(data, scene, method=method, **options)
