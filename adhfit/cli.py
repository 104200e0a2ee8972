"""Command line: ``adhfit simulate`` (DESIGN.md A2) and ``adhfit fit`` (A5).

Thin: parse, call the library, write files. Invalid input ends with exit status 2 and one line on
standard error that names the parameter, its value and the valid range; never a traceback.
"""
from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

from .errors import AdhfitError, ConvergenceError
from .params import DIMENSIONLESS

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
                                   "(DESIGN.md A2). Values are dimensionless groups unless --scene is given.")
    T = DIMENSIONLESS
    p.add_argument("--control", choices=("displacement", "pressure"))
    p.add_argument("--slip", choices=("no-slip", "frictionless"))
    fixed = p.add_mutually_exclusive_group()
    fixed.add_argument("--p", type=_number("p"), help=f"{T['p'].description}: {T['p'].valid_range}")
    fixed.add_argument("--d", type=_number("d"), help=f"{T['d'].description}: {T['d'].valid_range}")
    p.add_argument("--w", type=_number("w"), help=f"{T['w'].description}: {T['w'].valid_range}")
    p.add_argument("--rs", type=_number("rs"), help=f"{T['rs'].description}: {T['rs'].valid_range}")
    end = p.add_mutually_exclusive_group()
    end.add_argument("--a-max", type=_number("a-max"), help=T["a_max"].description)
    end.add_argument("--delta-max", type=_number("delta-max"), help=T["delta_max"].description)
    end.add_argument("--p-max", type=_number("p-max"), help=T["p_max"].description)
    p.add_argument("--lambda0", type=_number("lambda0"), default=None, help="pre-stretch (default 2)")
    p.add_argument("--points", type=_integer("points"), default=200, help="approximate number of rows")
    p.add_argument("--membrane", choices=("large-stretch", "exact"), default="large-stretch",
                   help="membrane model: the paper's large-stretch closed forms (default) or the exact "
                        "neo-Hookean membrane (lambda0 then matters)")
    p.add_argument("-o", "--output", type=Path, help="write the history as CSV")
    p.add_argument("--json", action="store_true", help="print the summary as one JSON object")
    p.add_argument("--plot", type=Path, help="write a plot of the history (PNG, PDF, SVG)")
    p.add_argument("--scene", type=Path, help="physical input: a scene file (DESIGN.md A3)")


def _fit_parser(sub) -> None:
    from .fitting.cli_support import add_fit_arguments  # noqa: PLC0415 - keeps simulate light
    add_fit_arguments(sub)


def _run_simulate(args) -> int:
    from .simulation import simulate  # noqa: PLC0415
    if args.scene is not None:
        kwargs, scene = _scene_kwargs(args)
    else:
        scene = None
        missing = [n for n in ("control", "slip", "w", "rs") if getattr(args, n) is None]
        if missing:
            raise _Usage(f"adhfit simulate: --{missing[0]} is required (or give --scene)")
        kwargs = {"control": args.control, "slip": args.slip, "p": args.p, "d": args.d, "w": args.w,
                  "rs": args.rs, "a_max": args.a_max, "delta_max": args.delta_max,
                  "p_max": args.p_max, "lambda0": 2.0 if args.lambda0 is None else args.lambda0}
    result = simulate(**kwargs, points=args.points, membrane=args.membrane)
    if args.output is not None:
        _write_csv(result.frame, args.output)
    if args.plot is not None:
        from .report.plots import plot_history  # noqa: PLC0415
        plot_history(result, scene=scene, path=args.plot)
    if args.json:
        print(json.dumps(result.summary, allow_nan=False))
    return 0


def _scene_kwargs(args):
    from .scene import load_scene  # noqa: PLC0415
    for name in ("control", "p", "d", "w", "rs", "lambda0"):
        if getattr(args, name) is not None:
            raise _Usage(f"adhfit simulate: --{name} cannot be combined with --scene (the scene sets it)")
    scene = load_scene(args.scene)
    kwargs = scene.to_dimensionless(slip=args.slip)
    given = {k: v for k, v in (("a_max", args.a_max), ("delta_max", args.delta_max),
                               ("p_max", args.p_max)) if v is not None}
    if given:
        for k in ("a_max", "delta_max", "p_max"):
            kwargs.pop(k, None)
        kwargs.update(given)
    elif not any(k in kwargs for k in ("a_max", "delta_max", "p_max")):
        raise _Usage("adhfit simulate: give a loading end (--a-max, --delta-max or --p-max) or set "
                     "[test] contact_radius_max / displacement_max / pressure_max in the scene")
    return kwargs, scene


def _write_csv(frame, path: Path) -> None:
    out = frame.copy()
    out["stable"] = out["stable"].map({True: "true", False: "false"})
    path.parent.mkdir(parents=True, exist_ok=True)
    out.to_csv(path, index=False, float_format="%.17g", na_rep="")


def _build_parser() -> _Parser:
    parser = _Parser(prog="adhfit", description="Adhesion tests with an inflated elastic membrane.")
    from . import __version__  # noqa: PLC0415
    parser.add_argument("--version", action="version", version=f"adhfit {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, parser_class=_Parser)
    _simulate_parser(sub)
    try:
        _fit_parser(sub)
    except ImportError:  # fitting not installed in this build
        pass
    return parser


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``adhfit`` console script; returns the exit status."""
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
        print(f"adhfit: {err}".replace("\n", " "), file=sys.stderr)
        return EXIT_FAILED
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


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
