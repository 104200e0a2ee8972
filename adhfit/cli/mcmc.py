"""``adhfit fit --method mcmc``: run :func:`adhfit.fitting.mcmc_fit.fit_curve_mcmc` from parsed arguments and write
OUTDIR/report.json, report.md, report.html, fit.png (least-squares curves), fit_mcmc.png
(posterior-predictive band), corner.png and chain.h5.  Called by :func:`.fit.run_fit`, which
has already checked the output directory."""
from __future__ import annotations

from pathlib import Path

from .arguments import fit_force_offset, fit_x_offset, read_options
from .engine import start_engine
from .writing import check_output_dir, summary_text, write_reports

__all__ = ["run_fit_mcmc"]


def run_fit_mcmc(args) -> int:
    """Run the MCMC fit for the ``adhfit fit`` arguments; returns the exit status."""
    from ..data import read_curve  # noqa: PLC0415
    from ..scene import load_scene  # noqa: PLC0415
    from ..units import parse_quantity  # noqa: PLC0415
    from ..fitting.mcmc_fit import fit_curve_mcmc  # noqa: PLC0415
    sigma = None if args.sigma is None else parse_quantity(args.sigma, "force", name="--sigma")
    scene = load_scene(args.scene)
    curve = read_curve(args.data, scene.control, **read_options(args))
    out = check_output_dir(args.output if args.output is not None else Path(f"{Path(args.data).stem}_fit"))
    quiet = getattr(args, "quiet", False)
    startup = start_engine(scene.control, quiet=quiet)
    out.mkdir(parents=True, exist_ok=True)  # the chains are written while sampling
    result = fit_curve_mcmc(curve, scene, slip=args.slip, sigma=sigma,
                            fit_x_offset=fit_x_offset(args, scene.control), fit_force_offset=fit_force_offset(args),
                            seed=args.seed, points=args.points, outdir=out, progress=False if quiet else None,
                            membrane=getattr(args, "membrane", None))
    images = {}
    if not args.no_plot:
        from ..report.mcmc_plots import plot_corner, plot_predictive  # noqa: PLC0415
        plot_predictive(result, path=out / "fit_mcmc.png")
        plot_corner(result, path=out / "corner.png")
        images = {name: out / name for name in ("fit_mcmc.png", "corner.png")}
    write_reports(result, out, plot=not args.no_plot, images=images, extra={"engine_startup_s": startup})
    text = summary_text(result, out) + "\nMCMC outputs: fit_mcmc.png, corner.png, chain.h5"
    state = "converged" if result.converged else "NOT CONVERGED (see report.html)"
    mc = result.mcmc
    probs = ", ".join(f"P({k}) = {v:.3g}" for k, v in mc["model_probabilities"]["probabilities"].items())
    print(f"MCMC {state}; {probs}; seed {mc['seed']}\n{text}")
    return 0
