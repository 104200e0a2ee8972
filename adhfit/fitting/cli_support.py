"""``adhfit fit`` (docs/contracts.md A5): the argument parser and the run function the CLI calls.

Thin: parse, call :func:`adhfit.fitting.fit.fit_curve`, write ``report.json``, ``report.md`` and
``fit.png`` into the output directory, print a short summary.  Invalid input raises
:class:`~adhfit.errors.InputError` / :class:`~adhfit.errors.DataError`, which the CLI turns into one
line on standard error and exit status 2.
"""
from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

from ..errors import InputError
from .options import DEFAULT_POINTS, METHODS, SLIP_CHOICES

#: ``--membrane`` choices (adhfit.scene.MEMBRANE_MODELS; repeated here to keep the parser's imports light)
MEMBRANE_CHOICES = ("auto", "large-stretch", "exact")

__all__ = ["add_fit_arguments", "read_options", "run_fit", "check_output_dir", "start_engine", "write_reports"]


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


def _pairs(flag: str, example: str):
    """An argparse type for ``key=value,key=value`` (``--columns``, ``--units``)."""
    def parse(text: str) -> dict[str, str]:
        out = {}
        for item in filter(None, (part.strip() for part in text.split(","))):
            key, sep, value = item.partition("=")
            if not sep or not key.strip() or not value.strip():
                raise argparse.ArgumentTypeError(f"{flag} takes KEY=VALUE pairs separated by commas, e.g. "
                                                 f"{flag} {example}; got {text!r}")
            out[key.strip()] = value.strip()
        return out
    return parse


def read_options(args) -> dict:
    """The reader overrides (``--columns``, ``--units``, ``--force-sign``, ``--displacement-sign``) given."""
    keys = ("columns", "units", "force_sign", "displacement_sign")
    return {k: getattr(args, k) for k in keys if getattr(args, k, None)}


def _workers(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        value = 0
    if value < 1:
        raise argparse.ArgumentTypeError(f"--workers must be a positive integer (local processes); got {text!r}")
    return value


def add_fit_arguments(subparsers) -> argparse.ArgumentParser:
    """Add the ``fit`` sub-command to an argparse sub-parser collection; returns its parser."""
    p = subparsers.add_parser(
        "fit", help="fit W_ad, mu*h and the slip condition to a measured curve",
        description="Fit the work of adhesion W_ad, the membrane stiffness mu*h and the interface slip "
                    "condition to a measured force curve (docs/contracts.md). Writes OUTDIR/report.json, "
                    "report.md, report.html and fit.png. Several files or a folder: one fit per curve, "
                    "OUTDIR/summary.csv and OUTDIR/summary.html (a page with every curve).")
    p.add_argument("data", type=Path, nargs="+", metavar="DATA",
                   help="measured curve (CSV, 'name [unit]' headers); several files or folders: a batch "
                        "with OUTDIR/summary.csv and summary.html (exit 1 if any curve failed)")
    p.add_argument("--scene", type=Path, default=None, metavar="SCENE.toml",
                   help="scene file: geometry and the fixed pressure or gap (default: the nearest "
                        "scene.toml in the curve's folder or, for a folder argument, its parents)")
    p.add_argument("--method", choices=METHODS, default="lsq", help="lsq: least squares (lmfit); mcmc: posterior sampling (emcee), both slips, model probabilities")
    p.add_argument("--slip", choices=SLIP_CHOICES, default=None,
                   help="slip condition; default: the scene's (auto = fit both and compare)")
    p.add_argument("--seed", type=_seed, default=None,
                   help="random seed for --method mcmc (least squares uses no random numbers)")
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
    p.add_argument("-q", "--quiet", action="store_true",
                   help="no progress bar and no start-up notice on standard error (results still printed)")
    r = p.add_argument_group("reading the data file", "needed only where the file does not tell "
                             "(instrument exports are recognised without them; see docs/input-formats.md)")
    r.add_argument("--columns", type=_pairs("--columns", "force=Load,displacement=Position"), default=None,
                   metavar="force=NAME,displacement=NAME", help="which header names hold which quantity")
    r.add_argument("--units", type=_pairs("--units", "displacement=mm,force=N"), default=None,
                   metavar="displacement=mm,force=N", help="units, overriding the file's")
    r.add_argument("--force-sign", choices=("compressive-positive", "tensile-positive"), default=None,
                   help="the file's force sign (default: compressive-positive)")
    r.add_argument("--displacement-sign", choices=("into-substrate-positive", "away-positive"), default=None,
                   help="the file's displacement sign (default: into-substrate-positive)")
    p.add_argument("--workers", type=_workers, default=None, metavar="N",
                   help="batch: fit the curves in N local processes (default: one per core)")
    p.add_argument("--scheduler", default=None, metavar="ADDRESS",
                   help="batch: fit the curves on the Dask distributed cluster at ADDRESS, e.g. "
                        "tcp://10.0.0.5:8786 (pip install 'adhfit[dask]'; files on a shared disk)")
    p.add_argument("--global", dest="global_fit", action="store_true",
                   help="several curves of one membrane and substrate: one W_ad, one mu*h and one slip condition, "
                        "offsets per curve (the load-cell zero always fitted), each curve its own scene (docs/contracts.md A7)")
    p.add_argument("--sigma-radius", default=None, metavar="LENGTH",
                   help="with --global: contact-radius noise, e.g. '2 um' (default: estimated per curve)")
    p.add_argument("--no-contact-radius", action="store_true",
                   help="with --global: do not fit the contact_radius column")
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


def check_output_dir(path: Path) -> Path:
    """Make sure ``path`` can hold the reports *before* any work, without creating it yet.

    Raises
    ------
    InputError
        ``path`` is an existing file, lies under a file, or its nearest existing folder is not writable.
    """
    path = Path(path)
    if path.exists() and not path.is_dir():
        raise InputError("-o/--output", str(path), "a folder (it is an existing file)",
                         "Give another name, or remove the file.")
    parent = next((q for q in [path, *path.parents] if q.exists()), Path("."))
    if not parent.is_dir():
        raise InputError("-o/--output", str(path), "a folder path", f"{parent} is a file, not a folder.")
    if not os.access(parent, os.W_OK | os.X_OK):
        raise InputError("-o/--output", str(path), "a folder you can write to",
                         f"{parent} is not writable; choose another folder, or change its permissions.")
    return path


def start_engine(control: str, *, quiet: bool = False) -> float:
    """Compile or load the engine before a fit starts its clock; returns the seconds it took.

    On a cold numba cache, prints the one-line notice on standard error first (not with ``quiet``).
    """
    from ..cli_engine import COMPILING_NOTICE, engine_cache_is_cold, warm_up  # noqa: PLC0415
    if not quiet and engine_cache_is_cold():
        print(COMPILING_NOTICE, file=sys.stderr, flush=True)
    return warm_up(control)


def _force_offset(args) -> bool:
    if args.no_force_offset and args.force_offset:
        raise InputError("--no-force-offset", True, "absent when --force-offset is given")
    return not args.no_force_offset


def run_fit(args) -> int:
    """Run ``adhfit fit`` from parsed arguments; returns the exit status."""
    if getattr(args, "global_fit", False):  # several curves, one fit: never the batch path
        from .global_cli import run_global  # noqa: PLC0415
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
    from .fit import fit_curve  # noqa: PLC0415
    if args.scene is None:
        args.scene = batch.single_scene(args.data)
    out = args.output if args.output is not None else Path(f"{Path(args.data).stem}_fit")
    check_output_dir(out)
    if args.method == "mcmc":
        from .mcmc_cli import run_fit_mcmc  # noqa: PLC0415
        return run_fit_mcmc(args)
    sigma = None if args.sigma is None else parse_quantity(args.sigma, "force", name="--sigma")
    scene = load_scene(args.scene)
    curve = read_curve(args.data, scene.control, **read_options(args))
    quiet = getattr(args, "quiet", False)
    startup = start_engine(scene.control, quiet=quiet)
    from ..cli_engine import elapsed  # noqa: PLC0415
    with elapsed(f"fitting {Path(args.data).name}", enabled=False if quiet else None):
        result = fit_curve(curve, scene, method=args.method, slip=args.slip, sigma=sigma,
                           fit_x_offset=_x_offset(args, scene.control), fit_force_offset=_force_offset(args),
                           seed=args.seed, points=args.points, profile=not args.no_profile,
                           membrane=getattr(args, "membrane", None))
    write_reports(result, out, plot=not args.no_plot, extra={"engine_startup_s": startup})
    print(_summary(result, out))
    return 0


def write_reports(result, out: Path, *, plot: bool = True, images: dict | None = None,
                  extra: dict | None = None) -> None:
    """Write report.json, report.md, report.html, plot_data.json (data and fitted curve, for a batch's
    summary.html) and (``plot``) fit.png of one fit into ``out``."""
    from ..report.fit_plot import plot_fit  # noqa: PLC0415
    from ..report.html import write_html  # noqa: PLC0415
    from ..report.json_report import write_json  # noqa: PLC0415
    from ..report.markdown import write_markdown  # noqa: PLC0415
    out.mkdir(parents=True, exist_ok=True)
    write_json(result, out / "report.json", extra=extra)
    write_markdown(result, out / "report.md")
    from ..report.summary_html import write_plot_data  # noqa: PLC0415
    write_plot_data(result, out / "plot_data.json")
    figures = dict(images or {})
    if plot:
        plot_fit(result, path=out / "fit.png")
        figures = {"fit.png": out / "fit.png", **figures}
    write_html(result, out / "report.html", images=figures, extra=extra)


def _fmt_estimate(name: str, e) -> str:
    """One line per estimate, honest about one-sided and undetermined parameters."""
    d = e if isinstance(e, dict) else e.as_dict()
    from ..report.text import estimate_text  # noqa: PLC0415
    return f"{name} = {estimate_text(name, d)}"


def _summary(result, out: Path) -> str:
    d = result.as_dict()
    lines = [f"slip: {d['slip'].get('verdict')}"]
    if d.get("model"):
        lines.append(f"membrane: {d['model']['membrane']} ({d['model']['why']})")
    shown = dict(d.get("parameters", {}))
    for name, e in shown.items():
        lines.append(_fmt_estimate(name, e))
    n_warn = len(d.get("warnings", []) or [])
    lines.append(f"{n_warn} warning(s); {d.get('model_evaluations')} model evaluations, "
                 f"{result.wall_time:.1f} s; wrote {out}/report.json, report.md, report.html"
                 + ("" if not (out / "fit.png").exists() else ", fit.png"))
    return "\n".join(lines)
