"""Choices of ``adhfit fit`` shared by the library and the command line (no heavy imports: the CLI
builds its parser from these for every command)."""
from __future__ import annotations

__all__ = ["METHODS", "SLIP_CHOICES", "DEFAULT_POINTS"]

#: fitting methods (``mcmc`` is accepted by the parser and refused until it is implemented)
METHODS = ("lsq", "mcmc")
#: slip choices of a fit: ``auto`` fits both conditions and compares them
SLIP_CHOICES = ("auto", "no-slip", "frictionless")
#: rows per computed history: interpolation error ~1e-4 of the largest force (see .model)
DEFAULT_POINTS = 150
