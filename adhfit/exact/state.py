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

import math
from dataclasses import dataclass

import numpy as np

from . import kernels as K

__all__ = ["Config", "State", "evaluate", "release_rate"]


@dataclass(frozen=True)
class Config:
    """Fixed data of a computation: pre-stretch, substrate curvature b/R_s, integration steps."""

    lambda0: float
    crv: float  # b / R_s (0 for a flat substrate)
    n: int = 64

    @property
    def beta(self) -> float:
        return 1.0 / self.lambda0


@dataclass
class State:
    """An exact-membrane state and its observables (dimensionless, DESIGN.md A1)."""

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
    t1p = K.tensions(l1p, l2)[0]
    q = l1m / l1p
    return (t1p * (1.0 - math.cos(alpha))
            + 0.5 * ((l1p - l1m) ** 2 / (l1m * l2) + (1.0 - 3.0 * q * q + 2.0 * q ** 3) / (l1m * l2) ** 3))


def _l1_frictionless(l1m: float, l2: float, alpha: float) -> float:
    """lambda1+ from t1(lambda1+, l2) cos(alpha) = t1(lambda1-, l2) (t1 increases with lambda1)."""
    target = K.tensions(l1m, l2)[0] / math.cos(alpha)
    x = l1m / math.cos(alpha) ** 0.5
    for _ in range(60):
        t, _ = K.tensions(x, l2)
        d1 = 1.0 / l2 + 3.0 / (x ** 4 * l2 ** 3)
        step = (t - target) / d1
        x = max(x - step, 0.5 * x)
        if abs(step) < 1e-15 * x:
            break
    return x


def _sphere_drop(a: float, crv: float) -> float:
    """Height of the substrate apex above the substrate at radius a: a^2/(rs + sqrt(rs^2 - a^2))."""
    return a * a * crv / (1.0 + math.sqrt(max(1.0 - (a * crv) ** 2, 0.0)))


def evaluate(cfg: Config, p: float, lc: float, rho_a: float = 0.0, alpha: float = 0.0,
             edge: str = "continuous", l1p: float | None = None) -> State:
    """Shoot one state from the apex to the clamp (see the module docstring for the arguments)."""
    beta, n = cfg.beta, cfg.n
    if rho_a <= 0.0:
        y = K.from_apex(K.FREE, lc, beta, n, p, K.A, K.B, K.C)
        return State(lc, 0.0, 0.0, p, 0.0, float(y[1]), 0.0, 0.0, float(y[0]), float(y[2]),
                     lc, lc, lc, float(y[4]), float(y[5]))
    yc = K.from_apex(K.CONTACT, lc, rho_a, n, cfg.crv, K.A, K.B, K.C)
    a, l1m = float(yc[0]), float(yc[1])
    l2 = a / rho_a
    if edge == "continuous":
        l1p = l1m
    elif edge == "frictionless":
        l1p = _l1_frictionless(l1m, l2, alpha)
    theta_a = alpha - math.asin(min(a * cfg.crv, 1.0))
    y0 = np.array([a, -_sphere_drop(a, cfg.crv), theta_a, l1p, yc[2], yc[3]])
    y = K.free_from_edge(y0, rho_a, beta, n, p, K.A, K.B, K.C)
    t1p = K.tensions(l1p, l2)[0]
    f = math.pi * a * (a * p - t1p * math.sin(theta_a))
    G = release_rate(alpha, l1p, l1m, l2)
    return State(lc, rho_a, alpha, p, a, float(y[1]), f, G, float(y[0]), float(y[2]),
                 l1m, l1p, l2, float(y[4]), float(y[5]))
