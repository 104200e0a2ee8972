"""``adhfit fit FILE ... --global`` (docs/contracts.md A7): one fit of a test series.

Thin: find the curves and each one's scene (``--scene``, else the nearest ``scene.toml``, as in a
batch), call :func:`~.global_fit.fit_global` (``--method lsq`` or ``mcmc``), write ``report.json``
(A5/A5b plus ``curves``), ``report.md``, ``report.html`` and ``fit.png`` (every curve with the shared fit
and its residuals; MCMC: also ``chain.h5``) into the output directory, print a short summary.
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
    from ..report.json_report import write_json  # noqa: PLC0415
    from ..scene import load_scene  # noqa: PLC0415
    from ..units import parse_quantity  # noqa: PLC0415
    from .cli_support import _x_offset, check_output_dir, read_options  # noqa: PLC0415
    from .global_fit import fit_global  # noqa: PLC0415
    out = check_output_dir(args.output if args.output is not None else Path("adhfit_global_fit"))
    jobs = _jobs(args)
    scenes = [load_scene(j.scene) for j in jobs]
    curves = [read_curve(j.data, sc.control, **read_options(args)) for j, sc in zip(jobs, scenes)]
    sigma = None if args.sigma is None else parse_quantity(args.sigma, "force", name="--sigma")
    sigma_a = None if getattr(args, "sigma_radius", None) is None else \
        parse_quantity(args.sigma_radius, "length", name="--sigma-radius")
    controls = {sc.control for sc in scenes}
    fit_x = _x_offset(args, scenes[0].control) if len(controls) == 1 else None
    slips = {sc.slip for sc in scenes}
    slip = args.slip or (slips.pop() if len(slips) == 1 else "auto")
    out.mkdir(parents=True, exist_ok=True)  # an MCMC fit writes its chains while sampling
    mcmc = {"outdir": out, "progress": False if getattr(args, "quiet", False) else None}
    result = fit_global(curves, scenes, method=args.method, slip=slip, sigma=sigma, sigma_contact_radius=sigma_a,
                        contact_radius=not getattr(args, "no_contact_radius", False), fit_x_offset=fit_x,
                        fit_force_offset=True, seed=args.seed, points=args.points, profile=not args.no_profile,
                        mcmc=mcmc if args.method == "mcmc" else None)
    write_json(result, out / "report.json")
    write_series_reports(result, out, plot=not args.no_plot)
    print(_summary(result, out))
    return 0


_CAPTION = ("Every curve (dots) with the shared fit (lines); below, each curve's residuals in units of its own "
            "noise σ (dashed: ±3), and the contact radius when it was fitted")


def write_series_reports(result, out: Path, *, plot: bool = True) -> None:
    """report.md, fit.png (``plot``) and report.html (the figure embedded) of a global fit into ``out``."""
    import json  # noqa: PLC0415

    from ..report.series_html import write_series_html  # noqa: PLC0415
    from ..report.series_markdown import write_series_markdown  # noqa: PLC0415
    d = json.loads((out / "report.json").read_text(encoding="utf-8"))  # exactly what report.json says
    write_series_markdown(d, out / "report.md")
    images = {}
    if plot:
        from ..report.series_plot import plot_series  # noqa: PLC0415
        plot_series(result, path=out / "fit.png")
        images = {_CAPTION: out / "fit.png"}
    write_series_html(d, out / "report.html", images=images)


def _summary(result, out: Path) -> str:
    lines = [f"global {result.method} fit of {len(result.curves)} curves; slip: {result.slip['verdict']}"]
    if result.method == "mcmc":
        probs = ", ".join(f"P({k}) = {v:.3g}" for k, v in result.mcmc["model_probabilities"]["probabilities"].items())
        lines.append(f"MCMC {'converged' if result.converged else 'NOT CONVERGED (see report.html)'}; {probs}; "
                     f"seed {result.mcmc['seed']}; chains in chain.h5")
    from .cli_support import _fmt_estimate  # noqa: PLC0415
    for name, e in result.parameters.items():
        lines.append(_fmt_estimate(name, e))
    lines.append(f"observables: {', '.join(result.observables)}; {len(result.warnings)} warning(s); "
                 f"{result.wall_time:.1f} s; wrote {out}/report.json, report.md, report.html"
                 + (", fit.png" if (out / "fit.png").exists() else ""))
    return "\n".join(lines)
