"""``adhfit fit FILE ... --global`` (docs/contracts.md A7): one fit of a test series.

Thin: find the curves and each one's scene (``--scene``, else the nearest ``scene.toml``, as in a
batch), call :func:`adhfit.fit` on them (``--method lsq`` or ``mcmc``), write the reports with
:func:`adhfit.report.write` (``report.json`` with ``curves``, ``report.md``, ``report.html`` and
``fit.png``: every curve with the shared fit and its residuals; MCMC: also ``chain.h5``), print a
short summary.
"""
from __future__ import annotations

from pathlib import Path

from ..errors import InputError

__all__ = ["run_global"]


def _jobs(args):
    from . import batch  # noqa: PLC0415
    data = [Path(p) for p in (args.data if isinstance(args.data, list) else [args.data])]
    if args.scene is not None and not Path(args.scene).is_file():
        raise InputError("--scene", str(args.scene), "an existing scene file (TOML)")
    jobs = batch.discover(data, scene=args.scene, outdir=args.output)
    for job in jobs:
        if job.scene is None:
            raise InputError("scene", str(job.data), f"a scene file for every curve ({job.scene_note})")
    if len(jobs) < 2:
        raise InputError("DATA", " ".join(map(str, data)), "two or more curves for --global")
    return jobs


def run_global(args) -> int:
    """Run ``adhfit fit ... --global`` from parsed arguments; returns the exit status."""
    from ..data import read_curve  # noqa: PLC0415
    from ..fitting.api import fit  # noqa: PLC0415
    from ..report import write  # noqa: PLC0415
    from ..scene import load_scene  # noqa: PLC0415
    from ..units import parse_quantity  # noqa: PLC0415
    from .arguments import fit_force_offset, fit_x_offset, read_options  # noqa: PLC0415
    from .writing import check_output_dir, exit_status  # noqa: PLC0415
    out = check_output_dir(args.output if args.output is not None else Path("adhfit_global_fit"))
    jobs = _jobs(args)
    scenes = [load_scene(j.scene) for j in jobs]
    from .reading import reading  # noqa: PLC0415
    curves = []
    for j, sc in zip(jobs, scenes):
        with reading(j.data, quiet=getattr(args, "quiet", False)):
            curves.append(read_curve(j.data, sc.control, **read_options(args)))
    sigma = None if args.sigma is None else parse_quantity(args.sigma, "force", name="--sigma")
    sigma_a = None if getattr(args, "sigma_radius", None) is None else \
        parse_quantity(args.sigma_radius, "length", name="--sigma-radius")
    controls = {sc.control for sc in scenes}
    fit_x = fit_x_offset(args, scenes[0].control) if len(controls) == 1 else None
    slips = {sc.slip for sc in scenes}
    slip = args.slip or (slips.pop() if len(slips) == 1 else "auto")
    by_method = ({"outdir": out, "progress": False if getattr(args, "quiet", False) else None}
                 if args.method == "mcmc" else {"profile": not args.no_profile})
    result = fit(curves, scenes, method=args.method, slip=slip, sigma=sigma, sigma_contact_radius=sigma_a,
                 contact_radius=not getattr(args, "no_contact_radius", False), fit_x_offset=fit_x,
                 fit_force_offset=fit_force_offset(args), seed=args.seed, points=args.points,
                 membrane=getattr(args, "membrane", None), **by_method)
    write(result, out, plot=not args.no_plot)
    print(_summary(result, out))
    return exit_status(result)


def _summary(result, out: Path) -> str:
    from .writing import estimate_line  # noqa: PLC0415
    lines = [f"global {result.method} fit of {len(result.curves)} curves; slip: {result.slip['verdict']}"]
    if result.method == "mcmc":
        probs = ", ".join(f"P({k}) = {v:.3g}" for k, v in result.mcmc["model_probabilities"]["probabilities"].items())
        lines.append(f"MCMC {'converged' if result.converged else 'NOT CONVERGED (see report.html)'}; {probs}; "
                     f"seed {result.mcmc['seed']}; chains in chain.h5")
    for name, e in result.parameters.items():
        lines.append(estimate_line(name, e))
    lines.append(f"observables: {', '.join(result.observables)}; {len(result.warnings)} warning(s); "
                 f"{result.wall_time:.1f} s; wrote {out}/report.json, report.md, report.html"
                 + (", fit.png" if (out / "fit.png").exists() else ""))
    return "\n".join(lines)
