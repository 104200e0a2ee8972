"""``adhfit fit``: one curve (least squares or MCMC), and the dispatch to a batch or ``--global``.

Thin: read the scene and the curve, call :func:`adhfit.fit`, write every report with
:func:`adhfit.report.write`, print a short summary.  Invalid input raises
:class:`~adhfit.errors.InputError` / :class:`~adhfit.errors.DataError`, which
:func:`adhfit.cli.main.main` turns into one line on standard error and exit status 2.
"""
from __future__ import annotations

from pathlib import Path

from .arguments import fit_force_offset, fit_x_offset, read_options
from .engine import EngineLoader, elapsed
from .painter import Painter
from .reading import reading
from .writing import check_output_dir, exit_status, summary_text

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
    # a second process loads matplotlib and draws fit.png on the other core while this one fits, and a
    # thread loads the compiled kernels while this one imports the fitting libraries
    painter = Painter() if not args.no_plot and getattr(args, "painter", True) else None
    engine = EngineLoader(quiet=getattr(args, "quiet", False))
    try:
        return _fit_one(args, painter, engine)
    finally:
        if painter is not None:
            painter.close()


def _fit_one(args, painter, engine) -> int:
    """One curve: read, fit (least squares or MCMC), write the reports, print the summary."""
    from . import batch  # noqa: PLC0415
    from ..data import read_curve  # noqa: PLC0415
    from ..fitting.api import fit  # noqa: PLC0415 - lmfit loads while the kernels load (thread)
    from ..fitting import stage  # noqa: F401, PLC0415
    from ..report import write  # noqa: PLC0415
    from ..scene import load_scene  # noqa: PLC0415
    from ..units import parse_quantity  # noqa: PLC0415
    if args.scene is None:
        args.scene = batch.single_scene(args.data)
    out = check_output_dir(args.output if args.output is not None else Path(f"{Path(args.data).stem}_fit"))
    sigma = None if args.sigma is None else parse_quantity(args.sigma, "force", name="--sigma")
    sigma_a = None if getattr(args, "sigma_radius", None) is None else \
        parse_quantity(args.sigma_radius, "length", name="--sigma-radius")
    scene = load_scene(args.scene)
    quiet = getattr(args, "quiet", False)
    with reading(args.data, quiet=quiet):
        curve = read_curve(args.data, scene.control, **read_options(args))
    startup = engine.wait(scene.control)
    mcmc = args.method == "mcmc"
    # MCMC samples the two slip conditions in two processes: one running clock here, no bars there
    by_method = {"outdir": out, "progress": False} if mcmc else {"profile": not args.no_profile}
    with elapsed(f"fitting {Path(args.data).name}", enabled=False if quiet else None):
        result = fit(curve, scene, method=args.method, slip=args.slip, sigma=sigma,
                     fit_x_offset=fit_x_offset(args, scene.control), fit_force_offset=fit_force_offset(args),
                     seed=args.seed, points=args.points, membrane=getattr(args, "membrane", None),
                     contact_radius=not getattr(args, "no_contact_radius", False), sigma_contact_radius=sigma_a,
                     **by_method)
    drawn = ()
    if painter is not None:
        from ..report.fit_plot import fit_view  # noqa: PLC0415
        out.mkdir(parents=True, exist_ok=True)
        painter.paint(fit_view(result), out / "fit.png")
        drawn = ("fit.png",) if painter.finish() else ()
    write(result, out, plot=not args.no_plot, extra={"engine_startup_s": startup}, drawn=drawn)
    text = summary_text(result, out)
    if mcmc:
        state = "converged" if result.converged else "NOT CONVERGED (see report.html)"
        probs = ", ".join(f"P({k}) = {v:.3g}" for k, v in result.mcmc["model_probabilities"]["probabilities"].items())
        text = (f"MCMC {state}; {probs}; seed {result.mcmc['seed']}\n{text}\n"
                "MCMC outputs: fit_mcmc.png, corner.png, chain.h5")
    print(text)
    return exit_status(result)
