"""``adhfit plan`` (docs/contracts.md A8): parse, call :func:`adhfit.planning.plan`, write the files, print
where they are and what is recommended."""
from __future__ import annotations

__all__ = ["run_plan"]


def run_plan(args) -> int:
    """Run one plan from parsed arguments; returns the exit status (0)."""
    from ..errors import InputError  # noqa: PLC0415
    from ..planning.api import plan  # noqa: PLC0415 - lmfit and the engine load only here
    if args.global_k is not None and args.global_k < 2:
        raise InputError("--global", args.global_k, "an integer >= 2 (curves in the series)",
                         "Leave --global out for one test.")
    result = plan(args.scene, work_of_adhesion=args.work_of_adhesion, mu_h=args.mu_h, noise=args.noise,
                  slip=args.slip, rows=args.rows, a_max=args.a_max, delta_max=args.delta_max,
                  pressure_max=args.pressure_max, vary=args.vary, global_k=args.global_k,
                  target_precision=args.target_precision, membrane=args.membrane, workers=args.workers,
                  radius_noise=args.radius_noise)
    files = result.write(args.output)
    n = len(result.protocols)
    inside = sum(bool(e["in_domain"]) for e in result.protocols)
    print(f"{n} protocol(s), {inside} inside the model's domain.")
    if result.recommended is not None:
        print(f"recommended: protocol {result.recommended}: {result.why}")
    else:
        print(f"no recommendation: {result.why}")
    if result.series is not None:
        print(f"series: {result.series['why']}")
    for name, path in files.items():
        print(f"wrote {path}")
    return 0
