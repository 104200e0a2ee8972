"""The contact stages of the exact membrane as shooting problems (one state each).

Each ``Stage`` knows its unknowns, residuals and fixed values, so a history is a continuation over
one parameter per stage: the contact radius ``a`` (making contact), the contact angle ``alpha``
(pinning) or the material coordinate of the contact edge ``rho_a`` (delamination). Under pressure
control ``p`` joins the unknowns and the gap ``d`` the residuals.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import cache
from operator import attrgetter

from ..errors import ConvergenceError
from .solve import solve_bracket, solve_path, solve_state
from .state import Config, State

__all__ = ["Stage", "making_contact", "pinning", "delamination", "onset", "branch_end"]


class PastVertical(ConvergenceError):
    """A solved state (residuals within tolerance) whose free membrane turns past vertical at the
    clamp: Case II, outside the model. Callers that bracket the Case I limit between solved states
    turn it into the domain's bound (``exact.history``)."""


@dataclass(frozen=True)
class Stage:
    """A one-parameter family of states."""

    cfg: Config
    edge: str
    fixed: dict
    unknowns: tuple
    residuals: tuple
    targets: dict
    param: str  # the continuation parameter: a key of ``fixed`` or of ``targets``
    scale: float = 0.0  # the predictor's variable (``march.abscissa``): < 0 making contact, > 0 delamination
    memo: dict = field(default_factory=dict, compare=False, repr=False)  # Jacobian reused along the path

    def solve(self, value: float, x0, tol: float = 1e-10) -> State:
        """The state at parameter ``value``, Newton from the guess ``x0`` (ordered as unknowns) to
        residuals below ``tol``."""
        fixed, targets = dict(self.fixed), dict(self.targets)
        value = float(value)
        if self.param in targets:
            targets[self.param] = value
        else:
            fixed[self.param] = value
        st = solve_state(self.cfg, self.edge, fixed, self.unknowns, x0, self.residuals, targets,
                         memo=self.memo, tol=tol)
        if not abs(st.theta_end) < 0.5 * math.pi:  # either way past vertical: Case II
            raise PastVertical("exact membrane: the free membrane turns past vertical at the clamp "
                                   "(Case II, outside the model: Case I only)",
                                   {**fixed, **targets, self.param: value, "lambda0": self.cfg.lambda0})
        return st

    def path(self, values, vs: list, xs: list, x0, tol: float = 1e-10) -> list:
        """The states at each of ``values`` in one compiled call, continuing from the solved
        parameters ``vs`` and unknowns ``xs`` (``x0`` when there are none): the states solved before
        the first failure (including a state past vertical at the clamp, which ``solve`` reports)."""
        return solve_path(self.cfg, self.edge, self.fixed, self.unknowns, self.residuals, self.targets,
                          self.param, values, vs, xs, x0, memo=self.memo, tol=tol, scale=self.scale)

    def bracket(self, x_m, g_m: float, w: float, top: float) -> tuple:
        """Steps in the parameter from 0 (the state with unknowns ``x_m`` and G = ``g_m``) until
        G >= w, in one compiled call (``solve.solve_bracket``)."""
        return solve_bracket(self.cfg, self.edge, self.fixed, self.unknowns, self.residuals, self.targets,
                             self.param, x_m, g_m, w, top, memo=self.memo)

    def x(self, st: State) -> list:
        """The unknowns of a solved state, as a start for the next one."""
        got = _getter(self.unknowns)(st)
        return list(got) if len(self.unknowns) > 1 else [got]


@cache
def _getter(names: tuple):
    return attrgetter(*names)


def _control(control: str, p: float | None, d: float | None):
    if control == "displacement":
        return {"p": p}, (), (), {}
    return {}, ("p",), ("d",), {"d": d}


def making_contact(cfg: Config, control: str, p=None, d=None) -> Stage:
    """Adhesionless, frictionless contact, parameter the contact radius ``a``."""
    fx, u, r, t = _control(control, p, d)
    return Stage(cfg, "continuous", fx, ("lc", "rho_a") + u, ("clamp", "a") + r, {**t, "a": 0.0}, "a", -1.0)


def pinning(cfg: Config, control: str, slip: str, m: State, p=None, d=None) -> Stage:
    """Contact pinning after the loading end ``m``, parameter the contact angle ``alpha``."""
    fx, u, r, t = _control(control, p, d)
    fx = {**fx, "rho_a": m.rho_a, "alpha": 0.0}
    if slip == "frictionless":
        return Stage(cfg, "frictionless", fx, ("lc",) + u, ("clamp",) + r, t, "alpha")
    return Stage(cfg, "given", {**fx, "lc": m.lc}, ("l1p",) + u, ("clamp",) + r, t, "alpha")


def onset(cfg: Config, control: str, slip: str, m: State, w: float, p=None, d=None) -> Stage:
    """The end of pinning (G = w at the pinned edge); its parameter is unused (``w``)."""
    fx, u, r, t = _control(control, p, d)
    fx = {**fx, "rho_a": m.rho_a}
    t = {**t, "w": w}
    if slip == "frictionless":
        return Stage(cfg, "frictionless", fx, ("lc", "alpha") + u, ("clamp", "G") + r, t, "w")
    return Stage(cfg, "given", {**fx, "lc": m.lc}, ("l1p", "alpha") + u, ("clamp", "G") + r, t, "w")


def delamination(cfg: Config, control: str, slip: str, m: State, w: float, p=None, d=None) -> Stage:
    """Quasi-static delamination (G = w), parameter the material coordinate of the edge ``rho_a``."""
    fx, u, r, t = _control(control, p, d)
    t = {**t, "w": w}
    fx = {**fx, "rho_a": m.rho_a}
    if slip == "frictionless":
        return Stage(cfg, "frictionless", fx, ("lc", "alpha") + u, ("clamp", "G") + r, t, "rho_a", m.rho_a)
    return Stage(cfg, "given", {**fx, "lc": m.lc}, ("l1p", "alpha") + u, ("clamp", "G") + r, t, "rho_a",
                 m.rho_a)


def branch_end(cfg: Config, control: str, m: State, w: float, p=None, d=None) -> Stage:
    """No slip, weak adhesion: where the quasi-static delamination branch ends (alpha = 0, the
    stretch mismatch alone releases w); unknowns lambda1+ and rho_a, parameter alpha (= 0)."""
    fx, u, r, t = _control(control, p, d)
    return Stage(cfg, "given", {**fx, "lc": m.lc, "alpha": 0.0}, ("l1p", "rho_a") + u,
                 ("clamp", "G") + r, {**t, "w": w}, "alpha")
