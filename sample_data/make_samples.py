"""Write the synthetic sample curves of sample_data/ (seeded; rerun to reproduce them byte for byte).

    python sample_data/make_samples.py            # from the repository root

Each case directory gets ``curve.csv`` (docs/contracts.md A4, physical units), ``scene.toml`` (A3, with
``slip = "auto"`` and neither μh nor W_ad: they are what a fit estimates) and ``truth.json`` (the
parameters, noise and offsets used).  See README.md in this directory.
"""
from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np

from adhfit.synthetic import synthetic_curve
from adhfit.scene import Scene

HERE = Path(__file__).resolve().parent
SEED = 20240611
NOISE = 0.005  # force noise: 0.5 % of the force at the end of loading
ROWS = 200

#: name -> scene fields, true parameters, loading end (m or Pa), offset of the measured control value
CASES = {
    # the paper's FEA set (section 4): beta = 1 mm, lambda0 = 2 (b = 2 mm), mu h = 2 N/m, R_s = 1 mm,
    # W_ad = 0.4 J/m^2; 1.2 kPa under displacement control, gap 0 under pressure control
    "fea_displacement": ({"membrane_radius": "2 mm", "substrate_radius": "1 mm", "control": "displacement",
                          "pressure": "1.2 kPa"}, 0.4, 2.0, 0.6e-3, 23.7e-6),
    "fea_pressure": ({"membrane_radius": "2 mm", "substrate_radius": "1 mm", "control": "pressure",
                      "gap": "0 mm"}, 0.4, 2.0, 1.6e3, 0.0),
    # a flat substrate, other material values
    "flat_displacement": ({"membrane_radius": "2 mm", "substrate_radius": "inf", "control": "displacement",
                           "pressure": "1.0 kPa"}, 0.3, 1.5, 0.4e-3, -41.0e-6),
    "flat_pressure": ({"membrane_radius": "2 mm", "substrate_radius": "inf", "control": "pressure",
                       "gap": "0.2 mm"}, 0.3, 1.5, 1.2e3, 0.0),
}


def _toml(fields: dict) -> str:
    rs = fields["substrate_radius"]
    fixed = (f'pressure = "{fields["pressure"]}"        # the fixed pressure' if "pressure" in fields
             else f'gap = "{fields["gap"]}"               # the fixed gap, clamped edge to substrate apex')
    return (f'# synthetic sample (sample_data/make_samples.py); mu_h and W_ad are left to the fit\n'
            f'[membrane]\nradius = "{fields["membrane_radius"]}"\nprestretch = 2.0\nmodel = "large-stretch"       # the curves were made with the large-stretch model\n\n'
            f'[substrate]\nradius = "{rs}"\n\n[test]\ncontrol = "{fields["control"]}"\n{fixed}\n\n'
            f'[interface]\nslip = "auto"\n')


def _csv(curve, control: str) -> str:
    head = "time [s],displacement [um],force [mN]" if control == "displacement" else \
        "time [s],pressure [kPa],force [mN]"
    k = 1e6 if control == "displacement" else 1e-3
    t = np.arange(len(curve.x)) * 0.5
    rows = [f"{ti:.1f},{xi * k:.4f},{fi * 1e3:.6f}" for ti, xi, fi in zip(t, curve.x, curve.force)]
    return "\n".join([head, *rows]) + "\n"


def main() -> None:
    rng = np.random.default_rng(SEED)
    for name, (fields, w_ad, mu_h, x_max, x_offset) in CASES.items():
        scene = Scene(**fields)
        for slip in ("no-slip", "frictionless"):
            curve, truth = synthetic_curve(scene, slip, work_of_adhesion=w_ad, mu_h=mu_h, x_max=x_max,
                                           rows=ROWS, noise=NOISE, x_offset=x_offset, rng=rng)
            out = HERE / f"{name}_{slip}"
            out.mkdir(exist_ok=True)
            (out / "curve.csv").write_text(_csv(curve, scene.control), encoding="utf-8")
            (out / "scene.toml").write_text(_toml(fields), encoding="utf-8")
            offset_key = "displacement_offset" if scene.control == "displacement" else "pressure_offset"
            doc = {"synthetic": True, "generator": "adhfit.synthetic.synthetic_curve", "seed": SEED,
                   "slip": slip, "work_of_adhesion": w_ad, "mu_h": mu_h, offset_key: x_offset,
                   "force_offset": 0.0, "noise_sigma_N": truth["sigma"], "noise_fraction_of_f_max": NOISE,
                   "loading_end": x_max, "loading_end_unit": "m" if scene.control == "displacement" else "Pa",
                   "rows": len(curve.x), "first_detached_row": truth["i_jump"],
                   "turning_point": {"x": truth["x_turning_point"], "force_N": truth["force_turning_point"]},
                   "note": "offset convention: true value = measured value + offset"}
            (out / "truth.json").write_text(json.dumps(doc, indent=2) + "\n", encoding="utf-8")
            print(f"{out.name}: {len(curve.x)} rows, sigma = {truth['sigma'] * 1e3:.4g} mN")


if __name__ == "__main__":
    main()
