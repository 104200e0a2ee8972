"""Test planning (docs/contracts.md A8, docs/planning.md): which protocol decides W_ad, μh and the slip.

Public names (imported on first use): :func:`plan`, :class:`Plan`, :class:`Protocol`.
"""
from __future__ import annotations

import importlib

__all__ = ["plan", "Plan", "Protocol"]

_WHERE = {"plan": ".api", "Plan": ".api", "Protocol": ".protocols"}


def __getattr__(name: str):
    if name in _WHERE:
        return getattr(importlib.import_module(_WHERE[name], __name__), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
