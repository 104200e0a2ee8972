"""The no-slip delamination branch's own end, alpha = 0, solved on it (issue 24).

On that branch G = w ties the edge stretch ratio t to the contact angle (eq. 62):
(t - 1)^2 / 2 + t (1 - cos alpha) = w, so alpha -> 0 where t meets 1 -+ sqrt(2 w), and t - t_end
varies with alpha^2. The continuation, which solves for t at each contact radius a, therefore stops
~1e-7 in alpha short of the end (t within 1e-12 of its bound), and an extremum lying at the end
(f_min and the turning point of a weakly adhering no-slip history) came out ~1e-7 off, differently
on every row grid. Here t is held at its bound and the radius a (with the pressure under pressure
control) is solved instead: the material condition (eq. 61), and the gap.
"""
from __future__ import annotations

import math

import numpy as np

from .branches import DEL_NS, admissible, material_residual, observe, state, unpack
from .jit import jit
from .newton import STEP

__all__ = ["END_ALPHA", "END_ULPS", "END_MAXITER", "END_GOLDEN", "end_stretch", "solve_end", "stretch_at",
           "end_extremum"]

#: the continuation's last state counts as next to the branch end below this contact angle (it
#: stops ~1e-7 short of alpha = 0; a stall elsewhere is not the end)
END_ALPHA = 1e-5

#: floats of t tried on either side of 1 -+ sqrt(2 w) for one whose eq. (62) angle is exactly 0
END_ULPS = 64
#: Newton iterations of the end solve (it starts ~1e-7 away: a few suffice)
END_MAXITER = 40


@jit
def end_stretch(t_last, w):
    """The t of the branch end next to ``t_last``: the float nearest 1 -+ sqrt(2 w) whose angle
    alpha (eq. 62 as :func:`.branches.unpack` evaluates it) is exactly 0, else the one with the least
    alpha; NaN if none is finite."""
    s = math.sqrt(2.0 * w)
    t0 = 1.0 - s if abs(t_last - (1.0 - s)) <= abs(t_last - (1.0 + s)) else 1.0 + s
    best, a_best = math.nan, math.inf
    for side in (1.0, -1.0):
        t = t0
        for _ in range(END_ULPS):
            alpha = unpack(DEL_NS, t, 0.0, 1.0, 0.0, w, 1.0)[1]
            if math.isfinite(alpha) and alpha < a_best:
                best, a_best = t, alpha
                if alpha == 0.0:
                    return t
            t = np.nextafter(t, side * math.inf)
    return best


@jit
def solve_end(pressure, t_end, a0, k0, c, w, a_m, L_m, d_fix, obs):
    """The end state (a, kappa) from (a0, k0), t held at ``t_end``: Newton on the material condition
    (and the gap under pressure control) with complex-step derivatives. Its observables go to
    ``obs``; returns (a, kappa, solved)."""
    a, k = a0, k0
    tc = complex(t_end, 0.0)
    done, polish = False, False
    for _ in range(END_MAXITER):
        r = material_residual(DEL_NS, tc, complex(k, 0.0), complex(a, STEP), c, w, a_m, L_m)
        if not math.isfinite(r.real):
            return a, k, False
        ra = r.imag / STEP
        if pressure:
            g = state(DEL_NS, tc, complex(k, 0.0), complex(a, STEP), c, w, a_m, True)
            gr, ga = g[2].real - d_fix, g[2].imag / STEP
            rk_ = material_residual(DEL_NS, tc, complex(k, STEP), complex(a, 0.0), c, w, a_m,
                                    L_m).imag / STEP
            gk = state(DEL_NS, tc, complex(k, STEP), complex(a, 0.0), c, w, a_m, True)[2].imag / STEP
            det = ra * gk - rk_ * ga
            if not (math.isfinite(det) and det != 0.0 and math.isfinite(gr)):
                return a, k, False
            da = (r.real * gk - rk_ * gr) / det
            dk = (ra * gr - ga * r.real) / det
        else:
            if not (math.isfinite(ra) and ra != 0.0):
                return a, k, False
            da, dk = r.real / ra, 0.0
        a, k = a - da, k - dk
        if polish:  # one step past convergence: the last digits
            done = True
            break
        polish = abs(da) <= 1e-12 * (1.0 + abs(a)) and abs(dk) <= 1e-12 * (1.0 + abs(k))
    if not (done and a > 0.0):
        return a, k, False
    return a, k, admissible(observe(DEL_NS, t_end, k, a, c, w, a_m, obs), obs)


#: golden-section steps of :func:`end_extremum` (0.618^60 of the bracket in alpha)
END_GOLDEN = 60


@jit
def stretch_at(alpha, t_end, w):
    """t at contact angle ``alpha`` on the root of eq. (62) with G = w that ends at ``t_end``."""
    s = math.sqrt(max(2.0 * w - math.sin(alpha) ** 2, 0.0))
    lo, hi = math.cos(alpha) - s, math.cos(alpha) + s
    return lo if abs(lo - t_end) <= abs(hi - t_end) else hi


@jit
def _value_at(pressure, alpha, ends, c, w, a_m, L_m, d_fix, key, sign, obs):
    """sign * obs[key] at the state of angle ``alpha`` (-inf where it does not solve), its a and
    kappa from predictors linear in alpha between the branch end and the bracket's other end
    (``ends`` = alpha_hi, t_end, a_end, kappa_end, a_hi, kappa_hi); returns (value, a, kappa)."""
    alpha_hi, t_end, a_e, k_e, a_hi, k_hi = ends
    r = alpha / alpha_hi
    t = t_end if alpha == 0.0 else stretch_at(alpha, t_end, w)
    a, k, good = solve_end(pressure, t, a_e + (a_hi - a_e) * r, k_e + (k_hi - k_e) * r, c, w, a_m, L_m,
                           d_fix, obs)
    if not good:
        return -math.inf, a, k
    return sign * obs[key], a, k


@jit
def end_extremum(pressure, ends, c, w, a_m, L_m, d_fix, key, sign, obs):
    """The state of largest sign * obs[key] with alpha in [0, alpha_hi] next to the branch end, the
    states parametrised by alpha (t in closed form, a and kappa solved: well conditioned down to
    alpha = 0, where the rows in t are not): golden section on (0, alpha_hi), then the end itself.
    ``ends`` = (alpha_hi, t_end, a_end, kappa_end, a_hi, kappa_hi). Returns (value, a, kappa, t) of
    the best state, its observables in ``obs``; value -inf if none solved."""
    g = 0.5 * (math.sqrt(5.0) - 1.0)
    tmp = np.empty(7)
    alpha_hi, t_end = ends[0], ends[1]
    lo, hi = 0.0, alpha_hi
    x1, x2 = hi - g * (hi - lo), lo + g * (hi - lo)
    f1 = _value_at(pressure, x1, ends, c, w, a_m, L_m, d_fix, key, sign, tmp)[0]
    f2 = _value_at(pressure, x2, ends, c, w, a_m, L_m, d_fix, key, sign, tmp)[0]
    for _ in range(END_GOLDEN):
        if f1 >= f2:
            hi, x2, f2 = x2, x1, f1
            x1 = hi - g * (hi - lo)
            f1 = _value_at(pressure, x1, ends, c, w, a_m, L_m, d_fix, key, sign, tmp)[0]
        else:
            lo, x1, f1 = x1, x2, f2
            x2 = lo + g * (hi - lo)
            f2 = _value_at(pressure, x2, ends, c, w, a_m, L_m, d_fix, key, sign, tmp)[0]
        if hi - lo <= 1e-15 * alpha_hi:
            break
    best = x1 if f1 >= f2 else x2
    v, a, k = _value_at(pressure, best, ends, c, w, a_m, L_m, d_fix, key, sign, obs)
    v0, a0, k0 = _value_at(pressure, 0.0, ends, c, w, a_m, L_m, d_fix, key, sign, tmp)
    if v0 >= v:  # the end itself (golden section never evaluates alpha = 0)
        obs[:] = tmp
        return v0, a0, k0, t_end
    return v, a, k, stretch_at(best, t_end, w)
