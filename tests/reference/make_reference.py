"""Write tests/data/reference_states.json: 30-digit reference states and summaries at fixed inputs.

Run from the repository root::

    python -m tests.reference.make_reference            # or: python tests/reference/make_reference.py

Every input is an IEEE double and is taken at its exact binary value, i.e. the very problem the engine
is given. Values are stored as 30-significant-digit strings (null where undefined: delta for |p| > 1).
Locators are stored as doubles: the tests hand exactly these numbers to the engine.
"""
from __future__ import annotations

import argparse
import json
import platform
import sys
import time
from pathlib import Path

if __package__ in (None, ""):  # run as a script: make the repository root importable
    sys.path.insert(0, str(Path(__file__).resolve().parents[2]))

import mpmath as mp  # noqa: E402

from tests.reference import mp_model as M  # noqa: E402

OUT = Path(__file__).resolve().parents[1] / "data" / "reference_states.json"
INF = float("inf")

#: (id, control, inputs, extra pinning fractions of alpha_onset); every case runs with both slips.
CASES = [
    ("base", "displacement", dict(p=0.6, w=0.2, rs=0.5, a_max=0.25), ()),
    ("flat", "displacement", dict(p=0.6, w=0.2, rs=INF, a_max=0.25), ()),
    ("p0", "displacement", dict(p=0.0, w=0.2, rs=0.5, a_max=0.25), ()),
    ("pneg-rs0.5", "displacement", dict(p=-0.3, w=0.2, rs=0.5, a_max=0.25), ()),
    ("pneg-rs1", "displacement", dict(p=-0.3, w=0.2, rs=1.0, a_max=0.25), ()),
    ("base", "pressure", dict(d=0.0, w=0.2, rs=0.5, a_max=0.25), ()),
    ("dneg", "pressure", dict(d=-0.2, w=0.2, rs=0.5, a_max=0.25), ()),
    ("flat", "pressure", dict(d=0.1, w=0.2, rs=INF, a_max=0.25), ()),
    # w = 3: no-slip pinning passes theta_a = pi/2 (alpha > 2.498) before G = w at alpha ~ 2.643, and
    # p_m ~ 1.50 > 1 exercises delta = None. The extra fractions put pinning states on the folded branch.
    ("folded", "pressure", dict(d=0.0, w=3.0, rs=0.5, a_max=0.4), (0.95, 0.97)),
]
MC_FRACTIONS = (0.3, 0.7, 1.0)  # of a_max
PIN_FRACTIONS = (0.25, 0.6, 0.999)  # of alpha_onset (0.999: stay inside the engine's own range)
DEL_FRACTIONS = (0.999, 0.6, 0.25, 0.05)  # of a_onset (no slip: 1.0 is a_max exactly)
SUMMARY_KEYS = ("f", "delta", "p", "a")


def _s(x) -> str | None:
    """30 significant digits, or None."""
    return None if x is None else mp.nstr(x, M.DPS, min_fixed=-mp.inf, max_fixed=mp.inf)


def _json_inputs(inputs: dict) -> dict:
    out = {"p": None, "d": None}
    out.update({k: ("inf" if v == INF else v) for k, v in inputs.items()})
    return out


def _state_record(control, slip, stage, inputs, loc_name, loc) -> dict:
    st = M.state(control, slip, stage, **inputs, **{loc_name: loc})
    rec = {"stage": stage, "locator": {loc_name: loc}, "folded": st["folded"]}
    for k in ("a", "alpha", "p", "d", "delta", "f", "G", "C2", "D", "L", "theta_a"):
        rec[k] = _s(st[k])
    return rec


def _locators(h: M.History, extra_pin) -> list[tuple[str, str, float]]:
    a_max, a_on, al_on = float(h.a_max), h.a_onset, h.alpha_onset
    locs = [("making_contact", "a", a_max * fr) for fr in MC_FRACTIONS]
    locs += [("pinning", "alpha", float(al_on * fr)) for fr in sorted(PIN_FRACTIONS + tuple(extra_pin))]
    for fr in DEL_FRACTIONS:
        a = a_max if (h.no_slip and fr == 0.999) else float(a_on * fr)
        locs.append(("delamination", "a", a))
    return locs


def build_case(case_id, control, inputs, extra_pin, slip) -> dict:
    """States along one history plus its summary."""
    t0 = time.perf_counter()
    with mp.workdps(M.DPS):
        h = M.history(control, slip, **inputs)
        states = [_state_record(control, slip, st, inputs, name, loc)
                  for st, name, loc in _locators(h, extra_pin)]
        summ = M.summary(control, slip, **inputs)
        summary = {"f_max": _s(summ["f_max"])}
        for key in ("onset", "f_min", "turning_point"):
            summary[key] = {k: _s(summ[key][k]) for k in SUMMARY_KEYS}
            summary[key]["stage"] = summ[key]["stage"]
            summary[key]["alpha"] = _s(summ[key]["alpha"])
        anchors = {"p_m": _s(h.end.kap), "L_m": _s(h.L_m), "alpha_onset": _s(h.alpha_onset),
                   "a_onset": _s(h.a_onset)}
    return {"id": f"{control}-{slip}-{case_id}", "control": control, "slip": slip,
            "inputs": _json_inputs(inputs), "anchors": anchors, "states": states, "summary": summary,
            "seconds": round(time.perf_counter() - t0, 1)}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("-o", "--output", type=Path, default=OUT)
    args = ap.parse_args(argv)
    t0 = time.perf_counter()
    cases = []
    for case_id, control, inputs, extra_pin in CASES:
        for slip in M.SLIPS:
            rec = build_case(case_id, control, inputs, extra_pin, slip)
            print(f"{rec['id']:45s} {len(rec['states']):3d} states  {rec['seconds']:6.1f} s", flush=True)
            cases.append(rec)
    doc = {
        "description": "30-digit mpmath reference states and summaries of the forward model "
                       "(tests/reference/mp_model.py; adaptive tanh-sinh quadrature, no closed forms).",
        "generator": "python -m tests.reference.make_reference",
        "mpmath_version": mp.__version__,
        "dps": M.DPS,
        "python": platform.python_version(),
        "conventions": {
            "units": "dimensionless, docs/contracts.md A1 (lengths over b; f = F/(2 mu h b); w = W_ad/(mu h))",
            "inputs": "IEEE doubles taken at their exact binary value; rs 'inf' = flat substrate",
            "locators": "making_contact and delamination: a; pinning: alpha (radians)",
            "values": "strings with 30 significant digits; null where undefined (delta for |p| > 1)",
            "summary": "f_max; onset (G = w), f_min (least f) and turning_point (least delta under "
                       "displacement control, least p under pressure control) over pinning and "
                       "delamination down to a = 1e-3 a_max",
            "extras": "C2, D, L = ln(beta/rho_a), theta_a, folded (theta_a > pi/2) are diagnostics",
        },
        "seconds": round(time.perf_counter() - t0, 1),
        "cases": cases,
    }
    args.output.parent.mkdir(parents=True, exist_ok=True)
    args.output.write_text(json.dumps(doc, indent=1) + "\n")
    n = sum(len(c["states"]) for c in cases)
    print(f"wrote {args.output} ({len(cases)} cases, {n} states) in {doc['seconds']} s")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
