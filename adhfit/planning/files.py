"""The files of a plan: DIR/plan.json (docs/contracts.md A8), DIR/report.html and DIR/scene.toml (the
recommended protocol, ready for ``adhfit simulate --scene`` and ``adhfit fit --scene``)."""
from __future__ import annotations

import json
import math
from pathlib import Path

from ..report.files import write_text
from ..report.plan_page import write_plan_page

__all__ = ["write_plan", "scene_toml"]


def _finite(obj):
    """JSON without NaN or infinity: those become null."""
    if isinstance(obj, float):
        return obj if math.isfinite(obj) else None
    if isinstance(obj, dict):
        return {k: _finite(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_finite(v) for v in obj]
    return obj


def scene_toml(protocol, entry: dict, inputs: dict) -> str:
    """The scene file of a protocol (docs/contracts.md A3), with the plan's numbers as comments."""
    sc = protocol.scene
    s = entry["settings"]
    rs = "inf" if math.isinf(sc.substrate_radius) else f"{sc.substrate_radius:.9g} m"
    # the control value the machine is programmed to (a contact-radius end converted, as the plan did)
    x_max = s.get("control_max", protocol.end_value)
    end = ("displacement_max", f"{x_max:.9g} m") if sc.control == "displacement" else ("pressure_max", f"{x_max:.9g} Pa")
    note = (f"  # contact radius {protocol.end_value:g} b = {protocol.end_value * sc.membrane_radius:.4g} m "
            f"({inputs['slips'][0]})" if protocol.end == "a_max" else "")
    fixed = (f'pressure = "{sc.pressure:.9g} Pa"          # the fixed pressure' if sc.control == "displacement"
             else f'gap = "{sc.gap:.9g} m"               # the fixed gap')
    w = entry["ci95_width"]["work_of_adhesion"]
    p = ", ".join(f"{k} {v:.3f}" for k, v in entry["p_slip_decided"].items())
    return "\n".join([
        "# the protocol adhfit plan recommends (docs/planning.md)",
        f"# run it with {s['rows']} rows (loading and unloading), force noise {100 * s['noise']:.3g} % of the peak force:",
        f"# expected 95 % width of W_ad {w:.3g} J/m^2 ({100 * w / inputs['work_of_adhesion']:.3g} %); "
        f"P(slip decided): {p}",
        "[membrane]", f'radius = "{sc.membrane_radius:.9g} m"', f"prestretch = {sc.prestretch:.9g}",
        f'model = "{sc.membrane_model}"', "",
        "[substrate]", f'radius = "{rs}"', "",
        "[test]", f'control = "{sc.control}"', fixed, f'{end[0]} = "{end[1]}"{note}', "",
        "[interface]", 'slip = "auto"', ""])


def write_plan(plan, outdir: Path) -> dict:
    """Write the plan's files into ``outdir`` (created); returns name -> path."""
    outdir.mkdir(parents=True, exist_ok=True)
    data = _finite(plan.to_dict())
    out = {"plan.json": outdir / "plan.json", "report.html": outdir / "report.html"}
    write_text(out["plan.json"], json.dumps(data, indent=1, allow_nan=False) + "\n")
    write_plan_page(data, out["report.html"])
    if plan.recommended is not None:
        out["scene.toml"] = outdir / "scene.toml"
        write_text(out["scene.toml"], scene_toml(plan.protocol(plan.recommended), plan.protocols[plan.recommended],
                                                 plan.inputs))
    elif (outdir / "scene.toml").exists():  # a stale recommendation of an earlier plan must not stay
        (outdir / "scene.toml").unlink()
    return out
