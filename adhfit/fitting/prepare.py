"""What every fit does first and last: read and check its inputs, and record where its numbers came from.

Shared by the least-squares (:mod:`.fit`), MCMC (:mod:`.mcmc_fit`) and series (:mod:`.global_fit`)
fits, so that they read data, reject options and write provenance the same way.
"""
from __future__ import annotations

import dataclasses
import math
import platform
from pathlib import Path

from ..errors import InputError
from .options import METHODS, SLIP_CHOICES
from .result import SlipFit

__all__ = ["read_inputs", "check_options", "segments_report", "provenance"]


def read_inputs(data, scene, read_options=None):
    """The curve and the scene as objects: paths are read (``read_options``: :func:`adhfit.data.read_curve`'s
    keywords), and their control modes must agree."""
    from ..data import read_curve  # noqa: PLC0415
    from ..scene import Scene, load_scene  # noqa: PLC0415
    if not isinstance(scene, Scene):
        scene = load_scene(scene)
    curve = read_curve(data, scene.control, **(read_options or {})) if isinstance(data, (str, Path)) else data
    if curve.control != scene.control:
        raise InputError("control", curve.control, f"'{scene.control}' (the scene's control mode)")
    return curve, scene


def check_options(method, slip, sigma, points, membrane="auto"):
    """Raise :class:`~adhfit.errors.InputError` for an option outside its range (one line naming it)."""
    from ..scene import MEMBRANE_MODELS  # noqa: PLC0415
    if membrane not in MEMBRANE_MODELS:
        raise InputError("membrane", membrane, "one of " + ", ".join(map(repr, MEMBRANE_MODELS)))
    if method not in METHODS:
        raise InputError("method", method, "one of 'lsq', 'mcmc'")
    if slip not in SLIP_CHOICES:
        raise InputError("slip", slip, "one of " + ", ".join(map(repr, SLIP_CHOICES)))
    if sigma is not None and not (isinstance(sigma, (int, float)) and math.isfinite(sigma) and sigma > 0):
        raise InputError("sigma", sigma, "a positive force noise in N")
    if not (isinstance(points, int) and 40 <= points <= 5000):
        raise InputError("points", points, "an integer in [40, 5000]")


def segments_report(seg, rep: SlipFit) -> dict:
    """Row-order segments of the report: the end of loading from the data, pull-off from the fit."""
    d = seg.as_dict()
    j = rep.split
    n = seg.n
    d.update({"i_jump": j, "n_attached": (n if j is None else j) - seg.i_turn - 1,
              "n_detached": 0 if j is None else n - j, "jump_from": "fitted model (its turning point)"})
    if j is not None and rep.predicted is not None:
        d["jump"] = float(abs(rep.predicted[j - 1] - rep.predicted[j]))
    return d


def provenance(curve, scene, seed, method, options) -> dict:
    """Where the numbers came from: adhfit and library versions, the input and its SHA-256, the scene,
    the seed, the method and its options."""
    import lmfit  # noqa: PLC0415
    import numpy  # noqa: PLC0415
    import scipy  # noqa: PLC0415
    from .. import __version__  # noqa: PLC0415
    fields = {f.name: getattr(scene, f.name) for f in dataclasses.fields(scene) if f.name != "source"}
    return {"adhfit_version": __version__, "input": curve.path, "input_sha256": curve.sha256,
            "scene_file": scene.source, "scene": fields, "seed": seed, "method": method, "options": options,
            "backend": "numba", "python": platform.python_version(), "numpy": numpy.__version__,
            "scipy": scipy.__version__, "lmfit": lmfit.__version__}
