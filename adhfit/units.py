"""The one place where physical units become dimensionless groups and back.

Physical inputs (scene files, CSV headers, keyword overrides) are parsed here with one pint
registry and reduced to plain SI floats; :class:`Scales` then maps SI values to the dimensionless
groups of docs/contracts.md A1 (paper section 5) and back.  Nothing else in adhfit converts units.
"""
from __future__ import annotations

import math
import re
from dataclasses import dataclass
from functools import lru_cache
from typing import TYPE_CHECKING, Any, NoReturn

import numpy as np

from .errors import DataError, InputError, clip, shown

if TYPE_CHECKING:
    import pint

__all__ = ["ureg", "registry", "DIMENSIONS", "GROUPS", "Scales", "parse_quantity",  # noqa: F822 (ureg: __getattr__)
           "unit_factor", "is_unit", "MAX_UNIT_CHARS", "MAX_VALUE_CHARS"]

#: Longest unit expression parsed, in characters.  The longest real ones ('kilogram_force / centimeter
#: ** 2') have ~30; pint's parser takes time quadratic in the length (a 10^6-character unit: hours).
MAX_UNIT_CHARS = 64
#: Longest value string (number and unit, e.g. ``"1.2 kPa"``) parsed, in characters.
MAX_VALUE_CHARS = 100


@lru_cache(maxsize=1)
def registry() -> pint.UnitRegistry:
    """The package's single unit registry, made on first use (``ureg`` is the same object).

    pint parses its definitions file on every new registry (~0.2 s); with ``cache_folder=":auto:"``
    it keeps the parsed definitions in the user's cache folder and a later process loads them in
    ~10 ms.  Where that folder cannot be written the registry is built without the cache.
    Create no other registry: quantities from two registries do not mix.
    """
    import pint  # noqa: PLC0415 - pint loads only when a unit is parsed
    try:
        return pint.UnitRegistry(cache_folder=":auto:")
    except OSError:
        return pint.UnitRegistry()


def __getattr__(name: str) -> Any:  # ``adhfit.units.ureg``, made on first use
    if name == "ureg":
        return registry()
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")

#: Physical dimensions adhfit accepts: key -> (pint dimensionality, noun phrase, example).
#: ``energy_per_area`` (W_ad) and ``force_per_length`` (mu h) share a dimensionality; they differ
#: only in how errors describe them.
DIMENSIONS: dict[str, tuple[str, str, str]] = {
    "length": ("[length]", "a length", "2 mm"),
    "pressure": ("[pressure]", "a pressure", "1.2 kPa"),
    "force": ("[force]", "a force", "1 mN"),
    "energy_per_area": ("[energy] / [area]", "an energy per area", "0.4 J/m^2"),
    "force_per_length": ("[force] / [length]", "a force per length", "2 N/m"),
    "time": ("[time]", "a time", "1 s"),
    "dimensionless": ("[]", "a dimensionless number", "2.0"),
}

_NUMBER = re.compile(r"^\s*([+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?|[+-]?inf(?:inity)?)\s*(.*?)\s*$",
                     re.IGNORECASE)


def _fail(message: str, name: str, value: Any, valid: str, where: str | None) -> NoReturn:
    """Raise a DataError (inside a file) or an InputError (a Python argument)."""
    if where is not None:
        raise DataError(f"{name} must be {valid}, got {shown(value)}. {message}".rstrip(), path=where)
    raise InputError(name, value, valid, message)


def _dimension(dimension: str) -> tuple[str, str, str]:
    if dimension not in DIMENSIONS:
        raise InputError("dimension", dimension, "one of " + ", ".join(map(repr, DIMENSIONS)))
    return DIMENSIONS[dimension]


def _unit_quantity(text: str) -> pint.Quantity:
    """Parse a unit expression ('kPa', 'J/m^2', '1e-3 N'); raise ValueError if pint cannot."""
    if len(text) > MAX_UNIT_CHARS:
        raise ValueError(f"{len(text):,} characters, longer than the {MAX_UNIT_CHARS} a unit may have")
    if "," in text or "#" in text:
        # pint would read '1,2 kPa' as 12 kPa and drop '# ...' silently.
        raise ValueError("commas and '#' are not allowed in units")
    try:
        q = registry().Quantity(text)
        q.to_base_units()
    except Exception as exc:  # pint raises many unrelated types (TokenError, AssertionError, ...)
        raise ValueError(str(exc) or type(exc).__name__) from exc
    return q


def parse_quantity(value: Any, dimension: str, *, name: str, where: str | None = None,
                   allow_inf: bool = False) -> float:
    """Return ``value`` in SI units as a float.

    Parameters
    ----------
    value : float, int or str
        A plain number, taken to be in SI units already, or a string with a unit such as
        ``"2 mm"``, ``"1.2 kPa"``, ``"0.4 J/m^2"``.  ``"inf"`` is accepted when ``allow_inf``.
    dimension : str
        One of the keys of :data:`DIMENSIONS` (``"length"``, ``"pressure"``, ...).
    name : str
        How the user knows the value (keyword or file key, e.g. ``"[membrane] radius"``); every
        error names it.
    where : str, optional
        File the value came from.  If given, errors are :class:`DataError` with that path,
        otherwise :class:`InputError`.
    allow_inf : bool
        Accept ``+inf`` (a flat substrate's radius).  NaN and ``-inf`` are always refused.

    Returns
    -------
    float
        The magnitude in SI base units (m, Pa, N, J/m^2 = N/m, s).

    Raises
    ------
    InputError, DataError
        The value is not a number or a string with a unit of the requested dimension.
    """
    dim, noun, example = _dimension(dimension)
    valid = f"{noun} (e.g. '{example}')" + (" or 'inf'" if allow_inf else "")
    if isinstance(value, bool) or not isinstance(value, (int, float, str, np.integer, np.floating)):
        _fail("", name, value, valid, where)
    if isinstance(value, str):
        if len(value) > MAX_VALUE_CHARS:
            _fail(f"It has {len(value):,} characters; a value with its unit has at most {MAX_VALUE_CHARS}.",
                  name, value, valid, where)
        if "," in value:
            _fail("Use a decimal point, not a comma, and one value only.", name, value, valid, where)
        match = _NUMBER.match(value)
        if match is None:
            _fail("It must start with a number.", name, value, valid, where)
        number, unit = float(match.group(1)), match.group(2)
        if unit:
            try:
                q = _unit_quantity(unit)
            except ValueError as exc:
                _fail(f"Unit '{clip(unit)}' is not understood ({clip(str(exc))}).", name, value, valid, where)
            if not q.check(dim):
                _fail(f"Unit '{clip(unit)}' is not {noun}.", name, value, valid, where)
            si = number * float(q.to_base_units().magnitude)
        elif dimension == "dimensionless" or math.isinf(number):
            si = number
        else:
            _fail("It has no unit: write e.g. "
                  f"'{example}', or a plain number (not a string) in SI units.", name, value, valid, where)
    else:
        si = float(value)
    if math.isnan(si):
        _fail("", name, value, valid, where)
    if math.isinf(si) and not (allow_inf and si > 0):
        _fail("Infinite values are not allowed here.", name, value, valid, where)
    return si


def is_unit(text: str) -> bool:
    """Whether ``text`` is a unit pint understands (``mm``, ``kN``, ``sec``); a guess, so never an error.

    Numbers count as units here (``"1e-3 N"`` is one); callers that look for unit names exclude them.
    Text longer than :data:`MAX_UNIT_CHARS` is not a unit.
    """
    try:
        _unit_quantity(text)
    except ValueError:
        return False
    return True


def unit_factor(unit: str, dimension: str, *, name: str, where: str | None = None) -> float:
    """Return the factor that converts a value in ``unit`` to SI (``unit_factor('mN', 'force') == 1e-3``).

    Parameters
    ----------
    unit : str
        A unit expression pint understands (``"um"``, ``"kPa"``, ``"1e-3 N"``).
    dimension : str
        Key of :data:`DIMENSIONS` the unit must have.
    name : str
        What the unit belongs to (e.g. ``"column 'force [mN]'"``), for error messages.
    where : str, optional
        File concerned: errors are then :class:`DataError` with that path.

    Raises
    ------
    InputError, DataError
        ``"unit kPa is not a force"`` and the like.
    """
    dim, noun, example = _dimension(dimension)
    try:
        q = _unit_quantity(unit)
    except ValueError as exc:
        msg = (f"unit '{clip(unit)}' is not understood ({clip(str(exc))}); expected {noun} such as "
               f"'{example.split()[-1]}'")
        if where is not None:
            raise DataError(msg, path=where, column=name) from None
        raise InputError(name, unit, f"a unit of {noun}", msg) from None
    if not q.check(dim):
        msg = f"unit {clip(unit)} is not {noun} (e.g. '{example.split()[-1]}')"
        if where is not None:
            raise DataError(msg, path=where, column=name)
        raise InputError(name, unit, f"a unit of {noun}", msg)
    factor = float(q.to_base_units().magnitude)
    if not (math.isfinite(factor) and factor > 0.0):
        msg = f"unit '{clip(unit)}' gives a scale factor of {factor!r}"
        if where is not None:
            raise DataError(msg, path=where, column=name)
        raise InputError(name, unit, "a unit with a finite positive scale", msg)
    return factor


#: Dimensionless groups of docs/contracts.md A1 -> the Scales attribute that makes them dimensional.
GROUPS: dict[str, str] = {
    "p": "pressure", "p_max": "pressure",
    "d": "length", "delta": "length", "delta_max": "length", "a": "length", "a_max": "length",
    "rs": "length",
    "f": "force",
    "w": "energy", "G": "energy",
}


def _scale(x: Any, factor: float) -> Any:
    arr = np.asarray(x, dtype=float) * factor
    return float(arr) if arr.ndim == 0 else arr


@dataclass(frozen=True)
class Scales:
    """Scales of the dimensionless groups (docs/contracts.md A1, paper section 5).

    Parameters
    ----------
    b : float
        Clamped membrane radius after pre-stretch, m.
    mu_h : float
        Membrane stiffness μh (shear modulus times undeformed thickness), N/m.

    Notes
    -----
    length = b (m), force = 2 μh b (N), pressure = 2 μh / b (Pa), energy = μh (J/m^2).
    Every ``to_*`` method takes SI values (floats or arrays) and returns the group; every
    ``from_*`` does the reverse.  Arrays stay arrays, scalars come back as floats.
    """

    b: float
    mu_h: float

    def __post_init__(self) -> None:
        for key in ("b", "mu_h"):
            v = getattr(self, key)
            if isinstance(v, bool) or not isinstance(v, (int, float, np.integer, np.floating)) \
                    or not (math.isfinite(v) and v > 0):
                raise InputError(key, v, "a finite positive number (SI units)")
            object.__setattr__(self, key, float(v))

    @property
    def length(self) -> float:
        """Length scale b, m."""
        return self.b

    @property
    def force(self) -> float:
        """Force scale 2 μh b, N."""
        return 2.0 * self.mu_h * self.b

    @property
    def pressure(self) -> float:
        """Pressure scale 2 μh / b, Pa."""
        return 2.0 * self.mu_h / self.b

    @property
    def energy(self) -> float:
        """Energy-per-area scale μh, J/m^2."""
        return self.mu_h

    def scale_of(self, group: str) -> float:
        """SI value of one unit of the dimensionless ``group`` (a key of :data:`GROUPS`)."""
        if group not in GROUPS:
            raise InputError("group", group, "one of " + ", ".join(map(repr, GROUPS)))
        return getattr(self, GROUPS[group])

    def to_dimensionless(self, group: str, value: Any) -> Any:
        """SI ``value`` -> dimensionless ``group``."""
        return _scale(value, 1.0 / self.scale_of(group))

    def to_si(self, group: str, value: Any) -> Any:
        """Dimensionless ``group`` -> SI value."""
        return _scale(value, self.scale_of(group))

    # Named helpers: one pair per A1 group.
    def to_f(self, force: Any) -> Any:
        """Force F (N, compressive positive) -> f = F / (2 μh b)."""
        return self.to_dimensionless("f", force)

    def from_f(self, f: Any) -> Any:
        """f -> force F, N."""
        return self.to_si("f", f)

    def to_p(self, pressure: Any) -> Any:
        """Pressure P (Pa) -> p = P b / (2 μh)."""
        return self.to_dimensionless("p", pressure)

    def from_p(self, p: Any) -> Any:
        """p -> pressure P, Pa."""
        return self.to_si("p", p)

    def to_d(self, gap: Any) -> Any:
        """Gap between clamped edge and substrate apex (m) -> d = gap / b."""
        return self.to_dimensionless("d", gap)

    def from_d(self, d: Any) -> Any:
        """d -> gap, m."""
        return self.to_si("d", d)

    def to_delta(self, displacement: Any) -> Any:
        """Contact displacement δ (m) -> delta = δ / b."""
        return self.to_dimensionless("delta", displacement)

    def from_delta(self, delta: Any) -> Any:
        """delta -> contact displacement δ, m."""
        return self.to_si("delta", delta)

    def to_a(self, contact_radius: Any) -> Any:
        """Contact radius (m) -> a = radius / b."""
        return self.to_dimensionless("a", contact_radius)

    def from_a(self, a: Any) -> Any:
        """a -> contact radius, m."""
        return self.to_si("a", a)

    def to_rs(self, substrate_radius: Any) -> Any:
        """Substrate radius R_s (m, ``inf`` for flat) -> rs = R_s / b."""
        return self.to_dimensionless("rs", substrate_radius)

    def from_rs(self, rs: Any) -> Any:
        """rs -> substrate radius R_s, m."""
        return self.to_si("rs", rs)

    def to_w(self, work_of_adhesion: Any) -> Any:
        """Work of adhesion W_ad (J/m^2) -> w = W_ad / μh."""
        return self.to_dimensionless("w", work_of_adhesion)

    def from_w(self, w: Any) -> Any:
        """w -> work of adhesion W_ad, J/m^2."""
        return self.to_si("w", w)

    def to_G(self, energy_release_rate: Any) -> Any:  # noqa: N802 - the paper's symbol
        """Energy release rate (J/m^2) -> G / μh."""
        return self.to_dimensionless("G", energy_release_rate)

    def from_G(self, G: Any) -> Any:  # noqa: N802,N803
        """G / μh -> energy release rate, J/m^2."""
        return self.to_si("G", G)
