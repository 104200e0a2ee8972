"""Candidate test protocols of a plan: the settings a lab chooses, checked, and the grid of them.

A protocol is one scene (geometry, control mode, the fixed pressure or gap), a loading end, a number of
rows and a force noise level (docs/contracts.md A8).  ``--vary NAME=LO:HI[:K]`` spans one or two of
these settings on an evenly spaced grid of K values each; every other setting is the scene's.
"""
from __future__ import annotations

import dataclasses
import itertools
import math
from dataclasses import dataclass

import numpy as np

from ..errors import InputError
from ..scene import Scene
from ..units import parse_quantity

__all__ = ["Protocol", "Setting", "SETTINGS", "END_NAMES", "parse_vary", "grid", "check_noise", "check_rows",
           "DEFAULT_K", "MAX_POINTS"]

#: values per varied setting when ``:K`` is not given
DEFAULT_K = 8
#: largest number of protocols one plan evaluates (K1 x K2)
MAX_POINTS = 2500
#: the loading ends a protocol may have (``a_max`` dimensionless, the others SI)
END_NAMES = ("a_max", "displacement_max", "pressure_max")


@dataclass(frozen=True)
class Setting:
    """One setting ``--vary`` can span.

    Attributes
    ----------
    name : str
    dimension : str or None
        A key of :data:`adhfit.units.DIMENSIONS` (values may carry units), or None (a plain number).
    unit : str
        The SI unit (or "" / "rows" / "fraction") reported in plan.json.
    lower, upper : float
        The valid range (open at a bound that is a strict inequality; see :meth:`check`).
    control : str or None
        The control mode the setting belongs to (None: both).
    description : str
    """

    name: str
    dimension: str | None
    unit: str
    lower: float
    upper: float
    control: str | None
    description: str

    def check(self, value: float, flag: str = "--vary") -> float:
        """``value`` when it lies in the valid range; else an :class:`InputError` naming the flag."""
        if not (math.isfinite(value) and self.lower < value <= self.upper):
            raise InputError(f"{flag} {self.name}", value, self.valid)
        return float(value)

    @property
    def valid(self) -> str:
        unit = f" {self.unit}" if self.unit not in ("", "fraction", "rows") else ""
        kind = "an integer" if self.name == "rows" else "a number"
        return f"{kind} in ({self.lower:g}, {self.upper:g}]{unit} ({self.description})"


#: every setting a plan can vary (a dict literal: the one registry)
SETTINGS: dict[str, Setting] = {
    "pressure": Setting("pressure", "pressure", "Pa", -1e7, 1e7, "displacement",
                        "the fixed pressure of a displacement-control test"),
    "gap": Setting("gap", "length", "m", -1.0, 1.0, "pressure", "the fixed gap of a pressure-control test"),
    "a_max": Setting("a_max", None, "", 0.0, 0.95, None, "contact radius over b at the end of loading"),
    "displacement_max": Setting("displacement_max", "length", "m", 0.0, 1.0, "displacement",
                                "largest contact displacement on loading"),
    "pressure_max": Setting("pressure_max", "pressure", "Pa", 0.0, 1e7, "pressure",
                            "largest pressure on loading"),
    "rows": Setting("rows", None, "rows", 19.0, 100_000.0, None, "rows of the whole test"),
    "noise": Setting("noise", None, "fraction", 0.0, 1.0, None, "force noise over the peak force"),
}
_ALIASES = {"delta_max": "displacement_max", "p_max": "pressure_max", "points": "rows", "sigma": "noise"}


def check_noise(value: float, flag: str = "--noise") -> float:
    """A force noise fraction in (0, 1]."""
    if not (isinstance(value, (int, float)) and math.isfinite(value) and 0.0 < value <= 1.0):
        what = "the largest contact radius" if "radius" in flag else "the peak force"
        raise InputError(flag, value, f"a fraction of {what} in (0, 1], e.g. 0.02 or 2%",
                         "A plan needs noise: with none every protocol decides everything.")
    return float(value)


def check_rows(value: float, flag: str = "--rows") -> int:
    """A row count in [20, 100000]."""
    if not (isinstance(value, (int, float)) and math.isfinite(value) and 20 <= value <= 100_000
            and float(value) == int(value)):
        raise InputError(flag, value, "an integer in [20, 100000] (rows of the whole test)")
    return int(value)


@dataclass(frozen=True)
class Protocol:
    """One candidate test.

    Attributes
    ----------
    scene : Scene
        Geometry, control mode and the fixed pressure (Pa) or gap (m).
    end : str
        One of :data:`END_NAMES`.
    end_value : float
        ``a_max`` dimensionless; ``displacement_max`` m; ``pressure_max`` Pa.
    rows : int
    noise : float
        Force noise σ over the peak force.
    invalid : tuple
        ``(setting, value, message)`` when the scene cannot take the value (e.g. a gap that keeps the
        membrane off the substrate): the protocol is then outside the model's domain, ``scene`` keeps
        the last valid value and the settings show the requested one.
    """

    scene: Scene
    end: str
    end_value: float
    rows: int
    noise: float
    invalid: tuple = ()

    def value(self, name: str) -> float:
        """The value of a setting (SI), for the maps."""
        if self.invalid and self.invalid[0] == name:
            return float(self.invalid[1])
        if name in ("pressure", "gap"):
            return float(getattr(self.scene, name))
        if name in END_NAMES:
            return float(self.end_value) if name == self.end else math.nan
        return float(getattr(self, name))

    def settings(self) -> dict:
        """plan.json ``settings`` (SI)."""
        sc = self.scene
        out = {"control": sc.control}
        out["pressure" if sc.control == "displacement" else "gap"] = float(
            sc.pressure if sc.control == "displacement" else sc.gap)
        out[self.end] = float(self.end_value)
        if self.end == "a_max":
            out["contact_radius_max"] = float(self.end_value * sc.membrane_radius)
        out.update(rows=int(self.rows), noise=float(self.noise))
        if self.invalid:
            out[self.invalid[0]] = float(self.invalid[1])
        return out

    def replace(self, name: str, value: float) -> "Protocol":
        """This protocol with one setting changed."""
        if name in ("pressure", "gap"):
            try:
                return dataclasses.replace(self, scene=dataclasses.replace(self.scene, **{name: float(value)}))
            except InputError as err:  # outside the scene's domain: kept as a protocol the model cannot run
                return dataclasses.replace(self, invalid=(name, float(value), str(err)))
        if name in END_NAMES:
            return dataclasses.replace(self, end=name, end_value=float(value))
        if name == "rows":
            return dataclasses.replace(self, rows=int(round(value)))
        return dataclasses.replace(self, noise=float(value))


def _split_unit(text: str) -> tuple[str, str]:
    """'2kPa' -> ('2', 'kPa'); '0.5' -> ('0.5', '')."""
    text = text.strip()
    k = len(text)
    while k > 0 and not (text[k - 1].isdigit() or text[k - 1] == "."):
        k -= 1
    return text[:k].strip(), text[k:].strip()


def _number(setting: Setting, text: str, unit: str, spec: str) -> float:
    num, own = _split_unit(text)
    unit = own or unit
    try:
        if setting.dimension is None:
            if unit == "%" and setting.name == "noise":
                return float(num) / 100.0
            if unit:
                raise ValueError(unit)
            return float(num)
        return parse_quantity(f"{num} {unit}" if unit else float(num), setting.dimension, name=f"--vary {setting.name}")
    except (ValueError, InputError):
        raise InputError(f"--vary {setting.name}", spec, f"LO:HI[:K] with {setting.valid}",
                         "Write e.g. --vary pressure=0.5:2kPa:10,a_max=0.1:0.4.") from None


def parse_vary(text: str | dict | None, control: str) -> dict[str, tuple[float, float, int]]:
    """``NAME=LO:HI[:K],...`` (or a dict NAME -> (lo, hi[, k])) -> {name: (lo, hi, k)}, SI, checked.

    At most two settings; LO < HI; 2 <= K <= 50 (K = 1 needs LO == HI: give the value in the scene instead).
    """
    if text is None or text == "" or text == {}:
        return {}
    items = text.items() if isinstance(text, dict) else \
        [part.partition("=")[::2] for part in filter(None, (p.strip() for p in str(text).split(",")))]
    out: dict = {}
    for raw_name, spec in items:
        name = _ALIASES.get(str(raw_name).strip().replace("-", "_"), str(raw_name).strip().replace("-", "_"))
        if name not in SETTINGS:
            raise InputError("--vary", raw_name, "one of " + ", ".join(SETTINGS),
                             "Write e.g. --vary pressure=0.5:2kPa,a_max=0.1:0.4.")
        s = SETTINGS[name]
        if s.control is not None and s.control != control:
            raise InputError(f"--vary {name}", spec, f"a setting of {control} control (the scene's)",
                             f"{name} belongs to {s.control} control; change [test] control in the scene.")
        if isinstance(spec, (tuple, list)):
            parts = list(spec)
            lo, hi = float(parts[0]), float(parts[1])
            k = int(parts[2]) if len(parts) > 2 else DEFAULT_K
        else:
            parts = str(spec).split(":")
            if len(parts) not in (2, 3) or not all(p.strip() for p in parts):
                raise InputError(f"--vary {name}", spec, "LO:HI or LO:HI:K",
                                 "Write e.g. --vary pressure=0.5:2kPa:10.")
            unit = _split_unit(parts[1])[1]
            lo, hi = _number(s, parts[0], unit, spec), _number(s, parts[1], unit, spec)
            try:
                k = int(parts[2]) if len(parts) == 3 else DEFAULT_K
            except ValueError:
                raise InputError(f"--vary {name}", spec, "LO:HI:K with K an integer in [2, 50]") from None
        if not lo < hi:
            raise InputError(f"--vary {name}", spec, f"LO < HI, both {s.valid}",
                             "An impossible range: swap the ends or widen it.")
        s.check(lo, f"--vary {name}")
        s.check(hi, f"--vary {name}")
        if name == "noise" and lo <= 0.0:
            check_noise(lo, "--vary noise")
        if name == "rows":
            check_rows(math.ceil(lo), "--vary rows")
        if not 2 <= k <= 50:
            raise InputError(f"--vary {name}", spec, "LO:HI:K with K an integer in [2, 50]")
        out[name] = (lo, hi, k)
    if len(out) > 2:
        raise InputError("--vary", text, "at most two settings (a map is two-dimensional)")
    ends = [n for n in out if n in END_NAMES]
    if len(ends) > 1:
        raise InputError("--vary", text, "at most one loading end (a_max, displacement_max or pressure_max)")
    if math.prod(k for _, _, k in out.values()) > MAX_POINTS:
        raise InputError("--vary", text, f"at most {MAX_POINTS} protocols in all (K1 x K2)")
    return out


def grid(base: Protocol, vary: dict) -> tuple[list[Protocol], list[np.ndarray]]:
    """Every protocol of the grid (the first varied setting slowest) and the axes' values."""
    axes = []
    for name, (lo, hi, k) in vary.items():
        values = np.linspace(lo, hi, k)
        if name == "rows":
            values = np.unique(np.round(values).astype(int)).astype(float)
        axes.append(values)
    out = []
    for combo in itertools.product(*axes):
        p = base
        for name, v in zip(vary, combo):
            p = p.replace(name, float(v))
        out.append(p)
    return out, axes
