"""``adhfit.plan``: which test decides W_ad, μh and the slip, answered before the lab runs it (docs/planning.md).

The inputs are a scene (geometry, control mode, fixed pressure or gap, membrane model), guessed W_ad and
μh, the force noise and the protocol (loading end, rows); ``vary`` spans one or two settings on a grid.
Every protocol is predicted with the fit's own likelihood (:mod:`.evaluate`), the cheapest one that
decides the slip and reaches the requested W_ad precision is recommended (:mod:`.recommend`), and for a
test series (``global_k``) the best set of k pressures or gaps is chosen (:mod:`.series`).
"""
from __future__ import annotations

import itertools
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import InputError
from ..units import parse_quantity
from .protocols import END_NAMES, Protocol, check_noise, check_rows, grid, parse_vary
from .recommend import DEFAULT_TARGET, recommend

__all__ = ["plan", "Plan", "parse_noise", "SLIP_CHOICES"]

SLIP_CHOICES = ("both", "no-slip", "frictionless")
_END_KEYS = {"a_max": "a_max", "delta_max": "displacement_max", "displacement_max": "displacement_max",
             "p_max": "pressure_max", "pressure_max": "pressure_max"}
_SCENE_END = {"contact_radius_max": "a_max", "displacement_max": "displacement_max", "pressure_max": "pressure_max"}


@dataclass(frozen=True)
class Plan:
    """A test plan (docs/contracts.md A8).

    Attributes
    ----------
    protocols : list of dict
        One plan.json entry per protocol (grid order: the first varied setting slowest).
    recommended : int or None
    why : str
    axes : dict
        Varied setting -> its grid values (SI), in order.
    inputs : dict
        What was planned for (SI).
    series : dict or None
        The ``global_k`` answer (:func:`.series.best_set`).
    base : Protocol
        The protocol the grid varies.
    """

    protocols: list
    recommended: int | None
    why: str
    axes: dict
    inputs: dict
    series: dict | None = None
    base: Any = field(default=None, repr=False, compare=False)
    computation: dict | None = None

    def to_dict(self) -> dict:
        """plan.json: the A8 keys, plus ``axes``, ``inputs`` and ``series``."""
        out = {"protocols": self.protocols, "recommended": self.recommended, "why": self.why,
               "axes": {k: [float(v) for v in vals] for k, vals in self.axes.items()}, "inputs": self.inputs}
        if self.series is not None:
            out["series"] = self.series
        if self.computation is not None:
            out["computation"] = self.computation
        return out

    def protocol(self, index: int) -> Protocol:
        """The :class:`Protocol` of entry ``index``."""
        p = self.base
        for name, value in self.protocols[index]["grid"].items():
            p = p.replace(name, value)
        return p

    def write(self, outdir: str | Path) -> dict:
        """Write plan.json, report.html and (with a recommendation) scene.toml; returns name -> path."""
        from .files import write_plan  # noqa: PLC0415 - matplotlib only when writing
        return write_plan(self, Path(outdir))


def parse_noise(value: Any, flag: str = "--noise") -> float:
    """``0.02``, ``"0.02"`` or ``"2%"`` -> 0.02, checked to lie in (0, 1]."""
    text = str(value).strip()
    try:
        v = float(text[:-1]) / 100.0 if text.endswith("%") else float(text)
    except ValueError:
        raise InputError(flag, value, "a fraction in (0, 1], e.g. 0.02 or 2%") from None
    return check_noise(v, flag)


def _end(scene, ends: dict, mu: float) -> tuple[str, float, str]:
    from ..synthetic import parse_end  # noqa: PLC0415
    given = {k: v for k, v in ends.items() if v is not None}
    if len(given) > 1:
        raise InputError("--" + list(given)[1].replace("_", "-"), list(given.values())[1],
                         "absent when another loading end is given", "Give one of --a-max, --delta-max, --pressure-max.")
    if not given:
        for key, name in _SCENE_END.items():
            value = getattr(scene, key)
            if value is not None:
                return name, value / scene.membrane_radius if name == "a_max" else float(value), f"[test] {key}"
        raise InputError("--a-max", None, "a loading end: --a-max A, --delta-max X or --pressure-max Q",
                         "Or set [test] contact_radius_max, displacement_max or pressure_max in the scene.")
    (key, value), = given.items()
    value = _plain(value)  # a bare number is the dimensionless group, as in simulate
    name = _END_KEYS[key]
    if name == "displacement_max" and scene.control != "displacement" or \
            name == "pressure_max" and scene.control != "pressure":
        raise InputError(f"--{key.replace('_', '-')}", value, f"a loading end of {scene.control} control (the scene's)",
                         "Use --delta-max under displacement control, --pressure-max under pressure control, or --a-max.")
    sc = scene.scales(mu)
    dim_key = {"a_max": "a_max", "displacement_max": "delta_max", "pressure_max": "p_max"}[name]
    try:
        group = parse_end(dim_key, value, sc)
    except InputError as err:
        raise InputError(f"--{key.replace('_', '-')}", value, "a positive number (dimensionless, docs/contracts.md "
                         "A1) or a value with a unit", str(err)) from None
    if not (math.isfinite(group) and group > 0):
        raise InputError(f"--{key.replace('_', '-')}", value, "a positive loading end")
    flag = f"--{key.replace('_', '-')}"
    if name == "a_max":
        return name, group, flag
    return name, group * sc.length if name == "displacement_max" else float(sc.from_p(group)), flag


def _plain(value: Any) -> Any:
    """A bare number written as text ("0.3") is SI, as on the command line of ``adhfit simulate``."""
    try:
        return float(value) if isinstance(value, str) else value
    except ValueError:
        return value


def _slips(slip: str) -> tuple:
    if slip not in SLIP_CHOICES:
        raise InputError("--slip", slip, "one of " + ", ".join(SLIP_CHOICES))
    return ("no-slip", "frictionless") if slip == "both" else (slip,)


def _run(protocols: list, slips: tuple, w: float, mu: float, membrane: str, workers: int,
         radius_noise: float | None = None, hints: list | None = None) -> list[dict]:
    from .evaluate import predict  # noqa: PLC0415
    hints = hints or [None] * len(protocols)
    if workers <= 1 or len(protocols) < 4:
        return [predict(p, slips, w, mu, membrane, radius_noise, h) for p, h in zip(protocols, hints)]
    import concurrent.futures as cf  # noqa: PLC0415
    import multiprocessing  # noqa: PLC0415
    ctx = multiprocessing.get_context("fork") if "fork" in multiprocessing.get_all_start_methods() else None
    with cf.ProcessPoolExecutor(max_workers=workers, mp_context=ctx) as pool:
        chunk = max(1, len(protocols) // (4 * workers))
        return list(pool.map(predict, protocols, [slips] * len(protocols), [w] * len(protocols),
                             [mu] * len(protocols), [membrane] * len(protocols), [radius_noise] * len(protocols),
                             hints, chunksize=chunk))


#: an axis of a map with at least this many values is computed in full on every other value (and its last)
#: only; the cells between take P(drift fitted) interpolated from those where they agree (:data:`DRIFT_AGREE`)
SUBGRID_MIN = 8


def _coarse(k: int) -> list[int]:
    return sorted(set(range(0, k, 2)) | {k - 1}) if k >= SUBGRID_MIN else list(range(k))


def _bracket(i: int, coarse: list[int]) -> list[tuple[int, float]]:
    """The coarse indices around ``i`` and their linear weights."""
    if i in coarse:
        return [(i, 1.0)]
    hi = next(c for c in coarse if c > i)
    lo = max(c for c in coarse if c < i)
    t = (i - lo) / (hi - lo)
    return [(lo, 1.0 - t), (hi, t)]

#: a cell between the sub-grid's takes the interpolated P(drift fitted) only where its neighbours' agree within
#: this (absolute); elsewhere it computes it from noisy copies (P(drift) jumps where the rows before contact cross
#: 5).  On the 20 x 20 map of benchmarks/plan_map_time.py: 304 of 676 predictions interpolated, P(drift) off by at
#: most 0.10, P(decided) by 0.015, the W_ad width by 2 % (docs/planning.md, "Cost").
#:
#: Not interpolated, measured on that map: W_ad's profile factors (:func:`.evaluate.profile_factors`; they jump
#: where the turning point crosses a row: even where all four neighbours agreed within 10 %, 3 of 33 cells were
#: off by 18-89 %), and the other slip's fit started at the neighbours' optimum (its χ² has several minima: λ
#: more than 5 % off in 82 of 676 predictions, P(decided) up to 0.56).
DRIFT_AGREE = 0.1


def _hint(entries: dict, neighbours: list, slips: tuple) -> dict:
    """slip -> the interpolated ``p_drift`` of a cell between the sub-grid's ``neighbours`` ((flat index,
    weight)); None where its neighbours do not agree (:data:`DRIFT_AGREE`) or leave the domain: the cell computes
    it from noisy copies."""
    if not all(entries[i]["in_domain"] for i, _ in neighbours):
        return {}
    tot = sum(wt for _, wt in neighbours)
    out = {}
    for s in slips:
        bs = [(entries[i]["by_slip"][s], wt / tot) for i, wt in neighbours]
        drift = [b["p_drift_fitted"] for b, _ in bs]
        hint = {"p_drift": None}
        if max(drift) - min(drift) <= DRIFT_AGREE:
            hint["p_drift"] = float(sum(b["p_drift_fitted"] * wt for b, wt in bs))
        out[s] = hint
    return out


def _run_map(protocols: list, axes: list, slips: tuple, w: float, mu: float, membrane: str, workers: int,
             radius_noise: float | None) -> tuple[list[dict], dict]:
    """Every protocol of the grid: the sub-grid (:data:`SUBGRID_MIN`) in full, then the cells between with
    :func:`_hint`.  Returns the entries and what the map computed how (plan.json ``computation``)."""
    shape = [len(a) for a in axes]
    coarse = [_coarse(k) for k in shape]
    full = [i for i, idx in enumerate(np.ndindex(*shape)) if all(j in c for j, c in zip(idx, coarse))]
    if len(full) == len(protocols):
        return _run(protocols, slips, w, mu, membrane, workers, radius_noise), {"sub_grid": None}
    done = dict(zip(full, _run([protocols[i] for i in full], slips, w, mu, membrane, workers, radius_noise)))
    rest, hints = [], []
    for i, idx in enumerate(np.ndindex(*shape)):
        if i in done:
            continue
        neighbours = [(int(np.ravel_multi_index(tuple(j for j, _ in combo), shape)), float(np.prod([wt for _, wt in combo])))
                      for combo in itertools.product(*[_bracket(j, c) for j, c in zip(idx, coarse)])]
        rest.append(i)
        hints.append(_hint(done, neighbours, slips))
    done.update(zip(rest, _run([protocols[i] for i in rest], slips, w, mu, membrane, workers, radius_noise, hints)))
    entries = [done[i] for i in range(len(protocols))]
    return entries, {"sub_grid": [[float(axes[d][j]) for j in c] for d, c in enumerate(coarse)],
                     "sub_grid_cells": len(full)}


def _computed(entries: list[dict]) -> dict:
    """How many (protocol, slip) predictions took W_ad's width (the fit's profile or the Fisher information) and
    P(drift fitted) (noisy copies or interpolated) by which method."""
    count: dict = {"w_ad_width": {}, "p_drift": {}}
    for e in entries:
        for b in (e.get("by_slip") or {}).values():
            for key, m in (("w_ad_width", b["w_ad_width_method"]), ("p_drift", b["p_drift_method"])):
                count[key][m] = count[key].get(m, 0) + 1
    return count


def _full(entry: dict) -> bool:
    return all(b["p_drift_method"] != "interpolated" for b in (entry.get("by_slip") or {}).values())


def plan(scene: Any, *, work_of_adhesion: float | str, mu_h: float | str, noise: float | str,
         slip: str = "both", rows: int = 300, a_max: float | str | None = None,
         delta_max: float | str | None = None, pressure_max: float | str | None = None,
         vary: str | dict | None = None, global_k: int | None = None, target_precision: float = DEFAULT_TARGET,
         membrane: str | None = None, workers: int = 1, radius_noise: float | str | None = None) -> Plan:
    """Predict what the fit will find for candidate protocols, and recommend one.

    Parameters
    ----------
    scene : path or adhfit.scene.Scene
        Geometry, control mode, the fixed pressure (displacement control) or gap (pressure control), and
        the membrane model (``[membrane] model``; ``auto`` as the fit decides it).
    work_of_adhesion, mu_h : float or str
        Guessed W_ad (J/m², or "0.4 J/m^2") and μh (N/m, or "2 N/m").
    noise : float or str
        Force noise σ as a fraction of the peak force (0.02 or "2%"), > 0.
    slip : {"both", "no-slip", "frictionless"}
        The true slip condition(s) to plan for.
    rows : int
        Rows of the whole test (loading and unloading), laid out as ``adhfit simulate --scene`` lays them.
    a_max, delta_max, pressure_max : float or str
        The loading end (one of them; default: the scene's): ``a_max`` the contact radius over b; the
        others a dimensionless group (docs/contracts.md A1) or a value with a unit ("0.4 mm", "1.2 kPa").
    vary : str or dict, optional
        ``"NAME=LO:HI[:K],..."`` (at most two settings: pressure, gap, a_max, displacement_max, pressure_max,
        rows, noise), or a dict NAME -> (lo, hi[, k]) in SI.
    global_k : int, optional
        For a test series: the best set of k values of the varied pressure (or gap).
    target_precision : float
        Requested W_ad precision: the expected 95 % interval width over W_ad (0.1 = ±5 %).
    membrane : {"auto", "large-stretch", "exact"}, optional
        Overrides the scene's membrane model.
    workers : int
        Local processes evaluating the protocols.
    radius_noise : float or str, optional
        A camera films the contact radius with this noise (a fraction of the largest contact radius, 0.01 or
        "1%"): the fit's contact-radius block joins the widths (single tests and ``global_k``).  The slip
        verdict stays force-only (its P is then a lower bound).

    Returns
    -------
    Plan

    Raises
    ------
    InputError
        Bad input, or no protocol inside the model's domain.
    """
    from ..scene import Scene, load_scene  # noqa: PLC0415
    sc = scene if isinstance(scene, Scene) else load_scene(scene)
    w = parse_quantity(_plain(work_of_adhesion), "energy_per_area", name="--work-of-adhesion")
    mu = parse_quantity(_plain(mu_h), "force_per_length", name="--mu-h")
    for flag, v in (("--work-of-adhesion", w), ("--mu-h", mu)):
        if not (math.isfinite(v) and v > 0):
            raise InputError(flag, v, "a positive value, e.g. '0.4 J/m^2' or '2 N/m'")
    sigma = parse_noise(noise)
    n_rows = check_rows(rows)
    slips = _slips(slip)
    if not (isinstance(target_precision, (int, float)) and 0 < target_precision <= 10):
        raise InputError("--target-precision", target_precision, "a number in (0, 10] (the 95 % width of W_ad "
                         "over W_ad, e.g. 0.1)")
    membrane = membrane or sc.membrane_model
    if membrane not in ("auto", "large-stretch", "exact"):
        raise InputError("--membrane", membrane, "one of 'auto', 'large-stretch', 'exact'")
    sc.scales(mu)
    end, end_value, end_flag = _end(sc, {"a_max": a_max, "delta_max": delta_max, "pressure_max": pressure_max}, mu)
    grid_spec = parse_vary(vary, sc.control)
    base = Protocol(scene=sc, end=end, end_value=end_value, rows=n_rows, noise=sigma)
    protocols, axes = grid(base, grid_spec)
    r_noise = None
    if radius_noise is not None:
        r_noise = parse_noise(radius_noise, "--radius-noise")
    entries, computation = _run_map(protocols, axes, slips, w, mu, membrane, workers, r_noise)
    names = list(grid_spec)
    for p, e in zip(protocols, entries):
        e["grid"] = {n: p.value(n) for n in names}
    if not any(e["in_domain"] for e in entries):
        flag = "--vary " + names[0] if names else end_flag
        why = entries[0].get("why_not", "")
        given = {"a_max": a_max, "delta_max": delta_max, "pressure_max": pressure_max}
        value = vary if names else next((v for v in given.values() if v is not None), end_value)
        raise InputError(flag, value, "a setting that keeps the test inside the model's domain",
                         f"All {len(entries)} protocol(s) leave it; the first because {why.rstrip('.')}. Fix: change "
                         f"the loading end, the pressure or gap, or the guessed W_ad and μh.")
    index, why = recommend(entries, w, target_precision)
    for _ in range(len(entries)):  # the recommended protocol with every part computed, not interpolated
        if index is None or _full(entries[index]):
            break
        entries[index] = _run([protocols[index]], slips, w, mu, membrane, 1, r_noise)[0]
        entries[index]["grid"] = {n: protocols[index].value(n) for n in names}
        index, why = recommend(entries, w, target_precision)
    computation["predictions"] = _computed(entries)
    if computation["sub_grid"] is not None:
        c = computation["predictions"]
        why += (f" (map: W_ad's width from the fit's profile in {c['w_ad_width'].get('profile', 0)} predictions, "
                f"the Fisher width in {c['w_ad_width'].get('fisher', 0)}; P(drift fitted) interpolated between the "
                f"sub-grid's cells in {c['p_drift'].get('interpolated', 0)}, from noisy copies in "
                f"{c['p_drift'].get('noisy copies', 0)}; plan.json by_slip says which)")
    inputs = {"scene": str(sc.source) if sc.source else None, "work_of_adhesion": w, "mu_h": mu, "noise": sigma,
              "rows": n_rows, "slips": list(slips), "loading_end": {end: end_value}, "target_precision": target_precision,
              "membrane": membrane, "radius_noise": r_noise, "vary": {k: list(v) for k, v in grid_spec.items()}, "p_decided_required": 0.9}
    result = Plan(protocols=entries, recommended=index, why=why, axes=dict(zip(names, axes)), inputs=inputs,
                  base=base, computation=computation)
    if global_k is not None:
        from .series import best_set  # noqa: PLC0415
        series = best_set(result, int(global_k), slips, w, mu, membrane)
        result = Plan(protocols=entries, recommended=index, why=why, axes=result.axes, inputs=inputs,
                      series=series, base=base, computation=computation)
    return result
