"""A frozen description of one test in SI units, and the TOML scene file of docs/contracts.md A3.

A :class:`Scene` holds geometry, material (μh), interface (slip, W_ad) and loading (control mode,
fixed pressure or gap, optional loading end); μh and W_ad may be left to the fit.
:meth:`Scene.to_dimensionless` gives the keyword arguments of :func:`adhfit.simulate`.
"""
from __future__ import annotations

import difflib
import functools
import re
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Mapping

import numpy as np

from .errors import DataError, InputError, clip, shown
from .membranes import membrane_choices
from .params import A_MAX_OVER_RS, CONTROLS, DIMENSIONLESS, FITTED, SLIP_CHOICES
from .units import DIMENSIONS, GROUPS, Scales, parse_quantity

__all__ = ["Scene", "load_scene", "normalize_priors", "CONTROLS", "SLIPS", "MEMBRANE_MODELS", "LAYOUT", "PRIOR_DISTS"]

#: Largest scene file read, in bytes (a scene is a few hundred bytes).
MAX_SCENE_BYTES = 1_000_000
#: Largest length a scene file may give as a plain number (read in metres, SI).  Membrane tests are
#: micrometres to centimetres; ``radius = 2`` meant 2 mm, and read as 2 m it made every later check
#: blame another setting (the pressure's unit).  A larger length is written with its unit ('0.5 m').
PLAIN_LENGTH_MAX = 0.1

SLIPS = SLIP_CHOICES
MEMBRANE_MODELS = membrane_choices()  # of a fit (docs/contracts.md A6); checked against the registry as it is

#: TOML layout (docs/contracts.md A3): section -> key -> (Scene field, dimension or None for a word).
LAYOUT: dict[str, dict[str, tuple[str, str | None]]] = {
    "membrane": {"radius": ("membrane_radius", "length"), "prestretch": ("prestretch", "dimensionless"),
                 "mu_h": ("mu_h", "force_per_length"), "model": ("membrane_model", None)},
    "substrate": {"radius": ("substrate_radius", "length")},
    "test": {"control": ("control", None), "pressure": ("pressure", "pressure"), "gap": ("gap", "length"),
             "contact_radius_max": ("contact_radius_max", "length"), "pressure_max": ("pressure_max",
             "pressure"), "displacement_max": ("displacement_max", "length")},
    "interface": {"slip": ("slip", None), "work_of_adhesion": ("work_of_adhesion", "energy_per_area")},
}
#: Scene field -> how the scene file spells it.
FILE_KEY = {fld: f"[{sec}] {key}" for sec, keys in LAYOUT.items() for key, (fld, _) in keys.items()}
_DIMENSION = {fld: dim for keys in LAYOUT.values() for fld, dim in keys.values()}

#: Large-stretch approximation (eq. 10) vs the exact neo-Hookean membrane: (λ0, relative error of the
#: free-inflation apex deflection at p = 0.6), docs/numerics.md C.
LARGE_STRETCH_ERROR = ((1.1, -0.33), (1.3, -0.15), (1.5, -0.067), (2.0, -0.012), (3.0, -0.001))

_FIXED = {"displacement": ("pressure", "gap", "the fixed pressure, e.g. '1.2 kPa'"),
          "pressure": ("gap", "pressure", "the fixed gap from clamped edge to substrate apex, e.g. '0.2 mm'")}
_ENDS = ("contact_radius_max", "displacement_max", "pressure_max")
#: Scene field -> its dimensionless group (docs/contracts.md A1), in the order simulate() lists them.
_GROUP_OF = {"pressure": "p", "gap": "d", "work_of_adhesion": "w", "substrate_radius": "rs",
             "contact_radius_max": "a_max", "displacement_max": "delta_max", "pressure_max": "p_max"}


@dataclass(frozen=True, kw_only=True)
class Scene:
    """One membrane adhesion test, in SI units (docs/contracts.md A3).

    Parameters
    ----------
    membrane_radius : float or str
        Clamped membrane radius after pre-stretch, b = λ0 β, m.
    substrate_radius : float or str
        Substrate radius R_s, m; ``inf`` for a flat substrate.
    control : {"displacement", "pressure"}
        Which quantity the test drives.
    prestretch : float
        Equibiaxial pre-stretch λ0 > 1: cancels under the large-stretch approximation, not for the exact membrane.
    mu_h : float or str, optional
        Membrane stiffness μh, N/m; ``None`` when it is to be fitted.
    pressure : float or str, optional
        Displacement control only: the fixed pressure P, Pa.
    gap : float or str, optional
        Pressure control only: the fixed gap d from the clamped edge to the substrate apex, m.
    slip : {"auto", "no-slip", "frictionless"}
        Interface slip condition; ``"auto"`` fits both and compares.
    work_of_adhesion : float or str, optional
        W_ad, J/m^2; ``None`` when it is to be fitted.
    contact_radius_max, displacement_max, pressure_max : float or str, optional
        At most one loading end for simulations: the largest contact radius (m), contact
        displacement δ (m, displacement control) or pressure (Pa, pressure control) on loading.
    membrane_model : {"auto", "large-stretch", "exact"}
        ``[membrane] model`` of a fit; ``"auto"``: exact where the data resolve the approximation's error.
    priors : dict, optional
        ``{parameter: {"dist": ..., ...}}`` for fitted parameters, see :func:`normalize_priors`.
    source : str, optional
        File the scene was read from (not compared).

    Strings with units (``"2 mm"``) are accepted for every physical value and stored as SI floats.
    Raises :class:`InputError` naming the first field missing, out of range or inconsistent.
    """

    membrane_radius: float
    substrate_radius: float
    control: str
    prestretch: float = 2.0
    mu_h: float | None = None
    pressure: float | None = None
    gap: float | None = None
    slip: str = "auto"
    work_of_adhesion: float | None = None
    contact_radius_max: float | None = None
    displacement_max: float | None = None
    pressure_max: float | None = None
    membrane_model: str = "auto"
    priors: dict[str, dict[str, Any]] = field(default_factory=dict, hash=False)
    source: str | None = field(default=None, compare=False)

    def __post_init__(self) -> None:
        set_ = functools.partial(object.__setattr__, self)  # frozen: normalise fields in place
        for key, choices in (("control", CONTROLS), ("slip", SLIPS), ("membrane_model", membrane_choices())):
            if getattr(self, key) not in choices:
                raise InputError(key, getattr(self, key), "one of " + ", ".join(map(repr, choices)))
        for key, dim in _DIMENSION.items():
            if dim is not None and getattr(self, key) is not None:
                inf_ok = key == "substrate_radius"
                set_(key, parse_quantity(getattr(self, key), dim, name=key, allow_inf=inf_ok))
        for key in ("membrane_radius", "substrate_radius", "mu_h", "work_of_adhesion"):
            v = getattr(self, key)
            if v is not None and not v > 0.0:
                noun = DIMENSIONS[_DIMENSION[key]][1].split(" ", 1)[1]
                raise InputError(key, v, f"a positive {noun} (SI units)")
        set_("prestretch", DIMENSIONLESS["lambda0"].check(self.prestretch, "prestretch"))
        self._check_fixed()
        self._check_end()
        set_("priors", normalize_priors(self.priors, prefix="priors"))

    def _check_fixed(self) -> None:
        needed, forbidden, what = _FIXED[self.control]
        if getattr(self, needed) is None:
            raise InputError(needed, None, DIMENSIONS[_DIMENSION[needed]][1],
                             f"It is required for control = '{self.control}' ({what}).")
        if getattr(self, forbidden) is not None:
            raise InputError(forbidden, getattr(self, forbidden), f"absent under control = '{self.control}'",
                             f"The {forbidden} varies in this test; give the {needed} instead ({what}).")
        if self.gap is not None:
            b, d = self.membrane_radius, self.gap / self.membrane_radius
            if not abs(d) < 1.0:
                raise InputError("gap", self.gap, f"a length in (-b, b) = (-{b:g}, {b:g}) m",
                                 "The substrate apex must lie within b of the clamped plane.")
            if 2 * d / (1 + d * d) + b / self.substrate_radius <= 0.0:
                raise InputError("gap", self.gap, "such that 2d/(1+d^2) > -b/R_s (d = gap/b)",
                                 "Contact must start at the substrate apex.")

    def _check_end(self) -> None:
        ends = [k for k in _ENDS if getattr(self, k) is not None]
        if len(ends) > 1:
            raise InputError(ends[1], getattr(self, ends[1]), "absent when another loading end is given",
                             f"Give at most one of {', '.join(_ENDS)}; got {', '.join(ends)}.")
        for key, control, other in (("displacement_max", "displacement", "pressure_max"),
                                    ("pressure_max", "pressure", "displacement_max")):
            if getattr(self, key) is not None and self.control != control:
                raise InputError(key, getattr(self, key), f"used with {control} control only",
                                 f"Use {other} or contact_radius_max.")
        b, rs = self.membrane_radius, self.substrate_radius
        if self.contact_radius_max is not None:
            hi = min(DIMENSIONLESS["a_max"].upper * b, A_MAX_OVER_RS * rs)
            if not 0.0 < self.contact_radius_max < hi:
                raise InputError("contact_radius_max", self.contact_radius_max,
                                 f"a length in (0, {hi:g}) m", f"It must stay below {A_MAX_OVER_RS:g} R_s "
                                 f"(contact on the substrate's upper hemisphere) and "
                                 f"{DIMENSIONLESS['a_max'].upper:g} b.")
        if self.displacement_max is not None:
            hi = DIMENSIONLESS["delta_max"].upper * b
            if not 0.0 < self.displacement_max < hi:
                raise InputError("displacement_max", self.displacement_max, f"a length in (0, {hi:g}) m")

    @property
    def b(self) -> float:
        """Membrane radius b, m."""
        return self.membrane_radius

    @property
    def lambda0(self) -> float:
        """Pre-stretch λ0, dimensionless."""
        return self.prestretch

    def scales(self, mu_h: float | str | None = None) -> Scales:
        """The :class:`~adhfit.units.Scales` of this scene (``mu_h`` overrides the scene's, N/m)."""
        value = self.mu_h if mu_h is None else parse_quantity(mu_h, "force_per_length", name="mu_h")
        if value is None:
            raise InputError("mu_h", None, "a positive force per length (e.g. '2 N/m')",
                             "The scene has no mu_h: pass one (e.g. the fit's current value).")
        return Scales(self.membrane_radius, value)

    def to_dimensionless(self, mu_h: float | str | None = None, work_of_adhesion: float | str | None = None,
                         *, slip: str | None = None) -> dict[str, Any]:
        """Keyword arguments of :func:`adhfit.simulate` for this scene (docs/contracts.md A2b).

        Parameters
        ----------
        mu_h : float or str, optional
            Overrides the scene's μh (N/m); required if the scene has none.
        work_of_adhesion : float or str, optional
            Overrides the scene's W_ad (J/m^2); required if the scene has none.
        slip : {"no-slip", "frictionless"}, optional
            Overrides the scene's slip; required when the scene says ``"auto"``.

        Returns
        -------
        dict
            ``control, slip, p`` (or ``d`` under pressure control), ``w, rs, lambda0`` and one of
            ``a_max, delta_max, p_max`` if the scene sets a loading end; dimensionless (A1).

        Raises
        ------
        InputError
            A value is missing, or its group is outside the model's domain (range given in SI).
        """
        scales = self.scales(mu_h)
        slip = self.slip if slip is None else slip
        if slip not in ("no-slip", "frictionless"):
            raise InputError("slip", slip, "one of 'no-slip', 'frictionless'",
                             "A simulation needs one slip condition; 'auto' only means 'fit both'.")
        w_si = self.work_of_adhesion if work_of_adhesion is None else \
            parse_quantity(work_of_adhesion, "energy_per_area", name="work_of_adhesion")
        if w_si is None:
            raise InputError("work_of_adhesion", None, "a positive energy per area (e.g. '0.4 J/m^2')",
                             "The scene has no work_of_adhesion: pass one (e.g. the fit's current value).")
        out: dict[str, Any] = {"control": self.control, "slip": slip}
        for key, group in _GROUP_OF.items():
            si = w_si if key == "work_of_adhesion" else getattr(self, key)
            if si is not None:
                out[group] = _group(scales, group, key, si)
        out["lambda0"] = self.prestretch
        if "p" in out and out["p"] + 1.0 / out["rs"] <= 0.0:  # as in adhfit.params.check_scene
            lowest = -2 * scales.mu_h / self.substrate_radius
            raise InputError("pressure", self.pressure, f"above -2 mu_h / R_s = {lowest:g} Pa", "The "
                             "membrane must be less concave than the substrate (contact starts at the apex).")
        return out

    def warnings(self) -> list[str]:
        """Facts a report should state about this scene's validity (empty if none)."""
        if self.prestretch >= 2.0:
            return []
        e = 100 * float(np.interp(self.prestretch, *zip(*LARGE_STRETCH_ERROR)))
        table = ", ".join(f"{100 * x:.2g} % at {lam:g}" for lam, x in LARGE_STRETCH_ERROR)
        return [f"prestretch λ0 = {self.prestretch:g} < 2: the large-stretch approximation (paper eq. 10) "
                f"is weak here. Against the exact neo-Hookean membrane its free-inflation apex deflection "
                f"is off by about {e:.2g} % at this λ0 ({table}); the pull-off force is far less sensitive."]


def _group(scales: Scales, group: str, key: str, si: float) -> float:
    """SI value of field ``key`` -> dimensionless ``group``, checked against the parameter table."""
    value = float(scales.to_dimensionless(group, si))
    row = DIMENSIONLESS[group]
    if not row.contains(value):
        lo, hi = (scales.to_si(group, x) for x in (row.lower, row.upper))
        unit = {"length": "m", "pressure": "Pa", "energy": "J/m^2"}[GROUPS[group]]
        span = ("(" if row.lower_open else "[") + f"{lo:g}, {hi:g}" + (")" if row.upper_open else "]")
        raise InputError(key, si, f"in {span} {unit} for b = {scales.b:g} m, mu_h = {scales.mu_h:g} N/m",
                         f"That is {group} = {value:.6g}; {group} must be {row.valid_range}.")
    return value


# ----------------------------------------------------------------------------------------------
# Priors (for the MCMC fit): kept as plain dicts, validated and converted to SI here.
#: Distribution -> its parameters, all in the fitted parameter's SI unit.
PRIOR_DISTS = {"loguniform": ("min", "max"), "uniform": ("min", "max"), "normal": ("mean", "sd")}
_PRIOR_DIMENSION = {"work_of_adhesion": "energy_per_area", "mu_h": "force_per_length"}


def normalize_priors(priors: Mapping[str, Any], *, prefix: str = "priors") -> dict[str, dict[str, Any]]:
    """Validate priors of fitted parameters; return a new dict with every number in SI.

    ``priors`` maps a parameter of :data:`adhfit.params.FITTED` to ``{"dist": "loguniform" |
    "uniform", "min": .., "max": ..}`` or ``{"dist": "normal", "mean": .., "sd": ..}``, numbers in SI
    or strings with units, e.g. ``{"work_of_adhesion": {"dist": "loguniform", "min": 0.01, "max": 10.0}}``.
    Errors are :class:`InputError` named ``{prefix}.{parameter}[.{key}]``.
    """
    if not isinstance(priors, Mapping):
        raise InputError(prefix, priors, "a table {parameter: {dist = ..., ...}}")
    out: dict[str, dict[str, Any]] = {}
    for name, spec in priors.items():
        label = f"{prefix}.{name}"
        if name not in _PRIOR_DIMENSION:
            raise InputError(label, spec, "a prior of a fitted parameter: " + ", ".join(_PRIOR_DIMENSION),
                             f"Unknown parameter '{clip(str(name))}';{_suggest(name, _PRIOR_DIMENSION)}".rstrip(";"))
        dist = spec.get("dist") if isinstance(spec, Mapping) else None
        if dist not in PRIOR_DISTS:
            raise InputError(label, spec, "a table with dist = " + " | ".join(map(repr, PRIOR_DISTS)) +
                             " and its parameters, e.g. {dist = 'loguniform', min = '0.01 J/m^2', "
                             "max = '10 J/m^2'}")
        wanted = {"dist", *PRIOR_DISTS[dist]}
        if set(spec) != wanted:
            raise InputError(label, spec, f"a {dist} prior with exactly the keys {', '.join(sorted(wanted))}",
                             f"Missing: {sorted(wanted - set(spec))}; unknown: {sorted(set(spec) - wanted)}.")
        entry = {"dist": dist} | {k: parse_quantity(spec[k], _PRIOR_DIMENSION[name], name=f"{label}.{k}")
                                  for k in PRIOR_DISTS[dist]}
        a, b, unit = entry[PRIOR_DISTS[dist][0]], entry[PRIOR_DISTS[dist][1]], FITTED[name].unit
        if dist == "normal" and not b > 0:
            raise InputError(f"{label}.sd", spec["sd"], f"positive (in {unit})")
        if dist != "normal" and not (a < b and a >= FITTED[name].lower and (dist == "uniform" or a > 0)):
            low = "> 0" if dist == "loguniform" else f">= {FITTED[name].lower:g}"
            raise InputError(label, spec, f"a range with min {low} and min < max (in {unit})")
        out[name] = entry
    return out


# ----------------------------------------------------------------------------------------------
# TOML
def load_scene(path: str | Path) -> Scene:
    """Read a scene file (TOML, docs/contracts.md A3).

    Parameters
    ----------
    path : str or Path
        The scene file.  Values are numbers in SI units or strings with units; ``"inf"`` for a
        flat substrate.  Sections: ``[membrane] [substrate] [test] [interface] [priors]``.

    Returns
    -------
    Scene

    Raises
    ------
    DataError
        With the path (and the line where it can be found): unreadable file, invalid TOML,
        unknown section or key (with the closest known one), missing or forbidden value, wrong
        unit, value out of range.
    """
    where = str(path)
    try:
        raw = Path(path).read_bytes()
        if len(raw) > MAX_SCENE_BYTES:
            raise DataError(f"the scene file has {len(raw):,} bytes; a scene file holds a few lines (at most "
                            f"{MAX_SCENE_BYTES:,} bytes): is this the scene file?", path=where)
        text = raw.decode("utf-8-sig")
        doc = tomllib.loads(text)
    except (OSError, UnicodeDecodeError) as exc:
        raise DataError(f"cannot read the scene file ({clip(str(exc))})", path=where) from None
    except RecursionError:  # tomllib recurses once per level of [[[...]]] or {a = {b = ...}}
        raise DataError("tables or arrays nested too deeply to read; a scene file holds '[section]' headers "
                        "and 'key = value' lines (priors: one inline table per parameter)", path=where) from None
    except tomllib.TOMLDecodeError as exc:
        m = re.search(r"at line (\d+)", str(exc))
        raise DataError(f"not valid TOML: {exc}", path=where, line=int(m.group(1)) if m else None) from None

    def fail(message: str, section: str | None = None, key: str | None = None) -> DataError:
        return DataError(message, path=where, line=_line_of(text, section, key))

    raw = _fields(doc, fail)
    try:
        return Scene(**raw, priors=doc.get("priors", {}), source=where)
    except InputError as exc:
        if exc.name.startswith("priors."):
            sec, k, key = "priors", exc.name.split(".")[1], "[priors] " + exc.name.split(".", 1)[1]
        else:
            key = FILE_KEY.get(exc.name, exc.name)
            sec, k = key[1:].split("] ") if key.startswith("[") else (None, None)
        table = doc.get(sec, {}) if sec not in (None, "priors") else {}
        given = table.get(k, exc.value) if isinstance(table, dict) else exc.value
        raise fail(f"{clip(key)} must be {clip(exc.valid, 300)}, got {shown(given)}. {clip(exc.reason, 300)}".rstrip(),
                   sec, k) from None


def _fields(doc: dict[str, Any], fail) -> dict[str, Any]:
    """Scene keyword arguments from a parsed scene file (raw values); layout and presence checks."""
    raw: dict[str, Any] = {}
    sections = ", ".join(f"[{s}]" for s in [*LAYOUT, "priors"])
    for section, table in doc.items():
        if section not in LAYOUT and section != "priors":
            if not isinstance(table, dict):
                owner = " or ".join(f"[{s}]" for s, keys in LAYOUT.items() if section in keys)
                raise fail(f"key '{clip(section)}' is outside any section; " + (
                    f"it belongs in {owner}." if owner else f"known sections: {sections}"), None, section)
            hint = _suggest(section, [*LAYOUT, "priors"])
            raise fail(f"unknown section [{clip(section)}];{hint} Known sections: {sections}.", section)
        if not isinstance(table, dict):
            raise fail(f"[{section}] must be a table (a '[{section}]' header and keys)", None, section)
        for key, value in table.items():
            if section == "priors":
                continue
            if key not in LAYOUT[section]:
                raise fail(f"[{section}] unknown key '{clip(key)}';{_suggest(key, LAYOUT[section])} Known keys: "
                           f"{', '.join(LAYOUT[section])}.", section, key)
            raw[LAYOUT[section][key][0]] = value
    _check_plain_lengths(raw, fail)
    for fld in ("membrane_radius", "substrate_radius", "control"):
        if fld not in raw:
            example = {"membrane_radius": "e.g. '2 mm'", "control": "'displacement' or 'pressure'",
                       "substrate_radius": "e.g. '1 mm', or 'inf' for a flat substrate"}[fld]
            raise fail(f"{FILE_KEY[fld]} is required ({example})", FILE_KEY[fld][1:].split("]")[0])
    if raw["control"] in _FIXED:
        needed, forbidden, what = _FIXED[raw["control"]]
        if needed not in raw:
            raise fail(f"[test] {needed} is required for control = '{raw['control']}' ({what})", "test")
        if forbidden in raw:
            raise fail(f"[test] {forbidden} is not used under control = '{raw['control']}' (it varies during "
                       f"the test); give [test] {needed} instead ({what})", "test", forbidden)
    return raw


def _check_plain_lengths(raw: dict[str, Any], fail) -> None:
    """A length given as a plain number (metres) beyond :data:`PLAIN_LENGTH_MAX` is a forgotten unit."""
    for fld, value in raw.items():
        if _DIMENSION.get(fld) != "length" or isinstance(value, bool) or not isinstance(value, (int, float)):
            continue
        if PLAIN_LENGTH_MAX < abs(value) < float("inf"):
            key = FILE_KEY[fld]
            section, name = key[1:].split("] ")
            raise fail(f"{key} = {value!r} is a plain number, so it is read in metres (SI): {value:g} m, larger "
                       f"than any membrane test (plain lengths above {PLAIN_LENGTH_MAX:g} m are refused); write "
                       f"the unit, e.g. {name} = '{value:g} mm' (or '{value:g} m' if you mean metres)", section, name)


def _suggest(word: str, known: Any) -> str:
    close = difflib.get_close_matches(word, list(known), n=1, cutoff=0.6)
    return f" did you mean '{close[0]}'?" if close else ""


def _line_of(text: str, section: str | None, key: str | None) -> int | None:
    """1-based line of ``key = ...`` in ``[section]`` (or of the section header), if it can be found."""
    current, header = None, None
    for n, line in enumerate(text.splitlines(), start=1):
        s = line.strip()
        m = re.match(r"^\[\s*([A-Za-z0-9_\-]+)\s*\]", s)
        if m:
            current = m.group(1)
            if current == section and header is None:
                header = n
            continue
        if key is not None and current == section and re.match(rf"^{re.escape(key)}\s*=", s):
            return n
    return header
