"""The options of ``adhfit.fit``: one shape for one curve or a series, least squares or MCMC, checked once.

No heavy imports: the command line builds its parser from the choice lists here for every command.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field, fields
from typing import Any

from ..errors import InputError
from ..membranes import membrane_choices
from ..params import METHODS, SLIP_CHOICES

__all__ = ["METHODS", "SLIP_CHOICES", "DEFAULT_POINTS", "MCMC_SETTINGS", "FitOptions"]

#: rows per computed history: interpolation error ~1e-4 of the largest force (see .model)
DEFAULT_POINTS = 150
#: MCMC settings a caller may override (:data:`.sampling.DEFAULTS` holds their defaults); every one a
#: positive integer
MCMC_SETTINGS = ("n_walkers", "n_ensembles", "tune_steps", "tune_rounds", "check_every", "max_steps",
                 "evidence_draws", "predictive_draws")


def _positive(name: str, value: Any, what: str) -> None:
    if value is not None and not (isinstance(value, (int, float)) and not isinstance(value, bool)
                                  and math.isfinite(value) and value > 0):
        raise InputError(name, value, f"a positive number in SI units ({what})")


def _choice(name: str, value: Any, choices: tuple) -> None:
    if value not in choices:
        raise InputError(name, value, "one of " + ", ".join(map(repr, choices)))


@dataclass(frozen=True)
class FitOptions:
    """Every option of a fit (``adhfit.fit``'s keywords), validated on construction.

    Attributes
    ----------
    method : {"lsq", "mcmc"}
    slip : {"auto", "no-slip", "frictionless"} or None
        None: each scene's ``[interface] slip`` (one value for a series, else ``auto``).
    membrane : {"auto", "large-stretch", "exact"} or None
        None: the scenes' ``[membrane] model`` (one value for a series, else ``auto``).
    sigma : float, optional
        Force noise σ, N, of every curve; default: estimated.
    sigma_contact_radius : float, optional
        Contact-radius noise, m; default: estimated.
    contact_radius : bool
        Fit a ``contact_radius`` column where a curve has one.
    fit_x_offset : bool, optional
        Fit the control offset (default: under displacement control only).
    fit_force_offset : bool
        Fit the load-cell zero.
    fit_force_drift : bool, optional
        Fit a linear drift of the load-cell zero over the test; default: where the rows before contact and
        after pull-off pin it (with the zero).
    seed : int, optional
        Recorded (least squares); the root of every random number (MCMC).
    points : int
        Rows per computed history.
    profile : bool
        Likelihood-profile intervals of the reported fit (least squares).
    stand_in : bool
        MCMC with the exact membrane: sample through the large-stretch model plus the exact model's
        difference, checked on posterior draws (:mod:`.stand_in`; the exact posterior is sampled
        directly when the check fails).  False: always sample the exact model (~10x slower).
    thin : bool
        Fit a curve of more than 6,000 rows as ~2,000 bins of consecutive rows (their means; the
        report says so, :func:`.segments.thin`); False fits every row, at a cost that grows with them.
    read_options : dict
        Keywords of :func:`adhfit.data.read_curve` for curves given as paths.
    outdir : path, optional
        MCMC: where ``chain.h5`` goes.
    workers : int, optional
        MCMC: processes (default: up to 2).
    progress : bool, optional
        MCMC: progress bar on standard error (default: on a terminal).
    mcmc : dict
        MCMC settings (:data:`MCMC_SETTINGS`).
    """

    method: str = "lsq"
    slip: str | None = None
    membrane: str | None = None
    sigma: float | None = None
    sigma_contact_radius: float | None = None
    contact_radius: bool = True
    fit_x_offset: bool | None = None
    fit_force_offset: bool = True
    fit_force_drift: bool | None = None
    seed: int | None = None
    points: int = DEFAULT_POINTS
    profile: bool = True
    thin: bool = True
    stand_in: bool = True
    read_options: dict = field(default_factory=dict)
    outdir: Any = None
    workers: int | None = None
    progress: bool | None = None
    mcmc: dict = field(default_factory=dict)

    def __post_init__(self) -> None:
        _choice("method", self.method, METHODS)
        if self.slip is not None:
            _choice("slip", self.slip, SLIP_CHOICES)
        if self.membrane is not None:
            _choice("membrane", self.membrane, membrane_choices())
        _positive("sigma", self.sigma, "N")
        _positive("sigma_contact_radius", self.sigma_contact_radius, "m")
        if not (isinstance(self.points, int) and not isinstance(self.points, bool) and 40 <= self.points <= 5000):
            raise InputError("points", self.points, "an integer in [40, 5000]")
        for flag in ("thin", "stand_in"):
            if not isinstance(getattr(self, flag), bool):
                raise InputError(flag, getattr(self, flag), "True or False")
        if self.seed is not None and not (isinstance(self.seed, int) and self.seed >= 0):
            raise InputError("seed", self.seed, "a non-negative integer")
        if self.workers is not None and not (isinstance(self.workers, int) and self.workers >= 1):
            raise InputError("workers", self.workers, "a positive integer")
        for key, value in self.mcmc.items():
            if key not in MCMC_SETTINGS:
                raise InputError(key, value, "an MCMC setting: one of " + ", ".join(MCMC_SETTINGS))
            if not (isinstance(value, int) and not isinstance(value, bool) and value > 0):
                raise InputError(key, value, "a positive integer")
        if self.method == "lsq":
            used = [k for k in ("outdir", "workers", "progress") if getattr(self, k) is not None]
            used += sorted(self.mcmc)
            if used:
                raise InputError(used[0], self.mcmc.get(used[0], getattr(self, used[0], None)),
                                 "absent with method='lsq' (an MCMC option)")

    @classmethod
    def from_keywords(cls, method: str = "lsq", **keywords: Any) -> "FitOptions":
        """Options from ``adhfit.fit``'s keywords: MCMC settings may be given flat (``n_walkers=8``) or in
        ``mcmc={...}``; an unknown keyword is one clear error naming it."""
        known = {f.name for f in fields(cls)}
        mcmc = dict(keywords.pop("mcmc", None) or {})
        for key in list(keywords):
            if key in MCMC_SETTINGS:
                mcmc[key] = keywords.pop(key)
            elif key not in known:
                raise InputError(key, keywords[key], "a keyword of adhfit.fit: " + ", ".join(sorted(known - {"mcmc"}))
                                 + ", or an MCMC setting (" + ", ".join(MCMC_SETTINGS) + ")")
        if keywords.get("read_options") is None:
            keywords.pop("read_options", None)
        return cls(method=method, mcmc=mcmc, **keywords)

    def as_dict(self) -> dict:
        """JSON-ready options for the provenance."""
        out = {f.name: getattr(self, f.name) for f in fields(self) if f.name not in ("outdir", "read_options")}
        out["outdir"] = None if self.outdir is None else str(self.outdir)
        return out
