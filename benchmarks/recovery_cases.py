"""Synthetic test curves for the recovery study (``recovery.py``): the truth, and what a lab adds to it.

The noise-free curve comes from the forward model alone (:func:`adhfit.simulate`, the dimensionless
engine, with the scene's scales); everything a real test adds is added here, not by the fitting
package: Gaussian force noise, an un-tared load cell, a load-cell zero that drifts during the test, a
test stopped early, an export that wrote every row twice.  The curve is written to a CSV file
(docs/contracts.md A4 columns) so that the fit reads it as a user's file would be read.

A test follows a real one: the control variable rises at a constant step from before contact to its
largest value, then falls at the same step.  On the way out the force follows the stable branch
(pinning, then delamination) down to the turning point of the control variable; past it the membrane
has jumped off and the force is zero.  The dense history is interpolated linearly in x on loading
and in u = sqrt(x - x_tp) on the way out (the force has a square-root fold at the turning point).
"""
from __future__ import annotations

import functools
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from adhfit import ConvergenceError, simulate
from adhfit.scene import Scene

TRUTH = {"work_of_adhesion": 0.4, "mu_h": 2.0}          # J/m^2, N/m (the paper's FEA set)
SLIPS = ("no-slip", "frictionless")
NOISES = (0.002, 0.005, 0.01, 0.02, 0.04, 0.05)          # force noise σ / peak force
BASELINE = 0.015                                         # un-tared load cell, fraction of the peak force
DRIFT = 0.01                                             # zero drift at the end of the test, fraction of the peak force
ROWS = 200                                               # rows of a whole test (loading and unloading)
STEP_S = 0.5                                             # time between rows, s


@dataclass(frozen=True)
class Case:
    """A test geometry: scene (control, substrate), largest control value, control offset."""

    name: str
    scene: Scene
    x_max: float     # m (displacement) or Pa (pressure)
    x_offset: float  # true minus measured control value


def _cases() -> dict[str, Case]:
    curved, flat = {"substrate_radius": "1 mm"}, {"substrate_radius": "inf"}
    disp, pres = {"control": "displacement", "pressure": "1.2 kPa"}, {"control": "pressure"}
    specs = [("displacement-curved", curved | disp, 0.6e-3, 20e-6),
             ("pressure-curved", curved | pres | {"gap": "0 mm"}, 1.6e3, 0.0),
             ("displacement-flat", flat | disp, 0.4e-3, -30e-6),
             ("pressure-flat", flat | pres | {"gap": "0.2 mm"}, 1.6e3, 0.0)]
    # the curves come from the large-stretch model, so they are fitted with it: the study measures the
    # estimator, not the model choice (benchmarks/bench_exact_fit.py studies the exact membrane)
    return {n: Case(n, Scene(membrane_radius="2 mm", membrane_model="large-stretch", **kw), x, off)
            for n, kw, x, off in specs}


CASES = _cases()
#: appended, never reordered: a replicate's seed uses the variant's index here (recovery.seed_sequence)
VARIANTS = ("clean", "baseline", "trunc-turn", "trunc-pinning", "trunc-delamination", "duplicated", "drift")
#: variants whose unloading never reaches delamination: W_ad is bounded from below only
LOWER_BOUND_VARIANTS = ("trunc-turn", "trunc-pinning")


@dataclass(frozen=True)
class Dense:
    """The noise-free test in SI: loading (x, f), way out to the turning point (x, f, G), stage ends."""

    xl: np.ndarray
    fl: np.ndarray
    xr: np.ndarray
    fr: np.ndarray
    gr: np.ndarray
    x_delam: float   # control value where delamination starts on the way out
    stable_delamination: bool  # False: pull-off at the end of pinning (pressure control, flat)


@functools.lru_cache(maxsize=16)
def dense(case: str, slip: str, points: int = 2000) -> Dense:
    """The dense forward history of ``case`` under ``slip`` (cached per process)."""
    c = CASES[case]
    sc = c.scene.scales(TRUTH["mu_h"])
    kw = c.scene.to_dimensionless(mu_h=TRUTH["mu_h"], work_of_adhesion=TRUTH["work_of_adhesion"], slip=slip)
    for k in ("a_max", "delta_max", "p_max"):
        kw.pop(k, None)
    disp = c.scene.control == "displacement"
    end = {"delta_max": sc.to_delta(c.x_max)} if disp else {"p_max": sc.to_p(c.x_max)}
    key, to_si = ("delta", sc.from_delta) if disp else ("p", sc.from_p)
    frame, err = None, None
    for extra in (0, 13, 37, 101, -499):
        try:
            frame = simulate(**kw, **end, points=points + extra).frame
            break
        except ConvergenceError as e:  # the engine's continuation stalled: a neighbouring row count
            err = e
    if frame is None:
        raise err
    stage, stable = frame["stage"].to_numpy(), frame["stable"].to_numpy(bool)
    x, f, g = (frame[k].to_numpy(float) for k in (key, "f", "G"))
    mc = np.flatnonzero(stage == "making_contact")
    out = np.concatenate([[mc[-1]], np.flatnonzero((stage != "making_contact") & stable)])
    delam = out[stage[out] == "delamination"]
    return Dense(xl=to_si(x[mc]), fl=sc.from_f(f[mc]), xr=to_si(x[out]), fr=sc.from_f(f[out]),
                 gr=g[out] * sc.energy, x_delam=float(to_si(x[delam[0] if delam.size else out[-1]])),
                 stable_delamination=delam.size > 1)


def applicable(case: str, slip: str, variant: str) -> bool:
    """False where the variant does not exist: no stable delamination to stop inside."""
    return variant != "trunc-delamination" or dense(case, slip).stable_delamination


def _noise_free(d: Dense, rows: int = ROWS) -> tuple[np.ndarray, np.ndarray, int]:
    """Rows (x, f) of the whole test at a constant step (about ``rows`` of them), and the index of the
    first unloading row."""
    x0, x1, x_tp = d.xl[0], d.xl[-1], d.xr[-1]
    start, stop = x0 - 0.08 * (x1 - x0), x_tp - 0.15 * (x1 - x_tp)
    step = ((x1 - start) + (x1 - stop)) / (rows - 1)
    up = np.linspace(start, x1, int(round((x1 - start) / step)) + 1)
    down = np.linspace(x1, stop, int(round((x1 - stop) / step)) + 1)[1:]
    f_up = np.where(up <= x0, 0.0, np.interp(up, d.xl, d.fl))
    u = np.sqrt(np.clip(d.xr - x_tp, 0.0, None))
    order = np.argsort(u)
    f_down = np.where(down < x_tp, 0.0, np.interp(np.sqrt(np.clip(down - x_tp, 0.0, None)), u[order],
                                                  d.fr[order]))
    return np.concatenate([up, down]), np.concatenate([f_up, f_down]), up.size


def _keep(variant: str, x: np.ndarray, n_up: int, d: Dense, rng: np.random.Generator) -> int:
    """Rows kept by a truncation variant (all rows otherwise)."""
    down = x[n_up:]
    if variant == "trunc-turn":            # stopped 5-15 rows after the turn
        return n_up + int(rng.integers(5, 16))
    if variant == "trunc-pinning":         # stopped inside pinning
        stop = d.x_delam + rng.uniform(0.3, 0.7) * (d.xl[-1] - d.x_delam)
    elif variant == "trunc-delamination":  # stopped inside delamination, before pull-off
        stop = d.xr[-1] + rng.uniform(0.3, 0.7) * (d.x_delam - d.xr[-1])
    else:
        return x.size
    return n_up + max(int(np.count_nonzero(down >= stop)), 1)


def drift(rows: int, f_peak: float) -> np.ndarray:
    """A load-cell zero that drifts linearly in time from 0 to ``DRIFT * f_peak`` over the whole test (N)."""
    return np.linspace(0.0, DRIFT * f_peak, rows)


def make_curve(case: str, slip: str, noise: float, variant: str, rng: np.random.Generator,
               path: Path, rows: int = ROWS) -> dict:
    """Write one synthetic test to ``path`` (CSV) and return its truth.

    Noise is drawn for every row of the full test first, so a truncated test is a prefix of a full one.
    ``rows`` sets the row spacing: the whole test has about that many rows (the default is the study's).
    """
    if variant not in VARIANTS:
        raise ValueError(f"variant {variant!r}: expected one of {VARIANTS}")
    c, d = CASES[case], dense(case, slip)
    x_true, f_true, n_up = _noise_free(d, rows)
    f_peak = float(np.max(d.fl))
    sigma = noise * f_peak
    force = f_true + rng.normal(0.0, sigma, f_true.size)
    offset = BASELINE * f_peak if variant == "baseline" else 0.0
    force = force + offset
    if variant == "drift":
        force = force + drift(force.size, f_peak)
    n = _keep(variant, x_true, n_up, d, rng)
    x_meas, force = x_true[:n] - c.x_offset, force[:n]
    u = np.sqrt(np.clip(d.xr - d.xr[-1], 0.0, None))
    order = np.argsort(u)
    g_max = float(np.max(np.interp(np.sqrt(np.clip(x_true[n_up:n] - d.xr[-1], 0.0, None)), u[order],
                                   d.gr[order])))
    time_s = np.arange(n) * STEP_S
    if variant == "duplicated":
        x_meas, force, time_s = (np.repeat(a, 2) for a in (x_meas, force, time_s))
    _write_csv(path, c.scene.control, time_s, x_meas, force)
    reached = x_true[n - 1] < d.xr[-1]
    detached = np.flatnonzero(x_true[n_up:n] < d.xr[-1])  # rows past the turning point: force zero
    return {**TRUTH, "slip": slip, "sigma": sigma, "force_offset": offset, "x_offset": c.x_offset,
            "force_drift": DRIFT * f_peak if variant == "drift" else 0.0,
            "peak_force": f_peak, "rows": int(x_meas.size), "pull_off_in_data": bool(reached),
            "first_detached_row": int(n_up + detached[0]) if detached.size else None,
            "G_max_reached": min(g_max, TRUTH["work_of_adhesion"])}


def _write_csv(path: Path, control: str, t: np.ndarray, x: np.ndarray, force: np.ndarray) -> None:
    head, scale = ("displacement [um]", 1e6) if control == "displacement" else ("pressure [kPa]", 1e-3)
    rows = "\n".join(f"{a:.2f},{b:.8g},{c:.8g}" for a, b, c in zip(t, x * scale, force * 1e3))
    Path(path).write_text(f"time [s],{head},force [mN]\n{rows}\n", encoding="utf-8")
