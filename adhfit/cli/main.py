"""The entry point: the parser, ``adhfit simulate`` (docs/contracts.md A2) and the sub-command ``fit``
(A5, :mod:`.fit`).

Thin: parse, call the library, write files. Invalid input ends with exit status 2 and one line on
standard error that names the parameter, its value and the valid range; never a traceback.
"""
from __future__ import annotations

import argparse
import json
import math
import os
import sys
from pathlib import Path

from ..errors import AdhfitError, ConvergenceError
from ..membranes import membrane_choices
from ..params import DIMENSIONLESS

__all__ = ["main"]

EXIT_INPUT = 2
EXIT_FAILED = 3


class _Usage(Exception):
    """A command-line usage error (message is the one line to print)."""


class _Parser(argparse.ArgumentParser):
    def error(self, message: str) -> None:  # one line, exit 2 (argparse prints usage + line)
        # "argument --p: --p must be ..." -> "--p must be ..."
        head, _, rest = message.partition(": ")
        if head.startswith("argument ") and rest.startswith(head[len("argument "):].split("/")[0]):
            message = rest
        raise _Usage(f"{self.prog}: {message}")


def _number(name: str):
    """argparse type: a float (``inf`` allowed where the table allows it) with a named message."""
    row = DIMENSIONLESS.get(name.replace("-", "_"))

    def convert(text: str) -> float:
        try:
            value = float(text)
        except ValueError:
            valid = row.valid_range if row else "a number"
            raise argparse.ArgumentTypeError(f"--{name} must be {valid}; got {text!r}") from None
        if math.isnan(value):
            raise argparse.ArgumentTypeError(f"--{name} must be a number; got {text!r}")
        return value
    return convert


def _end(name: str):
    """argparse type of a loading end: a number (dimensionless), or kept as text when it carries a unit
    (physical, only with --scene)."""
    number = _number(name)

    def convert(text: str):
        try:
            return number(text)
        except argparse.ArgumentTypeError:
            if any(c.isalpha() for c in text.replace("inf", "")):
                return text  # e.g. "0.6 mm": checked against --scene later
            raise
    return convert


def _seed(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        value = -1
    if value < 0:
        raise argparse.ArgumentTypeError(f"--seed must be a non-negative integer; got {text!r}")
    return value


def _integer(name: str):
    def convert(text: str) -> int:
        try:
            return int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(
                f"--{name} must be {DIMENSIONLESS[name].valid_range.replace('a number', 'an integer')}; "
                f"got {text!r}") from None
    return convert


def _simulate_parser(sub) -> None:
    p = sub.add_parser("simulate", help="compute a loading history (dimensionless or from a scene file)",
                       description="Compute a loading history of the inflated-membrane adhesion model "
                                   "(docs/contracts.md). Values are dimensionless groups unless --scene is given.")
    T = DIMENSIONLESS
    p.add_argument("--control", choices=("displacement", "pressure"))
    p.add_argument("--slip", choices=("no-slip", "frictionless"))
    fixed = p.add_mutually_exclusive_group()
    fixed.add_argument("--p", type=_number("p"), help=f"{T['p'].description}: {T['p'].valid_range}")
    fixed.add_argument("--d", type=_number("d"), help=f"{T['d'].description}: {T['d'].valid_range}")
    p.add_argument("--w", type=_number("w"), help=f"{T['w'].description}: {T['w'].valid_range}")
    p.add_argument("--rs", type=_number("rs"), help=f"{T['rs'].description}: {T['rs'].valid_range}")
    end = p.add_mutually_exclusive_group()
    unit = " (with --scene also a value with a unit, e.g. {})"
    end.add_argument("--a-max", type=_end("a-max"), help=T["a_max"].description + unit.format("'0.5 mm'"))
    end.add_argument("--delta-max", type=_end("delta-max"),
                     help=T["delta_max"].description + unit.format("'0.6 mm'"))
    end.add_argument("--p-max", type=_end("p-max"), help=T["p_max"].description + unit.format("'1.6 kPa'"))
    p.add_argument("--lambda0", type=_number("lambda0"), default=None, help="pre-stretch (default 2)")
    p.add_argument("--points", type=_integer("points"), default=200, help="approximate number of rows")
    p.add_argument("--membrane", choices=membrane_choices(auto=False), default="large-stretch",
                   help="membrane model: the paper's large-stretch closed forms (default) or the exact "
                        "neo-Hookean membrane (lambda0 then matters)")
    p.add_argument("-o", "--output", type=Path, help="write the history as CSV")
    p.add_argument("--json", action="store_true", help="print the summary as one JSON object")
    p.add_argument("--plot", type=Path, help="write a plot of the history (PNG, PDF, SVG)")
    p.add_argument("--scene", type=Path,
                   help="physical input: a scene file (docs/contracts.md). -o then writes a measured-style "
                        "curve (displacement [um] or pressure [kPa], force [mN]) that 'adhfit fit' reads")
    p.add_argument("--mu-h", default=None, metavar="VALUE", help="with --scene: membrane stiffness, e.g. '2 N/m'")
    p.add_argument("--work-of-adhesion", default=None, metavar="VALUE",
                   help="with --scene: work of adhesion, e.g. '0.4 J/m^2'")
    p.add_argument("--noise", type=float, default=0.0, metavar="FRACTION",
                   help="with --scene: Gaussian force noise, a fraction of the force at the end of loading "
                        "(e.g. 0.01; default 0)")
    p.add_argument("--seed", type=_seed, default=None, help="with --scene: seed of the noise")
    p.add_argument("--history", action="store_true",
                   help="with --scene: write the full dimensionless history (the columns without --scene) "
                        "instead of the measured-style curve")


def _fit_parser(sub) -> None:
    from .arguments import add_fit_arguments  # noqa: PLC0415 - keeps simulate light
    from .fit import run_fit  # noqa: PLC0415
    from .interrupt import interruptible  # noqa: PLC0415 - Ctrl-C: one line, status 130, no process left
    add_fit_arguments(sub).set_defaults(run=interruptible(run_fit))
    from .arguments import add_plan_arguments  # noqa: PLC0415
    from .plan import run_plan  # noqa: PLC0415 - the planning package loads only when a plan runs
    add_plan_arguments(sub).set_defaults(run=interruptible(run_plan))


def _run_simulate(args) -> int:
    from ..simulation import simulate  # noqa: PLC0415
    if args.scene is not None:
        kwargs, scene = _scene_kwargs(args)
    else:
        scene = None
        for name in ("mu_h", "work_of_adhesion", "seed"):
            if getattr(args, name) is not None:
                raise _Usage(f"adhfit simulate: --{name.replace('_', '-')} needs --scene (physical units)")
        if args.noise or args.history:
            raise _Usage(f"adhfit simulate: --{'noise' if args.noise else 'history'} needs --scene")
        for name in ("a_max", "delta_max", "p_max"):
            if isinstance(getattr(args, name), str):
                valid = DIMENSIONLESS[name].valid_range
                raise _Usage(f"adhfit simulate: --{name.replace('_', '-')} must be {valid}; got "
                             f"{getattr(args, name)!r} (a value with a unit needs --scene)")
        missing = [n for n in ("control", "slip", "w", "rs") if getattr(args, n) is None]
        if missing:
            raise _Usage(f"adhfit simulate: --{missing[0]} is required (or give --scene)")
        kwargs = {"control": args.control, "slip": args.slip, "p": args.p, "d": args.d, "w": args.w,
                  "rs": args.rs, "a_max": args.a_max, "delta_max": args.delta_max,
                  "p_max": args.p_max, "lambda0": 2.0 if args.lambda0 is None else args.lambda0}
    result = simulate(**kwargs, points=args.points, membrane=args.membrane)
    if args.output is not None:
        if scene is not None and not args.history:
            _write_measured(args, scene, result)
        else:
            _write_csv(result.frame, args.output)
    if args.plot is not None:
        from ..report.plots import plot_history  # noqa: PLC0415
        plot_history(result, scene=None if scene is None else scene.scales(args.mu_h), path=args.plot)
    if args.json:
        print(json.dumps(result.summary, allow_nan=False))
    return 0


def _scene_kwargs(args):
    from ..scene import load_scene  # noqa: PLC0415
    for name in ("control", "p", "d", "w", "rs", "lambda0"):
        if getattr(args, name) is not None:
            raise _Usage(f"adhfit simulate: --{name} cannot be combined with --scene (the scene sets it)")
    from ..synthetic import parse_end  # noqa: PLC0415
    scene = load_scene(args.scene)
    kwargs = scene.to_dimensionless(args.mu_h, args.work_of_adhesion, slip=args.slip)
    scales = scene.scales(args.mu_h)
    given = {k: parse_end(k, v, scales) for k, v in (("a_max", args.a_max), ("delta_max", args.delta_max),
                                                     ("p_max", args.p_max)) if v is not None}
    if given:
        for k in ("a_max", "delta_max", "p_max"):
            kwargs.pop(k, None)
        kwargs.update(given)
    elif not any(k in kwargs for k in ("a_max", "delta_max", "p_max")):
        raise _Usage("adhfit simulate: give a loading end (--a-max, --delta-max or --p-max) or set "
                     "[test] contact_radius_max / displacement_max / pressure_max in the scene")
    return kwargs, scene


def _write_measured(args, scene, result) -> None:
    """The measured-style CSV of a scene run (what a testing machine records; 'adhfit fit' reads it)."""
    from ..synthetic import loading_end_si, measured_frame  # noqa: PLC0415
    scales = scene.scales(args.mu_h)
    kw = result.inputs
    x_max = loading_end_si(result.frame, scene.control, scales)
    frame, _ = measured_frame(scene, kw["slip"], mu_h=scales.mu_h, work_of_adhesion=kw["w"] * scales.mu_h,
                              x_max=x_max, rows=args.points, noise=args.noise, seed=args.seed)
    args.output.parent.mkdir(parents=True, exist_ok=True)
    frame.to_csv(args.output, index=False, float_format="%.9g")


def _write_csv(frame, path: Path) -> None:
    out = frame.copy()
    out["stable"] = out["stable"].map({True: "true", False: "false"})
    path.parent.mkdir(parents=True, exist_ok=True)
    out.to_csv(path, index=False, float_format="%.17g", na_rep="")


def _build_parser() -> _Parser:
    parser = _Parser(prog="adhfit", description="Adhesion tests with an inflated elastic membrane.")
    from .. import __version__  # noqa: PLC0415
    parser.add_argument("--version", action="version", version=f"adhfit {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, parser_class=_Parser)
    _simulate_parser(sub)
    try:
        _fit_parser(sub)
    except ImportError:  # fitting not installed in this build
        pass
    return parser


def run() -> None:
    """The ``adhfit`` console script: :func:`main`, then exit without the interpreter's teardown.

    Everything a command writes is closed by then; what is left is freeing the compiled engine, the
    libraries and their modules, which takes 0.5-0.9 s after a fit for nothing.  The output streams
    are flushed first.
    """
    status = main()
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except (OSError, ValueError):  # a closed pipe: nothing more can be delivered anyway
            pass
    os._exit(status)


def main(argv: list[str] | None = None) -> int:
    """The command line: parse ``argv`` (default ``sys.argv[1:]``), run the command; returns the exit
    status (:func:`run` is the console script)."""
    parser = _build_parser()
    try:
        args = parser.parse_args(argv)
        if args.command == "simulate":
            return _run_simulate(args)
        return args.run(args)
    except _Usage as err:
        print(str(err).replace("\n", " "), file=sys.stderr)
        return EXIT_INPUT
    except ConvergenceError as err:
        # DomainError (a ConvergenceError subclass) is "no solution exists here": its own status 4, so a
        # script can tell it from a solver failure (3); docs/contracts.md "Errors and exit statuses".
        # Imported here so that this mapping stays the only part of the module it touches.
        from ..errors import DomainError  # noqa: PLC0415
        print(f"adhfit: {err}".replace("\n", " "), file=sys.stderr)
        return 4 if isinstance(err, DomainError) else EXIT_FAILED
    except (AdhfitError, ValueError) as err:
        print(f"adhfit: {err}".replace("\n", " "), file=sys.stderr)
        return EXIT_INPUT
    except OSError as err:
        print(f"adhfit: {err}".replace("\n", " "), file=sys.stderr)
        return EXIT_INPUT
    except Exception as err:  # noqa: BLE001 - the CLI promises one line, never a traceback
        print(f"adhfit: internal error ({type(err).__name__}: {err}); please report it".replace("\n", " "),
              file=sys.stderr)
        return 1



