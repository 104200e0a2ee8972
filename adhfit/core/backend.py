"""The engine's branch functions, dispatched to the compiled kernels or to the numpy reference.

``evaluate``, ``solve_state``, ``derivative`` and ``check_ok`` have exactly the signatures and return
types of :mod:`.branches` (Branch objects in, dicts of arrays out) and the same semantics; by default
they run the numba kernels of :mod:`.compiled` (~50x less overhead per call). numba is imported on
the first call, not when adhfit is imported.

Backend choice: ``with use("numpy"):`` (or ``"numba"``) selects one explicitly for a block and
restores the previous choice after it. Otherwise the environment variable ``ADHFIT_BACKEND``, read
once at the first call, decides: ``numpy`` selects :mod:`.branches`; ``numba`` requires the compiled
kernels (ImportError without numba); unset or ``auto`` uses numba when it is installed.
"""
from __future__ import annotations

import math
import os
from contextlib import contextmanager

import numpy as np

from ..errors import ConvergenceError
from . import branches, continuation
from .branches import Branch, Context

__all__ = ["evaluate", "solve_state", "compiled_kernels", "derivative", "check_ok", "solve_rows", "mc_pressure", "follow",
           "extremum", "active", "use", "ENV"]

#: environment variable that selects the backend
ENV = "ADHFIT_BACKEND"
_CHOICES = ("auto", "numba", "numpy")
_KEYS = ("a", "alpha", "p", "d", "f", "G", "J0")
_CODES = {("making_contact", "no-slip"): 0, ("making_contact", "frictionless"): 0,
          ("pinning", "no-slip"): 1, ("pinning", "frictionless"): 2,
          ("delamination", "no-slip"): 3, ("delamination", "frictionless"): 4}
#: the resolved backend: the compiled module, or None for numpy; unresolved until first use
_UNSET = object()
_F64 = np.dtype(np.float64)
_active = _UNSET


def _resolve(choice: str):
    if choice not in _CHOICES:
        raise ValueError(f"The '{ENV}' setting must be one of {', '.join(_CHOICES)}. Got {choice!r} instead.")
    if choice == "numpy":
        return None
    try:
        from . import compiled
    except ImportError:
        if choice == "numba":
            raise
        return None
    return compiled


def _compiled():
    """The compiled kernels, or None when the numpy backend is in use."""
    global _active
    if _active is _UNSET:
        _active = _resolve(os.environ.get(ENV, "auto").strip().lower() or "auto")
    return _active


def compiled_kernels():
    """The compiled kernel module when the numba backend is in use, else None."""
    return _compiled()


def active() -> str:
    """Name of the backend in use: ``"numba"`` or ``"numpy"``."""
    return "numpy" if _compiled() is None else "numba"


@contextmanager
def use(name: str):
    """Run a block with backend ``name`` ("numba", "numpy" or "auto"); the previous choice is restored."""
    global _active
    previous = _active
    _active = _resolve(name)
    try:
        yield
    finally:
        _active = previous


def _code(branch: Branch) -> int:
    return _CODES[branch.stage, branch.slip]


def _ctx(ctx: Context):
    return float(ctx.c), float(ctx.w), float(ctx.a_m), float(ctx.L_m)


def _flat(a: np.ndarray, dtype, shape) -> np.ndarray:
    """``a`` as a contiguous 1-D array of ``dtype`` with the elements of ``shape`` (no copy if it is one)."""
    if a.dtype != dtype:
        a = a.astype(dtype)
    if a.shape == shape:
        return a.ravel()
    if a.ndim == 0:
        return np.full(math.prod(shape), a)
    return np.broadcast_to(a, shape).ravel()


def _unflat(out, shape):
    if out.shape[1:] == shape:
        return {k: out[i] for i, k in enumerate(_KEYS)}
    return {k: out[i].reshape(shape) for i, k in enumerate(_KEYS)}


def evaluate(branch: Branch, x, kappa, loc, ctx: Context) -> dict:
    """All observables of the states (x, kappa) at locators ``loc``; complex-safe.

    Same as :func:`.branches.evaluate`: ``a, alpha, p, d, f, G, J0, ok`` arrays, complex when any
    input is complex (complex-step derivatives), ``ok`` False outside the model.
    """
    K = _compiled()
    if K is None:
        return branches.evaluate(branch, x, kappa, loc, ctx)
    loc, kappa = np.asarray(loc), np.asarray(kappa)
    x = loc if x is None else np.asarray(x)
    cplx = loc.dtype.kind == "c" or kappa.dtype.kind == "c" or x.dtype.kind == "c"
    dtype = np.dtype(np.complex128 if cplx else np.float64)
    shape = loc.shape
    if kappa.shape != shape or x.shape != shape:
        shape = np.broadcast_shapes(x.shape, kappa.shape, shape)
    lf = _flat(loc, dtype, shape)
    c, w, a_m, _ = _ctx(ctx)
    out, ok = K.evaluate_batch(_code(branch), lf if x is loc else _flat(x, dtype, shape),
                               _flat(kappa, dtype, shape), lf, c, w, a_m)
    res = _unflat(out, shape)
    res["ok"] = ok if ok.shape == shape else ok.reshape(shape)
    return res


def _raise(branch, K, status, loc, kappa, ctx, pressure, d_fix):
    i = int(np.flatnonzero(status)[0])
    s = int(status[i])
    unknown = "t" if branch.slip == "no-slip" else "a"
    if s == K.FAIL_OUTER:
        what = f"{branch.stage} ({branch.slip}): pressure from the fixed gap: no convergence in 60 iterations"
    elif s == K.FAIL_BRACKET:
        what = f"{branch.stage} ({branch.slip}): {unknown} from the material condition: no sign change on the bracket"
    else:
        what = f"{branch.stage} ({branch.slip}): {unknown} from the material condition: no convergence in 60 iterations"
    inputs = {"w": ctx.w, "rs": 1 / ctx.c if ctx.c else np.inf, "a_m": ctx.a_m}
    if pressure:
        inputs.update(d=d_fix, kappa0=float(kappa[i]))
    else:
        inputs["kappa"] = float(kappa[i])
    inputs.update({branch.locator: float(loc[i]), "index": i,
                   "unconverged": int(np.count_nonzero(status))})
    raise ConvergenceError(what, inputs)


def solve_state(branch: Branch, loc, ctx: Context, *, kappa=None, d_fix=None, kappa0=None, x0=None):
    """Solve the state(s) at real locators ``loc`` (see :func:`.branches.solve_state`).

    Displacement control: give ``kappa``. Pressure control: give ``d_fix`` and a start ``kappa0``.

    Returns
    -------
    x, kappa : ndarray or None, ndarray

    Raises
    ------
    ConvergenceError
        When the solve of any row fails, with that row's inputs.
    """
    K = _compiled()
    if K is None:
        return branches.solve_state(branch, loc, ctx, kappa=kappa, d_fix=d_fix, kappa0=kappa0, x0=x0)
    loc = np.asarray(loc, float)
    shape = loc.shape
    f64 = np.dtype(np.float64)
    implicit = branch.target is not None
    pressure = d_fix is not None
    k = _flat(np.asarray(kappa0 if pressure else kappa, float), f64, shape)
    if not pressure and not implicit:
        return None, k.reshape(shape)
    lf = loc.ravel()
    has_x0 = x0 is not None
    xf = _flat(np.asarray(x0, float), f64, shape) if has_x0 else lf
    c, w, a_m, L_m = _ctx(ctx)
    xs, ks, status = K.solve_batch(_code(branch), pressure, lf, k, xf, has_x0, c, w, a_m, L_m,
                                   float(d_fix) if pressure else 0.0)
    if status.any():
        _raise(branch, K, status, lf, k, ctx, pressure, d_fix)
    if xs.shape != shape:
        xs, ks = xs.reshape(shape), ks.reshape(shape)
    return (xs if implicit else None), ks


def solve_rows(branch: Branch, loc, ctx: Context, *, kappa=None, d_fix=None, kappa0=None, x0=None):
    """:func:`solve_state` and :func:`evaluate` at the solved states, in one compiled call.

    Returns
    -------
    x, kappa, state : ndarray or None, ndarray, dict
        ``state`` as :func:`evaluate` returns it (real), plus ``first_bad``: the index of the first
        state outside the model or with a non-finite observable (-1 if none; what :func:`check_ok`
        raises for). The numpy backend leaves ``first_bad`` out.

    Raises
    ------
    ConvergenceError
        As :func:`solve_state`.
    """
    K = _compiled()
    if K is None:
        x, k = branches.solve_state(branch, loc, ctx, kappa=kappa, d_fix=d_fix, kappa0=kappa0, x0=x0)
        return x, k, branches.evaluate(branch, x, k, loc, ctx)
    loc = np.ascontiguousarray(loc, dtype=float)
    shape = loc.shape
    implicit = branch.target is not None
    pressure = d_fix is not None
    k = _flat(np.asarray(kappa0 if pressure else kappa, float), _F64, shape)
    lf = loc.ravel()
    has_x0 = x0 is not None
    xf = _flat(np.asarray(x0, float), _F64, shape) if has_x0 else lf
    c, w, a_m, L_m = _ctx(ctx)
    xs, ks, status, out, ok, bad = _paths().solve_observe_batch(
        _code(branch), pressure, lf, k, xf, has_x0, c, w, a_m, L_m, float(d_fix) if pressure else 0.0)
    if (implicit or pressure) and bad >= 0 and status.any():
        _raise(branch, K, status, lf, k, ctx, pressure, d_fix)
    res = _unflat(out, shape)
    res["ok"] = ok.reshape(shape)
    res["first_bad"] = int(bad)
    return (xs.reshape(shape) if implicit else None), ks.reshape(shape), res


def mc_pressure(a, ctx: Context, d_fix: float, lo, hi):
    """Pressure control, making contact: kappa with the gap d_fix (see :func:`.branches.mc_pressure`).

    Raises
    ------
    ConvergenceError
        When a row has no sign change on its bracket or does not converge.
    """
    K = _compiled()
    if K is None:
        return branches.mc_pressure(a, ctx, d_fix, lo, hi)
    a = np.ascontiguousarray(a, dtype=float)
    lo = np.ascontiguousarray(np.broadcast_to(lo, a.shape), dtype=float).ravel()
    hi = np.ascontiguousarray(np.broadcast_to(hi, a.shape), dtype=float).ravel()
    ks, status = K.mc_pressure_batch(a.ravel(), float(ctx.c), float(d_fix), lo, hi)
    if status.any():
        i = int(np.flatnonzero(status)[0])
        what = ("no sign change on the bracket" if status[i] == K.FAIL_BRACKET else
                "the bracket closed on a point outside the domain")
        raise ConvergenceError(f"making contact: pressure from the fixed gap: {what}",
                               {"d": d_fix, "index": i, "lo": lo[i], "hi": hi[i]})
    return ks.reshape(a.shape)


def derivative(branch: Branch, loc, ctx: Context, x, kappa, *, pressure_control: bool) -> dict:
    """d(observable)/d(locator) along the branch at solved states (see :func:`.branches.derivative`).

    Returns
    -------
    dict
        ``a, alpha, p, d, f, G, J0`` float arrays.
    """
    K = _compiled()
    if K is None:
        return branches.derivative(branch, loc, ctx, x, kappa, pressure_control=pressure_control)
    loc, kappa = np.asarray(loc, float), np.real(kappa)
    x = loc if x is None else np.real(x)
    shape = loc.shape
    if np.shape(kappa) != shape or x.shape != shape:
        shape = np.broadcast_shapes(x.shape, np.shape(kappa), shape)
    f64 = np.dtype(np.float64)
    lf = _flat(loc, f64, shape)
    c, w, a_m, L_m = _ctx(ctx)
    out = K.derivative_batch(_code(branch), bool(pressure_control), lf,
                             lf if x is loc else _flat(x, f64, shape),
                             _flat(np.asarray(kappa, float), f64, shape), c, w, a_m, L_m)
    return _unflat(out, shape)


_CHECKED = ("a", "alpha", "p", "d", "f", "G")


def check_ok(state: dict, what: str, inputs: dict) -> None:
    """Raise ConvergenceError when a solved state is outside the model or not finite.

    Same as :func:`.branches.check_ok`; real 1-D states (the common case) are checked compiled.
    """
    K = _compiled()
    ok = state["ok"]
    vals = [state[k] for k in _CHECKED]
    if (K is None or not isinstance(ok, np.ndarray) or ok.ndim != 1
            or any(not isinstance(v, np.ndarray) or v.dtype != np.float64 or v.shape != ok.shape
                   for v in vals)):
        return branches.check_ok(state, what, inputs)
    i = K.first_bad(ok, *vals)
    if i >= 0:
        raise ConvergenceError(f"{what}: state outside the model's domain (free membrane past "
                               f"vertical at the clamp, or no real solution)",
                               {**inputs, "index": i})


# ----------------------------------------------------------------------------------------------
# continuation and extrema (continuation.py / compiled.py)

def _paths():
    """The compiled kernels (called only when the numba backend is active)."""
    return _compiled()


def follow(branch: Branch, l0, targets, x0, k0, ctx: Context, d_fix, *, log: bool,
           sqrt: bool = False, max_steps: int = 2000, allow_end: bool = False):
    """Follow a branch from a solved state through target locators (see :func:`.continuation.follow`).

    Returns
    -------
    at_targets, path : tuple of ndarray
        (locators, x, kappa) at the targets reached and at every accepted step.
    """
    K = _compiled()
    if K is None:
        return continuation.follow(branch, l0, targets, x0, k0, ctx, d_fix, log=log, sqrt=sqrt,
                                   max_steps=max_steps, allow_end=allow_end)
    P = _paths()
    targets = np.atleast_1d(np.asarray(targets, float))
    c, w, a_m, L_m = _ctx(ctx)
    pressure = d_fix is not None
    scale = P.SCALE_LOG if log else (P.SCALE_SQRT if sqrt else P.SCALE_LINEAR)
    status, n_out, ox, ok_, pl, px, pk, _, _ = P.follow_kernel(
        _code(branch), pressure, float(l0), targets, math.nan if x0 is None else float(x0),
        float(k0), c, w, a_m, L_m, float(d_fix) if pressure else 0.0, scale, int(max_steps),
        bool(allow_end))
    if status == P.F_STEPS:
        raise ConvergenceError(f"{branch.stage} ({branch.slip}): too many continuation steps",
                               {"locator": float(pl[-1]), "d": d_fix, "w": ctx.w})
    if status == P.F_STALLED:
        raise ConvergenceError(f"{branch.stage} ({branch.slip}): continuation stalled (the state "
                               f"leaves the model's domain)",
                               {"locator": float(pl[-1]), "kappa": float(pk[-1]), "d": d_fix,
                                "w": ctx.w})
    return (targets[:n_out], ox[:n_out], ok_[:n_out]), (pl, px, pk)


def extremum(branch: Branch, lo: float, hi: float, ctx: Context, d_fix, kappa, key: str,
             sign: float, rows):
    """The state in [lo, hi] where ``sign * key`` is largest (see :func:`.continuation.extremum`).

    Returns
    -------
    loc, state : float, dict
        ``state`` has ``a, alpha, p, d, f, G, J0`` (1-element float arrays) and ``ok``.
    """
    K = _compiled()
    if K is None:
        return continuation.extremum(branch, lo, hi, ctx, d_fix, kappa, key, sign, rows)
    P = _paths()
    rl, rx, rk = (np.ascontiguousarray(r, dtype=float) for r in rows)
    c, w, a_m, L_m = _ctx(ctx)
    pressure = d_fix is not None
    status, loc, obs, ok = P.extremum_kernel(
        _code(branch), pressure, float(lo), float(hi), rl, rx, rk,
        0.0 if pressure else float(kappa), c, w, a_m, L_m, float(d_fix) if pressure else 0.0,
        P.KEY_CODES[key], float(sign), continuation.BRENT_XTOL, continuation.BRENT_RTOL,
        continuation.BRENT_MAXITER)
    if status != P.E_OK:
        what = {P.E_SOLVE: "the state does not solve", P.E_SEARCH: "a solve in the root search failed",
                P.E_NOCONV: f"no convergence in {continuation.BRENT_MAXITER} iterations"}[status]
        raise ConvergenceError(f"{branch.stage} ({branch.slip}): extremum of {key}: {what}",
                               {"lo": float(lo), "hi": float(hi), branch.locator: float(loc)})
    state = {k: obs[i:i + 1] for i, k in enumerate(_KEYS)}
    state["ok"] = np.array([bool(ok)])
    state["first_bad"] = 0 if not (ok and all(math.isfinite(v) for v in obs[:6])) else -1
    return float(loc), state
