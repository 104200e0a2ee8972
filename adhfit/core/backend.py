"""The engine's branch functions, dispatched to the compiled kernels or to the numpy reference.

``evaluate``, ``solve_state``, ``derivative`` and ``check_ok`` have exactly the signatures and return
types of :mod:`.branches` (Branch objects in, dicts of arrays out) and the same semantics; by default
they run the numba kernels of :mod:`.compiled` (~50x less overhead per call). numba is imported on
the first call, not when adhfit is imported.

Backend choice, read at every call: the environment variable ``ADHFIT_BACKEND`` = ``numpy`` selects
:mod:`.branches`; ``numba`` requires the compiled kernels (ImportError without numba); unset or
``auto`` uses numba when it is installed and numpy otherwise.
"""
from __future__ import annotations

import math
import os

import numpy as np

from ..errors import ConvergenceError
from . import branches
from .branches import Branch, Context

__all__ = ["evaluate", "solve_state", "derivative", "check_ok", "active"]

#: environment variable that selects the backend
ENV = "ADHFIT_BACKEND"
_KEYS = ("a", "alpha", "p", "d", "f", "G", "J0")
_CODES = {("making_contact", "no-slip"): 0, ("making_contact", "frictionless"): 0,
          ("pinning", "no-slip"): 1, ("pinning", "frictionless"): 2,
          ("delamination", "no-slip"): 3, ("delamination", "frictionless"): 4}
_kernels = None       # the compiled module once imported; False when numba is missing


def _compiled():
    """The compiled kernels, or None when the numpy backend is selected or numba is missing."""
    global _kernels
    choice = os.environ.get(ENV, "auto")
    if choice == "numpy":
        return None
    if _kernels is None:
        try:
            from . import compiled
        except ImportError:
            if choice == "numba":
                raise
            _kernels = False
        else:
            _kernels = compiled
    elif _kernels is False and choice == "numba":
        from . import compiled  # noqa: F401  (raises the ImportError)
    return _kernels or None


def active() -> str:
    """Name of the backend the next call will use: ``"numba"`` or ``"numpy"``."""
    return "numpy" if _compiled() is None else "numba"


def _ctx(ctx: Context):
    return float(ctx.c), float(ctx.w), float(ctx.a_m), float(ctx.L_m)


def _flat(v, dtype, shape):
    """``v`` as a contiguous 1-D array of ``dtype`` with the elements of ``shape`` (no copy if it is one)."""
    a = np.asarray(v, dtype)
    if a.shape == shape:
        return a.ravel()
    if a.ndim == 0:
        return np.full(math.prod(shape), a)
    return np.broadcast_to(a, shape).ravel()


def _shape(*vs):
    shapes = [np.shape(v) for v in vs if v is not None]
    s = shapes[0]
    for t in shapes[1:]:
        if t != s:
            return np.broadcast_shapes(*shapes)
    return s


def _unflat(out, shape, keys=_KEYS):
    if out.shape[1:] == shape:
        return {k: out[i] for i, k in enumerate(keys)}
    return {k: out[i].reshape(shape) for i, k in enumerate(keys)}


def evaluate(branch: Branch, x, kappa, loc, ctx: Context) -> dict:
    """All observables of the states (x, kappa) at locators ``loc``; complex-safe.

    Same as :func:`.branches.evaluate`: ``a, alpha, p, d, f, G, J0, ok`` arrays, complex when any
    input is complex (complex-step derivatives), ``ok`` False outside the model.
    """
    K = _compiled()
    if K is None:
        return branches.evaluate(branch, x, kappa, loc, ctx)
    cplx = np.iscomplexobj(kappa) or np.iscomplexobj(loc) or np.iscomplexobj(x)
    dtype = np.complex128 if cplx else np.float64
    shape = _shape(x, kappa, loc)
    lf = _flat(loc, dtype, shape)
    xf = lf if x is None else _flat(x, dtype, shape)
    c, w, a_m, _ = _ctx(ctx)
    out, ok = K.evaluate_batch(_CODES[branch.stage, branch.slip], xf, _flat(kappa, dtype, shape),
                               lf, c, w, a_m)
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
        When any row's solve fails, with that row's inputs.
    """
    K = _compiled()
    if K is None:
        return branches.solve_state(branch, loc, ctx, kappa=kappa, d_fix=d_fix, kappa0=kappa0, x0=x0)
    loc = np.asarray(loc, float)
    shape = loc.shape
    implicit = branch.target is not None
    pressure = d_fix is not None
    if not pressure:
        kappa = np.broadcast_to(np.asarray(kappa, float), shape)
        if not implicit:
            return None, kappa
        k = kappa.ravel()
    else:
        k = _flat(kappa0, np.float64, shape)
    lf = loc.ravel()
    # as solve_unknown: any non-finite start value sends every row to the middle of its bracket
    has_x0 = x0 is not None and not pressure and bool(np.all(np.isfinite(x0)))
    xf = _flat(x0, np.float64, shape) if has_x0 else lf
    c, w, a_m, L_m = _ctx(ctx)
    xs, ks, status = K.solve_batch(_CODES[branch.stage, branch.slip], pressure, lf, k, xf, has_x0,
                                   c, w, a_m, L_m, float(d_fix) if pressure else 0.0)
    if status.any():
        _raise(branch, K, status, lf, k, ctx, pressure, d_fix)
    xs = xs.reshape(shape) if implicit else None
    return xs, (ks.reshape(shape) if pressure else kappa)


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
    shape = _shape(loc, x, kappa)
    lf = _flat(loc, np.float64, shape)
    xf = lf if x is None else _flat(np.real(x), np.float64, shape)
    c, w, a_m, L_m = _ctx(ctx)
    out = K.derivative_batch(_CODES[branch.stage, branch.slip], bool(pressure_control), lf, xf,
                             _flat(np.real(kappa), np.float64, shape), c, w, a_m, L_m)
    return _unflat(out, shape)


def check_ok(state: dict, what: str, inputs: dict) -> None:
    """Raise ConvergenceError when a solved state is outside the model or not finite."""
    K = _compiled()
    if K is None:
        return branches.check_ok(state, what, inputs)
    ok = np.asarray(state["ok"], bool).ravel()
    vals = np.stack([np.broadcast_to(np.real(state[k]), state["ok"].shape).ravel()
                     for k in ("a", "alpha", "p", "d", "f", "G")])
    i = K.first_bad(ok, vals)
    if i >= 0:
        raise ConvergenceError(f"{what}: state outside the model's domain (free membrane past "
                               f"vertical at the clamp, or no real solution)",
                               {**inputs, "index": i})
