"""The one parameter table.

Every dimensionless model input and every fitted physical parameter is declared here once: name,
symbol, unit, default, bounds and a description. Validation, lmfit ``Parameters``, CLI help, report
labels and random draws for stress tests all read this table.

The bounds of the dimensionless groups are the domain where the model (paper sections 2-3, Case I
free inflation, contact on the upper hemisphere of the substrate) is defined and where the engine is
stress-tested; they are not the large-stretch approximation's accuracy limit (see README).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from .errors import InputError


@dataclass(frozen=True)
class Param:
    """One row of the parameter table.

    Attributes
    ----------
    name : str
        Keyword name (Python API); the CLI option is ``--`` + name with ``_`` -> ``-``.
    symbol : str
        Symbol for reports and plots.
    unit : str
        ``"1"`` for dimensionless groups, else an SI unit string pint understands.
    default : float or None
        Default value, ``None`` when the user must give one.
    lower, upper : float
        Bounds of the valid range.
    lower_open, upper_open : bool
        Whether the bound itself is excluded.
    description : str
        One line for help texts.
    """

    name: str
    symbol: str
    unit: str
    default: float | None
    lower: float
    upper: float
    lower_open: bool
    upper_open: bool
    description: str

    @property
    def valid_range(self) -> str:
        lo = "(" if self.lower_open else "["
        hi = ")" if self.upper_open else "]"
        return f"a number in {lo}{_fmt(self.lower)}, {_fmt(self.upper)}{hi}"

    def contains(self, value: float) -> bool:
        if not (isinstance(value, (int, float, np.floating, np.integer)) and not isinstance(value, bool)):
            return False
        v = float(value)
        if math.isnan(v):
            return False
        if math.isinf(v) and not (v == self.upper == math.inf and not self.upper_open):
            return False
        above = v > self.lower if self.lower_open else v >= self.lower
        below = v < self.upper if self.upper_open else v <= self.upper
        return above and below

    def check(self, value: Any, name: str | None = None) -> float:
        """Return ``value`` as a float, or raise :class:`InputError` naming the parameter."""
        if not self.contains(value):
            raise InputError(name or self.name, value, self.valid_range)
        return float(value)


def _fmt(x: float) -> str:
    if math.isinf(x):
        return "inf" if x > 0 else "-inf"
    return f"{x:g}"


def _p(name, symbol, unit, default, lower, upper, description, lower_open=True, upper_open=True):
    return Param(name, symbol, unit, default, lower, upper, lower_open, upper_open, description)


#: Dimensionless groups (docs/contracts.md A1).  Cross-parameter constraints are in ``check_scene``.
DIMENSIONLESS: dict[str, Param] = {
    "p": _p("p", "Pb/2μh", "1", None, -1.0, 1.0,
            "pressure P b/(2 mu h) = b/R (fixed under displacement control)"),
    "d": _p("d", "d/b", "1", None, -1.0, 1.0,
            "gap between clamped edge and substrate apex over b (fixed under pressure control)"),
    # below ~1e-6 the pull-off force is below ~1e-9 of the force scale: no adhesion to speak of
    "w": _p("w", "W_ad/μh", "1", None, 1e-6, 10.0, "work of adhesion over mu h",
            lower_open=False, upper_open=False),
    "rs": _p("rs", "R_s/b", "1", math.inf, 0.02, math.inf,
             "substrate radius over b; inf for a flat substrate", lower_open=False, upper_open=False),
    "a_max": _p("a_max", "a_max/b", "1", None, 1e-3, 0.95,
                "largest contact radius reached on loading, over b", lower_open=False, upper_open=False),
    "delta_max": _p("delta_max", "δ_max/b", "1", None, 0.0, 2.0,
                    "largest contact displacement reached on loading, over b"),
    "p_max": _p("p_max", "P_max b/2μh", "1", None, -1.0, 5.0,
                "largest pressure reached on loading (pressure control)"),
    "lambda0": _p("lambda0", "λ0", "1", 2.0, 1.0, 100.0, "equibiaxial pre-stretch", upper_open=False),
    "points": _p("points", "N", "1", 200, 10, 50_000, "approximate number of rows",
                 lower_open=False, upper_open=False),
}

#: Physical parameters a fit can estimate (SI).  Bounds are the fit's box.
FITTED: dict[str, Param] = {
    "work_of_adhesion": _p("work_of_adhesion", "W_ad", "J/m^2", None, 0.0, math.inf,
                           "work of adhesion"),
    "mu_h": _p("mu_h", "μh", "N/m", None, 0.0, math.inf, "membrane stiffness (shear modulus x thickness)"),
    # nuisance parameters of a measured curve (adhfit.fitting): added to the measured values
    "displacement_offset": _p("displacement_offset", "δ_0", "m", 0.0, -math.inf, math.inf,
                              "added to the measured displacement (the contact point is never known "
                              "exactly); fitted by default under displacement control"),
    "pressure_offset": _p("pressure_offset", "P_0", "Pa", 0.0, -math.inf, math.inf,
                          "added to the measured pressure (transducer zero); off by default"),
    "force_offset": _p("force_offset", "F_0", "N", 0.0, -math.inf, math.inf,
                       "added to the model force (load-cell zero at the first row); fitted by default"),
    "force_drift": _p("force_drift", "F_d", "N", 0.0, -math.inf, math.inf,
                      "linear drift of the load-cell zero from the first row to the last, added to the model "
                      "force; fitted where rows before contact and after pull-off pin it"),
}


#: How close a_max may come to the substrate's equator, as a fraction of rs (contact must stay on the
#: upper hemisphere, paper section 3.1); beyond it the edge slope diverges.
A_MAX_OVER_RS = 0.95


def check_scene(control: str, slip: str, *, p: float | None, d: float | None, w: float, rs: float,
                a_max: float | None, delta_max: float | None, p_max: float | None,
                lambda0: float, points: int) -> dict[str, float]:
    """Validate a dimensionless scene; return the checked values.

    Raises
    ------
    InputError
        Naming the first parameter that is missing, out of range, or violates a cross-parameter
        constraint (e.g. ``a_max < 0.95 rs``; ``p > -1/rs`` so that contact starts at the apex).
    """
    if control not in ("displacement", "pressure"):
        raise InputError("control", control, "one of 'displacement', 'pressure'")
    if slip not in ("no-slip", "frictionless"):
        raise InputError("slip", slip, "one of 'no-slip', 'frictionless'")
    T = DIMENSIONLESS
    out: dict[str, float] = {}
    if control == "displacement":
        if p is None:
            raise InputError("p", p, T["p"].valid_range, "Displacement control needs the fixed pressure p.")
        if d is not None:
            raise InputError("d", d, "absent under displacement control (it varies); give p instead")
        out["p"] = T["p"].check(p)
    else:
        if d is None:
            raise InputError("d", d, T["d"].valid_range, "Pressure control needs the fixed gap d.")
        if p is not None:
            raise InputError("p", p, "absent under pressure control (it varies); give d instead")
        out["d"] = T["d"].check(d)
    out["w"] = T["w"].check(w)
    out["rs"] = T["rs"].check(rs)
    out["lambda0"] = T["lambda0"].check(lambda0)
    if not isinstance(points, (int, np.integer)) or isinstance(points, bool):
        raise InputError("points", points, "an integer in [10, 50000]")
    out["points"] = int(T["points"].check(points))

    ends = {k: v for k, v in (("a_max", a_max), ("delta_max", delta_max), ("p_max", p_max)) if v is not None}
    if len(ends) != 1:
        raise InputError("a_max", a_max, "given alone",
                         "Give exactly one loading end: a_max, delta_max (displacement control) "
                         "or p_max (pressure control).")
    (end, value), = ends.items()
    if end == "delta_max" and control != "displacement":
        raise InputError("delta_max", value, "used with displacement control only; use p_max or a_max")
    if end == "p_max" and control != "pressure":
        raise InputError("p_max", value, "used with pressure control only; use delta_max or a_max")
    out[end] = T[end].check(value)

    curv = 1.0 / out["rs"] + 0.0  # + 0.0: no "-0" in messages for a flat substrate
    if end == "a_max" and out["a_max"] >= A_MAX_OVER_RS * out["rs"]:
        raise InputError("a_max", out["a_max"], f"below {A_MAX_OVER_RS:g} rs = {A_MAX_OVER_RS * out['rs']:g}",
                         "Contact must stay on the substrate's upper hemisphere.")
    if control == "displacement":
        if out["p"] + curv <= 0.0:
            raise InputError("p", out["p"], f"a number in ({_fmt(0.0 - curv)}, 1) for rs = {out['rs']:g}",
                             "The membrane must be less concave than the substrate (p > -1/rs) "
                             "for contact to start at the apex.")
    else:
        p_cr = 2.0 * out["d"] / (1.0 + out["d"] ** 2)
        if p_cr + curv <= 0.0:
            raise InputError("d", out["d"], f"such that 2d/(1+d^2) > -1/rs = {_fmt(0.0 - curv)}",
                             "Contact must start at the substrate apex.")
    return out


# --- choice lists: the one place every layer (scene file, options, command line, reports) reads them ----
#: loading modes (docs/contracts.md A1-A3)
CONTROLS = ("displacement", "pressure")
#: each loading mode's control variable: its key in a dimensionless history (δ or p)
CONTROL_KEY = {"displacement": "delta", "pressure": "p"}
#: the two interface limits of the model
SLIP_CONDITIONS = ("no-slip", "frictionless")
#: slip choices of a scene or a fit: ``auto`` fits both conditions and compares them
SLIP_CHOICES = ("auto", *SLIP_CONDITIONS)
# membrane models: adhfit.membranes.MEMBRANES (one entry each) and its membrane_choices()
#: fitting methods
METHODS = ("lsq", "mcmc")
