"""``adhfit.fit``: the one entry point of every fit, whatever the method and however many curves.

A curve is a series of one.  :func:`fit` reads and checks the curves and scenes once (:class:`Problem`),
runs the least-squares stage (:func:`.stage.least_squares`: each slip condition's objective, the
membrane model, the slip verdict, intervals) and, with ``method="mcmc"``, samples the posterior from
there (:func:`.sampling.sample`).  Every path returns the same frozen :class:`~.result.FitResult`; an
MCMC fit carries its run in ``sampling``, a series its curves in ``curves``.
"""
from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ..errors import InputError
from .options import FitOptions
from .result import FitResult

__all__ = ["fit", "Problem", "read_problem"]


@dataclass
class Problem:
    """What is fitted: the curves (SI, checked), their scenes, and the choices that follow from them.

    Attributes
    ----------
    curves, scenes : list
        One scene per curve.
    labels : list of str
        Each curve's file (or a name).
    checks : list of str
        Warnings of the input checks (repeated rows left out, a zero that moved, ...).
    slip, membrane : str
        The slip choice (``auto`` or one condition) and the membrane choice.
    observables : tuple of str
        ``force`` and every secondary observable fitted.
    sigmas : dict
        Observable name -> given noise σ (SI).
    series : bool
        More than one curve (report.json ``curves``).
    """

    curves: list
    scenes: list
    labels: list
    checks: list
    slip: str
    membrane: str
    observables: tuple
    sigmas: dict
    series: bool


def _one(values: set, given: str | None) -> str:
    return given if given is not None else (values.pop() if len(values) == 1 else "auto")


def read_problem(data: Any, scene: Any, opts: FitOptions) -> Problem:
    """Read and check the curves and scenes (paths or objects) of a fit."""
    from ..data import read_curve  # noqa: PLC0415
    from ..scene import Scene, load_scene  # noqa: PLC0415
    from .observables import OBSERVABLES, PRIMARY  # noqa: PLC0415
    from .plausibility import check_curve  # noqa: PLC0415
    from .segments import thin  # noqa: PLC0415
    many = isinstance(data, Sequence) and not isinstance(data, (str, bytes, Path))
    datas = list(data) if many else [data]
    if not datas:
        raise InputError("curves", 0, "one curve or more")
    scenes = list(scene) if isinstance(scene, (list, tuple)) else [scene] * len(datas)
    if len(scenes) != len(datas):
        raise InputError("scenes", len(scenes), f"one scene, or one per curve ({len(datas)})")
    scenes = [s if isinstance(s, Scene) else load_scene(s) for s in scenes]
    curves, checks = [], []
    for d, sc in zip(datas, scenes):
        c = read_curve(d, sc.control, **opts.read_options) if isinstance(d, (str, Path)) else d
        if c.control != sc.control:
            raise InputError("control", c.control, f"'{sc.control}' (the scene's control mode)")
        c, notes = check_curve(c, sc)  # repeated rows left out; absurd data raise here
        c, thinned = thin(c) if opts.thin else (c, None)  # a dense log: bins of consecutive rows (said)
        prefix = f"{c.path}: " if len(datas) > 1 else ""
        checks += [prefix + n for n in notes + ([thinned] if thinned else [])]
        curves.append(c)
    if len({sc.control for sc in scenes}) > 1 and opts.fit_x_offset is not None:
        raise InputError("fit_x_offset", opts.fit_x_offset, "None (the default of each control mode) when the "
                         "curves mix displacement and pressure control")
    sigmas = {PRIMARY: opts.sigma}
    observables = [PRIMARY]
    for name, obs in OBSERVABLES.items():
        if name == "contact_radius" and not opts.contact_radius:
            continue
        if any(obs.rows(c) is not None for c in curves):
            observables.append(name)
            sigmas[name] = opts.sigma_contact_radius if name == "contact_radius" else None
    return Problem(curves=curves, scenes=scenes, labels=[str(c.path) for c in curves], checks=checks,
                   slip=_one({sc.slip for sc in scenes}, opts.slip),
                   membrane=_one({sc.membrane_model for sc in scenes}, opts.membrane),
                   observables=tuple(observables), sigmas=sigmas, series=len(curves) > 1)


def fit(data: Any, scene: Any, *, method: str = "lsq", **options: Any) -> FitResult:
    """Fit the work of adhesion W_ad, the stiffness μh and the slip condition.

    Parameters
    ----------
    data : path, adhfit.data.Curve, or a sequence of them
        One measured curve (docs/contracts.md A4), or the curves of a test series (A7: one W_ad, one μh
        and one slip condition for all, offsets and noise levels per curve).
    scene : path, adhfit.scene.Scene, or a sequence of them
        The scene (A3); for a series one per curve, or one for all.
    method : {"lsq", "mcmc"}
        Least squares (lmfit), or posterior sampling (emcee, started from the least-squares fits).
    **options
        The fields of :class:`~.options.FitOptions` (``slip``, ``membrane``, ``sigma``,
        ``sigma_contact_radius``, ``contact_radius``, ``fit_x_offset``, ``fit_force_offset``, ``seed``,
        ``points``, ``profile``, ``thin``, ``read_options``; MCMC: ``outdir``, ``workers``, ``progress``,
        ``stand_in``), and the
        MCMC settings (``n_walkers``, ``max_steps``, ...: flat, or as ``mcmc={...}``).  The same for one
        curve or many.

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
    import time  # noqa: PLC0415
    t0 = time.perf_counter()
    opts = FitOptions.from_keywords(method, **options)
    problem = read_problem(data, scene, opts)
    from .stage import least_squares  # noqa: PLC0415
    stage = least_squares(problem, opts, profile=opts.profile and opts.method == "lsq")
    if opts.method == "mcmc":
        from .bayes.sampling import sample  # noqa: PLC0415 - emcee loads only for MCMC
        return sample(problem, stage, opts, t0)
    from .stage import assemble  # noqa: PLC0415
    return assemble(problem, stage, opts, t0)
