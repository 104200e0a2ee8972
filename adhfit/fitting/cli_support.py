"""``adhfit fit`` (DESIGN.md A5): the argument parser and the run function the CLI calls.

Thin: parse, call :func:`adhfit.fitting.fit.fit_curve`, write ``report.json``, ``report.md`` and
``fit.png`` into the output directory, print a short summary.  Invalid input raises
:class:`~adhfit.errors.InputError` / :class:`~adhfit.errors.DataError`, which the CLI turns into one
line on standard error and exit status 2.
"""
from __future__ import annotations

import argparse
from pathlib import Path

from ..errors import InputError
from .options import DEFAULT_POINTS, METHODS, SLIP_CHOICES

#: ``--membrane`` choices (adhfit.scene.MEMBRANE_MODELS; repeated here to keep the parser's imports light)
MEMBRANE_CHOICES = ("auto", "large-stretch", "exact")

__all__ = ["add_fit_arguments", "run_fit"]


def _seed(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"--seed must be a non-negative integer; got {text!r}") from None
    if value < 0:
        raise argparse.ArgumentTypeError(f"--seed must be a non-negative integer; got {text!r}")
    return value


def _points(text: str) -> int:
    try:
        return int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"--points must be an integer in [40, 5000]; got {text!r}") from None


def add_fit_arguments(subparsers) -> argparse.ArgumentParser:
    """Add the ``fit`` sub-command to an argparse sub-parser collection; returns its parser."""
    p = subparsers.add_parser(
        "fit", help="fit W_ad, mu*h and the slip condition to a measured curve",
        description="Fit the work of adhesion W_ad, the membrane stiffness mu*h and the interface slip "
                    "condition to a measured force curve (DESIGN.md A5). Writes OUTDIR/report.json, "
                    "report.md, report.html and fit.png. Several files or a folder: one fit per curve and "
                    "OUTDIR/summary.csv (see adhfit.fitting.batch).")
    p.add_argument("data", type=Path, nargs="+", metavar="DATA",
                   help="measured curve (CSV, 'name [unit]' headers); several files or folders: a batch "
                        "with OUTDIR/summary.csv (exit 1 if any curve failed)")
    p.add_argument("--scene", type=Path, default=None, metavar="SCENE.toml",
                   help="scene file: geometry and the fixed pressure or gap (default: the nearest "
                        "scene.toml in the curve's folder or, for a folder argument, its parents)")
    p.add_argument("--method", choices=METHODS, default="lsq", help="lsq: least squares (lmfit); mcmc: posterior sampling (emcee), both slips, model probabilities")
    p.add_argument("--slip", choices=SLIP_CHOICES, default=None,
                   help="slip condition; default: the scene's (auto = fit both and compare)")
    p.add_argument("--seed", type=_seed, default=None, help="random seed (recorded; lsq draws none)")
    p.add_argument("-o", "--output", type=Path, default=None, metavar="OUTDIR",
                   help="output directory (default: ./<DATA stem>_fit)")
    p.add_argument("--sigma", default=None, metavar="FORCE",
                   help="force noise, e.g. '0.01 mN' (default: estimated from the residuals)")
    p.add_argument("--force-offset", action="store_true",
                   help="fit the load-cell zero (the default; kept for older scripts)")
    p.add_argument("--no-force-offset", action="store_true",
                   help="fix the load-cell zero at 0 instead of fitting it (the data must be tared)")
    p.add_argument("--no-offset", action="store_true",
                   help="do not fit the displacement offset (displacement control)")
    p.add_argument("--pressure-offset", action="store_true", help="fit a pressure offset (pressure control)")
    p.add_argument("--membrane", choices=MEMBRANE_CHOICES, default=None,
                   help="membrane model: large-stretch (the paper's), exact (neo-Hookean, slower), auto (exact "
                        "where the data resolve the difference); default: the scene's [membrane] model (auto)")
    p.add_argument("--points", type=_points, default=DEFAULT_POINTS, help="rows per computed history")
    p.add_argument("--no-profile", action="store_true", help="covariance intervals only (faster)")
    p.add_argument("--no-plot", action="store_true", help="do not write fit.png")
    p.set_defaults(run=run_fit)
    return p


def _x_offset(args, control: str) -> bool:
    if args.no_offset and args.pressure_offset:
        raise InputError("--no-offset", True, "absent when --pressure-offset is given")
    if control == "displacement":
        if args.pressure_offset:
            raise InputError("--pressure-offset", True, "used with pressure control only")
        return not args.no_offset
    return bool(args.pressure_offset)


def _force_offset(args) -> bool:
    if args.no_force_offset and args.force_offset:
        raise InputError("--no-force-offset", True, "absent when --force-offset is given")
    return not args.no_force_offset


def run_fit(args) -> int:
    """Run ``adhfit fit`` from parsed arguments; returns the exit status."""
    from ..data import read_curve  # noqa: PLC0415
    from ..report.fit_plot import plot_fit  # noqa: PLC0415
    from ..report.json_report import write_json  # noqa: PLC0415
    from ..report.markdown import write_markdown  # noqa: PLC0415
    from ..scene import load_scene  # noqa: PLC0415
    from ..units import parse_quantity  # noqa: PLC0415
    from .fit import fit_curve  # noqa: PLC0415
    from . import batch  # noqa: PLC0415
    if isinstance(args.data, list):  # the command line gives a list: a batch, or one curve
        if batch.is_batch(args.data):
            return batch.run_batch(args, run_fit)
        args.data = args.data[0]
    if args.scene is None:
        args.scene = batch.single_scene(args.data)
    if args.method == "mcmc":
        from .mcmc_cli import run_fit_mcmc  # noqa: PLC0415
        return run_fit_mcmc(args)
    sigma = None if args.sigma is None else parse_quantity(args.sigma, "force", name="--sigma")
    scene = load_scene(args.scene)
    curve = read_curve(args.data, scene.control)
    result = fit_curve(curve, scene, method=args.method, slip=args.slip, sigma=sigma,
                       fit_x_offset=_x_offset(args, scene.control), fit_force_offset=_force_offset(args),
                       seed=args.seed, points=args.points, profile=not args.no_profile,
                       membrane=getattr(args, "membrane", None))
    out = args.output if args.output is not None else Path(f"{Path(args.data).stem}_fit")
    out.mkdir(parents=True, exist_ok=True)
    write_json(result, out / "report.json")
    write_markdown(result, out / "report.md")
    if not args.no_plot:
        plot_fit(result, path=out / "fit.png")
    from ..report.html import write_html  # noqa: PLC0415
    write_html(result, out / "report.html", images={} if args.no_plot else {"fit.png": out / "fit.png"})
    print(_summary(result, out))
    return 0


def _summary(result, out: Path) -> str:
    lines = [f"slip: {result.slip['verdict']}"]
    lines.append(f"membrane: {result.model['membrane']} ({result.model['why']})")
    for e in result.parameters.values():
        status = getattr(e, "status", "determined")
        if status == "lower_bound":
            lines.append(f"{e.name} >= {e.ci95[0]:.5g} {e.unit} (one-sided 95 %; the data bound it from below only)")
            continue
        if status == "upper_bound":
            lines.append(f"{e.name} <= {e.ci95[1]:.5g} {e.unit} (one-sided 95 %; the data bound it from above only)")
            continue
        if status == "undetermined":
            lines.append(f"{e.name}: not determined by these data")
            continue
        ci = "" if e.ci95 is None else f"  95 % [{e.ci95[0]:.5g}, {e.ci95[1]:.5g}]"
        se = "" if e.stderr is None else f" ± {e.stderr:.2g}"
        lines.append(f"{e.name} = {e.value:.5g}{se} {e.unit}{ci}")
    lines.append(f"{len(result.warnings)} warning(s); {result.n_evaluations} model evaluations, "
                 f"{result.wall_time:.1f} s; wrote {out}/report.json, report.md, report.html, fit.png")
    return "\n".join(lines)
