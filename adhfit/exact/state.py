"""One equilibrium state of the exact membrane, shot from the apex to the clamp.

A state is fixed by the centre stretch ``lc`` (of the contact field, or of the free membrane), the
material coordinate of the contact edge ``rho_a`` (0: no contact), the contact angle ``alpha`` and
how lambda1 jumps at the contact edge (``edge``):

- ``"continuous"``: lambda1+ = lambda1- (adhesionless making contact, alpha = 0);
- ``"frictionless"``: T1+ cos(alpha) = T1- fixes lambda1+ (paper eq. 53 with exact tensions);
- ``"given"``: lambda1+ = ``l1p`` (no slip: the shear traction at the edge takes the difference).

The contact field is the frictionless field on the substrate grown from the apex with centre
stretch ``lc`` (for no slip: the field frozen at the end of loading, i.e. ``lc`` of that state).
"""
from __future__ import annotations

from dataclasses import dataclass

from . import kernels as K

__all__ = ["Config", "State", "evaluate", "release_rate", "DEFAULT_N"]

DEFAULT_N = 8  # steps per segment (contact segments 1.3 n, free inflation 3 n: kernels.py), the least n
# whose worst error over lambda0 = 1.1-3 and the four base cases is over 10x below issue 11's 1e-6 on
# every row against n = 128 (benchmarks/results/exact_n.md)


@dataclass(frozen=True)
class Config:
    """Fixed data of a computation: pre-stretch, substrate curvature b/R_s, integration steps."""

    lambda0: float
    crv: float  # b / R_s (0 for a flat substrate)
    n: int = DEFAULT_N

    @property
    def beta(self) -> float:
        return 1.0 / self.lambda0


@dataclass
class State:
    """An exact-membrane state and its observables (dimensionless, docs/contracts.md A1)."""

    lc: float
    rho_a: float
    alpha: float
    p: float
    a: float
    d: float
    f: float
    G: float
    r_end: float
    theta_end: float
    l1m: float
    l1p: float
    l2a: float
    u: float
    v: float


def release_rate(alpha: float, l1p: float, l1m: float, l2: float) -> float:
    """Energy release rate over mu h, paper eq. (23) with the exact tension T1+."""
    return float(K.release_rate(alpha, l1p, l1m, l2))


_LAST: dict = {}


def _contact(cfg: Config, lc: float, rho_a: float):
    """The contact field's end state, remembered for the last (lc, rho_a): Newton steps and
    difference quotients in alpha or lambda1+ (no slip) do not change it."""
    key = (lc, rho_a, cfg.crv, cfg.n)
    last = _LAST.get("v")  # one (key, value) tuple: read and written atomically (threads)
    if last is not None and last[0] == key:
        return last[1]
    yc = K.from_apex(K.CONTACT, lc, rho_a, cfg.n, cfg.crv, K.A, K.B, K.C)
    _LAST["v"] = (key, yc)
    return yc


_EDGES = {"continuous": K.CONTINUOUS, "frictionless": K.FRICTIONLESS, "given": K.GIVEN}


def evaluate(cfg: Config, p: float, lc: float, rho_a: float = 0.0, alpha: float = 0.0,
             edge: str = "continuous", l1p: float | None = None) -> State:
    """Shoot one state from the apex to the clamp (see the module docstring for the arguments)."""
    rho_a = max(rho_a, 0.0)
    l1 = 0.0 if l1p is None else l1p
    if rho_a == 0.0:
        o = K.shot(_EDGES[edge], p, cfg.crv, cfg.beta, cfg.n, lc, 0.0, alpha, l1, K.A, K.B, K.C)
    else:
        o = K.shot_from_edge(_EDGES[edge], p, cfg.crv, cfg.beta, cfg.n, _contact(cfg, lc, rho_a), rho_a,
                             alpha, l1, K.A, K.B, K.C)
    r_end, d, th, a, f, G, l1m, l1p_, l2, u, v = (float(x) for x in o)
    return State(lc, rho_a, alpha, p, a, d, f, G, r_end, th, l1m, l1p_, l2, u, v)
