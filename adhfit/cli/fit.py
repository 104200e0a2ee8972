"""``adhfit fit``: one curve by least squares, and the dispatch to a batch, ``--global`` or MCMC.

Thin: read the scene and the curve, call :func:`adhfit.fitting.fit.fit_curve`, write the reports
(:mod:`.writing`), print a short summary.  Invalid input raises :class:`~adhfit.errors.InputError` /
:class:`~adhfit.errors.DataError`, which :func:`adhfit.cli.main.main` turns into one line on standard
error and exit status 2.
"""
from __future__ import annotations

from pathlib import Path

from .arguments import fit_force_offset, fit_x_offset, read_options
from .engine import elapsed, start_engine
from .writing import check_output_dir, summary_text, write_reports

__all__ = ["run_fit"]


def run_fit(args) -> int:
    """Run ``adhfit fit`` from parsed arguments; returns the exit status."""
    if getattr(args, "global_fit", False):  # several curves, one fit: never the batch path
        from .series import run_global  # noqa: PLC0415
        return run_global(args)
    from . import batch  # noqa: PLC0415
    if isinstance(args.data, list):  # the command line gives a list: a batch, or one curve
        if batch.is_batch(args.data):  # before the heavy imports: the workers may do all the fitting
            if args.output is not None:
                check_output_dir(args.output)
            return batch.run_batch(args, run_fit)
        args.data = args.data[0]
    from ..data import read_curve  # noqa: PLC0415
    from ..scene import load_scene  # noqa: PLC0415
    from ..units import parse_quantity  # noqa: PLC0415
    from ..fitting.fit import fit_curve  # noqa: PLC0415
    if args.scene is None:
        args.scene = batch.single_scene(args.data)
    out = args.output if args.output is not None else Path(f"{Path(args.data).stem}_fit")
    check_output_dir(out)
    if args.method == "mcmc":
        from .mcmc import run_fit_mcmc  # noqa: PLC0415
        return run_fit_mcmc(args)
    sigma = None if args.sigma is None else parse_quantity(args.sigma, "force", name="--sigma")
    scene = load_scene(args.scene)
    curve = read_curve(args.data, scene.control, **read_options(args))
    quiet = getattr(args, "quiet", False)
    startup = start_engine(scene.control, quiet=quiet)
    with elapsed(f"fitting {Path(args.data).name}", enabled=False if quiet else None):
        result = fit_curve(curve, scene, method=args.method, slip=args.slip, sigma=sigma,
                           fit_x_offset=fit_x_offset(args, scene.control), fit_force_offset=fit_force_offset(args),
                           seed=args.seed, points=args.points, profile=not args.no_profile,
                           membrane=getattr(args, "membrane", None))
    write_reports(result, out, plot=not args.no_plot, extra={"engine_startup_s": startup})
    print(summary_text(result, out))
    return 0


