"""Fits of measured curves: W_ad, μh and the slip condition (docs/contracts.md A5, B4).

Public names (imported on first use, so that ``adhfit simulate`` does not load lmfit):
:func:`fit` (the one entry point), :func:`fit_curve`, :func:`fit_global` (a test series as one fit), :class:`FitResult`, :class:`CurveModel`, :func:`synthetic_curve`.
"""
from __future__ import annotations

import importlib

__all__ = ["fit", "fit_curve", "fit_global", "FitResult", "SlipFit", "Estimate", "CurveModel", "synthetic_curve"]

_WHERE = {"fit": ".api", "fit_curve": ".fit", "fit_global": ".global_fit", "FitResult": ".result", "SlipFit": ".result", "Estimate": ".result",
          "CurveModel": ".model", "synthetic_curve": ".synthetic"}


def __getattr__(name: str):
    if name in _WHERE:
        return getattr(importlib.import_module(_WHERE[name], __name__), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
