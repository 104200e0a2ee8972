"""``adhfit fit``'s options (docs/contracts.md A5, A4b, A7) and ``adhfit plan``'s (A8): the parsers and what the
options mean.

Parsing only: nothing here reads a file or runs a fit.  Invalid values end with argparse's one-line
error (exit status 2, see :mod:`.main`) or an :class:`~adhfit.errors.InputError` naming the flag.
"""
from __future__ import annotations

import argparse
from pathlib import Path

from ..errors import InputError
from ..fitting.options import DEFAULT_POINTS
from ..membranes import membrane_choices
from ..params import METHODS, SLIP_CHOICES

__all__ = ["add_fit_arguments", "add_plan_arguments", "read_options", "fit_x_offset", "fit_force_offset"]


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
    p.add_argument("--membrane", choices=membrane_choices(), default=None,
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
    p.add_argument("--resume", action="store_true",
                   help="batch: keep the reports of curves an earlier batch into the same -o already fitted from "
                        "the same file, scene and settings; fit only the others (docs/contracts.md A7b)")
    p.add_argument("--global", dest="global_fit", action="store_true",
                   help="several curves of one membrane and substrate: one W_ad, one mu*h and one slip condition, "
                        "offsets per curve, each curve its own scene (docs/contracts.md A7)")
    p.add_argument("--sigma-radius", default=None, metavar="LENGTH",
                   help="contact-radius noise, e.g. '2 um' (default: estimated per curve)")
    p.add_argument("--no-contact-radius", action="store_true",
                   help="do not fit the contact_radius column (fitted by default where a curve has one)")
    return p


def fit_x_offset(args, control: str) -> bool:
    if args.no_offset and args.pressure_offset:
        raise InputError("--no-offset", True, "absent when --pressure-offset is given")
    if control == "displacement":
        if args.pressure_offset:
            raise InputError("--pressure-offset", True, "used with pressure control only")
        return not args.no_offset
    return bool(args.pressure_offset)


def fit_force_offset(args) -> bool:
    if args.no_force_offset and args.force_offset:
        raise InputError("--no-force-offset", True, "absent when --force-offset is given")
    return not args.no_force_offset


def add_plan_arguments(subparsers) -> argparse.ArgumentParser:
    """Add the ``plan`` sub-command (docs/contracts.md A8) to an argparse sub-parser collection; returns its parser."""
    p = subparsers.add_parser(
        "plan", help="plan a test: which protocol decides W_ad, mu*h and the slip (before running it)",
        description="Predict, for candidate protocols, the 95 % interval widths of W_ad and mu*h that a fit "
                    "will report and the probability that it decides the slip condition; recommend the cheapest "
                    "protocol that decides the slip (P >= 0.9) and reaches --target-precision (docs/planning.md). "
                    "Writes DIR/plan.json, DIR/report.html and DIR/scene.toml (the recommended protocol).")
    p.add_argument("--scene", type=Path, required=True, metavar="SCENE.toml",
                   help="geometry, control mode, the fixed pressure or gap, membrane model")
    p.add_argument("--work-of-adhesion", required=True, metavar="W", help="guessed W_ad, e.g. '0.3 J/m^2'")
    p.add_argument("--mu-h", required=True, metavar="MU", help="guessed membrane stiffness, e.g. '1.5 N/m'")
    p.add_argument("--noise", required=True, metavar="SIGMA",
                   help="force noise as a fraction of the peak force, e.g. 0.02 or 2%%")
    p.add_argument("--slip", choices=("both", "no-slip", "frictionless"), default="both",
                   help="the true slip condition(s) to plan for (default both)")
    p.add_argument("--rows", type=int, default=300, metavar="N", help="rows of the whole test (default 300)")
    end = p.add_mutually_exclusive_group()
    end.add_argument("--a-max", default=None, metavar="A", help="loading end: contact radius over b")
    end.add_argument("--delta-max", default=None, metavar="X",
                     help="loading end: largest displacement (dimensionless, or with a unit, e.g. '0.4 mm')")
    end.add_argument("--pressure-max", default=None, metavar="Q",
                     help="loading end: largest pressure (dimensionless, or with a unit, e.g. '1.2 kPa')")
    p.add_argument("--vary", default=None, metavar="NAME=LO:HI[:K],...",
                   help="span one or two settings (pressure, gap, a_max, displacement_max, pressure_max, rows, "
                        "noise), e.g. pressure=0.5:2kPa:10,a_max=0.1:0.4:10")
    p.add_argument("--global", dest="global_k", type=int, default=None, metavar="K",
                   help="test series: the best set of K values of the varied pressure (or gap)")
    p.add_argument("--radius-noise", default=None, metavar="FRACTION",
                   help="a camera films the contact radius with this noise (fraction of the largest contact radius, "
                        "e.g. 1%%): its information joins the widths (single tests and --global)")
    p.add_argument("--target-precision", type=float, default=0.1, metavar="FRACTION",
                   help="requested W_ad precision: expected 95 %% interval width over W_ad (default 0.1)")
    p.add_argument("--membrane", choices=membrane_choices(), default=None,
                   help="membrane model (default: the scene's; auto as the fit decides it)")
    p.add_argument("--workers", type=_workers, default=1, metavar="N", help="local processes (default 1)")
    p.add_argument("-o", "--output", type=Path, required=True, metavar="DIR", help="output directory")
    return p
