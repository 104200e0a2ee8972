"""Fits of measured curves: W_ad, μh and the slip condition (docs/contracts.md A5, A7, B4).

Public names (imported on first use, so that ``adhfit simulate`` does not load lmfit):
:func:`fit` (the one entry point: one curve or a series, least squares or MCMC), :class:`FitResult`,
:class:`FitOptions`, :class:`CurveModel`.  Synthetic measured curves: :mod:`adhfit.synthetic`.
"""
from __future__ import annotations

import importlib

__all__ = ["fit", "FitResult", "FitOptions", "SlipFit", "Estimate", "CurveModel"]

_WHERE = {"fit": ".api", "FitResult": ".result", "FitOptions": ".options", "SlipFit": ".result", "Estimate": ".result",
          "CurveModel": ".model"}


def __getattr__(name: str):
    if name in _WHERE:
        return getattr(importlib.import_module(_WHERE[name], __name__), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
