"""Independent 30-digit reference of the adhesive membrane contact model (test oracle only).

Straight from the paper's equations (Yang, Srivastava & Long; sections 2-3 and 5) with mpmath
adaptive quadrature and hand-written root solves. It deliberately shares nothing with ``adhfit.core``:
no Carlson closed forms, no imports from the engine. Use it to hold the engine to account, never as
the engine.

Dimensionless throughout (docs/contracts.md A1, B1): lengths over b, kappa = p = P b / (2 mu h), D = kappa C1,
C2 = Cbar2 / b**2, so that eq. (38) reads

    sin(theta) = (kappa r**2 + D) / sqrt(r**2 + C2),
    Q(r) = (r**2 + C2) - (kappa r**2 + D)**2 = (r**2 + C2) cos(theta)**2,
    J0 = int dr / sqrt(Q)                    -> ln(beta / rho_a), eqs. (35), (41), (42), (57)
    J1 = int (kappa r**2 + D) / sqrt(Q) dr   -> -z(a), eqs. (25), (46)-(48), (58)

with f = F / (2 mu h b) = -pi D (eqs. 26, 50, 59). The material coordinate enters only through
L = ln(beta / rho_a), so lambda0 drops out of every observable (docs/numerics.md C).

Quadrature: in u = r**2, Q is a quadratic with roots u_minus <= u_plus (u_plus = inf when kappa = 0).
Tanh-sinh on an integrand with a 1/sqrt endpoint singularity loses about half the digits, so the
pieces next to a root are integrated after the substitutions u = u_minus + s**2 or u = u_plus - t**2,
which make the integrand smooth; the rest is integrated in ln(u). Every quadrature checks its own
error estimate.
"""
from __future__ import annotations

import functools
from dataclasses import dataclass

import mpmath as mp

DPS = 30
#: Quadrature error estimates above this raise: the reference must be far better than 1e-9.
QUAD_TOL = mp.mpf("1e-24")
#: Newton stops when the residual (J0 or gap, both O(1)) is below this.
NEWTON_FTOL = mp.mpf("1e-25")

CONTROLS = ("displacement", "pressure")
SLIPS = ("no-slip", "frictionless")
STAGES = ("making_contact", "pinning", "delamination")


class Inadmissible(ValueError):
    """Profile constants for which Q < 0 somewhere on the free membrane (no such equilibrium)."""


class NoConvergence(RuntimeError):
    """A reference root solve or extremum search did not converge."""


# --------------------------------------------------------------------------------------------------
# Small geometric helpers
# --------------------------------------------------------------------------------------------------
def _mpf(x) -> mp.mpf:
    """Exact conversion (a float becomes its exact binary value, the number the engine sees)."""
    return x if isinstance(x, mp.mpf) else mp.mpf(x)


def _ratio(a: mp.mpf, rs: mp.mpf) -> mp.mpf:
    """a / rs; 0 on a flat substrate (rs = inf)."""
    return mp.mpf(0) if mp.isinf(rs) else a / rs


def _sag(a: mp.mpf, rs: mp.mpf) -> mp.mpf:
    """rs - sqrt(rs**2 - a**2), the substrate drop at r = a, written without cancellation (B1)."""
    if mp.isinf(rs):
        return mp.mpf(0)
    return a * a / (rs + mp.sqrt(rs * rs - a * a))


def d0(p) -> mp.mpf | None:
    """Free-inflation apex deflection over b, eq. (15) in the form kappa / (1 + sqrt(1 - kappa**2)).

    Returns None for |p| > 1, where the Case I cap does not exist (docs/contracts.md A2).
    """
    p = _mpf(p)
    if abs(p) > 1:
        return None
    return p / (1 + mp.sqrt(1 - p * p))


def p_cr(d) -> mp.mpf:
    """Pressure at which the free apex touches the substrate at gap d, eq. (64)."""
    d = _mpf(d)
    return 2 * d / (1 + d * d)


def sin_theta_a(alpha: mp.mpf, a: mp.mpf, rs: mp.mpf) -> mp.mpf:
    """sin(theta_a) with theta_a = alpha - asin(a/rs), eq. (22)."""
    x = _ratio(a, rs)
    return mp.sqrt(1 - x * x) * mp.sin(alpha) - x * mp.cos(alpha)


def theta_a(alpha: mp.mpf, a: mp.mpf, rs: mp.mpf) -> mp.mpf:
    """Tangent angle of the free membrane at the contact edge, eq. (22)."""
    return alpha - mp.asin(_ratio(a, rs))


# --------------------------------------------------------------------------------------------------
# The two integrals J0 and J1
# --------------------------------------------------------------------------------------------------
def _quadratic(kap: mp.mpf, D: mp.mpf, C2: mp.mpf) -> tuple[mp.mpf, mp.mpf]:
    """Factor Q(u) = -kap**2 u**2 + B u + C = (q - kap**2 u)(u - u_minus).

    The larger root is u_plus = q / kap**2. q is formed so that neither root is lost to cancellation
    and kappa = 0 (Q linear, u_plus = inf) needs no special case.
    """
    B = 1 - 2 * kap * D
    C = C2 - D * D
    disc = 1 - 4 * kap * D + 4 * kap * kap * C2  # B**2 + 4 kap**2 C
    if disc < 0:
        raise Inadmissible(f"Q has no real roots (discriminant {mp.nstr(disc, 5)})")
    sd = mp.sqrt(disc)
    q = (B + sd) / 2 if B >= 0 else 2 * kap * kap * C / (sd - B)
    if q <= 0:
        raise Inadmissible("Q < 0 for every u > 0")
    return q, -C / q


def _integrate(kap, D, q, um, u_lo, u_hi) -> mp.mpc:
    """J0 + i J1 over r^2 in [u_lo, u_hi], where u_minus <= u_lo < u_hi <= u_plus.

    J0 and J1 share every node: the integrand is returned as one complex number (real part for J0,
    imaginary part for J1), which halves the cost.
    """
    k2 = kap * kap
    up = q / k2 if kap != 0 else mp.inf

    def g(u, weight):
        return mp.mpc(weight, weight * (kap * u + D))

    def f_log(v):  # u = exp(v): dr / sqrt(Q) = sqrt(u) dv / (2 sqrt(Q))
        u = mp.exp(v)
        return g(u, mp.sqrt(u) / (2 * mp.sqrt((q - k2 * u) * (u - um))))

    def f_low(s):  # u = u_minus + s^2 removes the root at u_minus
        u = um + s * s
        return g(u, 1 / (mp.sqrt(u) * mp.sqrt(q - k2 * u)))

    def f_high(t):  # u = u_plus - t^2 removes the root at u_plus
        u = up - t * t
        return g(u, 1 / (mp.sqrt(u) * abs(kap) * mp.sqrt(u - um)))

    # Geometric pieces (each a factor <= 16 in u) keep the 1/r-like range at small a cheap.
    n = max(2, int(mp.ceil(mp.log(u_hi / u_lo) / mp.log(16))))
    edges = [u_lo * (u_hi / u_lo) ** (mp.mpf(k) / n) for k in range(n + 1)]
    edges[0], edges[-1] = u_lo, u_hi
    total = mp.mpc(0)
    for k in range(n):
        x, y = edges[k], edges[k + 1]
        if k == 0 and x - um <= y - x:
            val, err = mp.quad(f_low, [mp.sqrt(x - um), mp.sqrt(y - um)], error=True)
        elif k == n - 1 and up - y <= y - x:
            val, err = mp.quad(f_high, [mp.sqrt(up - y), mp.sqrt(up - x)], error=True)
        else:
            val, err = mp.quad(f_log, [mp.log(x), mp.log(y)], error=True)
        if err > QUAD_TOL * (1 + abs(val)):
            raise NoConvergence(f"quadrature error {mp.nstr(err, 3)} on u in [{x}, {y}]")
        total += val
    return total


def integrals(kap, D, C2, a, folded: bool = False) -> tuple[mp.mpf, mp.mpf]:
    """J0 = ln(beta/rho_a) and J1 = -z(a) for the free membrane between the contact edge and r = 1.

    Parameters
    ----------
    kap, D, C2 : mpf
        Pressure kappa = p, D = kappa C1 and C2 (dimensionless, lengths over b).
    a : mpf
        Contact radius over b.
    folded : bool
        True when theta_a > pi/2 (no slip only): the membrane first runs inward to r = eta, where
        theta = pi/2 and eta**2 is the smaller root of Q (eq. 44, docs/numerics.md C), then out to r = 1.
        Eqs. (42) (with the corrected, positive sign) and (47).

    Returns
    -------
    (J0, J1) : tuple of mpf
    """
    q, um = _quadratic(kap, D, C2)
    u_a = a * a
    k2 = kap * kap
    if q - k2 < 0:  # r = 1 beyond u_plus: the edge tangent would pass through vertical
        raise Inadmissible("Q < 0 at the clamped edge")
    if not folded:
        gap = u_a - um
        if gap < 0:
            # theta_a at pi/2 puts a**2 exactly on the root; allow rounding, nothing more.
            if gap < -mp.mpf("1e-26") * u_a:
                raise Inadmissible("Q < 0 just outside the contact edge")
            um = u_a
        tot = _integrate(kap, D, q, um, u_a, mp.mpf(1))
        return tot.real, tot.imag
    if not (0 < um < u_a):
        raise Inadmissible("folded profile needs 0 < eta**2 < a**2")
    if kap * um + D <= 0:
        raise Inadmissible("at eta the tangent points down (theta = -pi/2), not up")
    inner = _integrate(kap, D, q, um, um, u_a)
    outer = _integrate(kap, D, q, um, um, mp.mpf(1))
    tot = inner + outer
    return tot.real, tot.imag


# --------------------------------------------------------------------------------------------------
# Profile constants of each stage
# --------------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Solution:
    """One equilibrium: contact radius, angle, profile constants and the two integrals."""

    a: mp.mpf
    alpha: mp.mpf
    kap: mp.mpf
    D: mp.mpf
    C2: mp.mpf
    folded: bool
    J0: mp.mpf
    J1: mp.mpf
    G: mp.mpf
    rs: mp.mpf

    @property
    def gap(self) -> mp.mpf:
        """d = -z(a) - rs + sqrt(rs**2 - a**2), eqs. (25), (48), (58)."""
        return self.J1 - _sag(self.a, self.rs)

    @property
    def f(self) -> mp.mpf:
        """f = F / (2 mu h b) = -pi D, eqs. (26), (50), (59)."""
        return -mp.pi * self.D


def contact_profile(kap, a, rs) -> Solution:
    """Making contact (sec. 3.1): C2 = 0, D = -(kappa + 1/rs) a**2 (eq. 19 times kappa), G = 0."""
    D = -(kap + _ratio(mp.mpf(1), rs)) * a * a
    J0, J1 = integrals(kap, D, mp.mpf(0), a)
    return Solution(a, mp.mpf(0), kap, D, mp.mpf(0), False, J0, J1, mp.mpf(0), rs)


def _no_slip_G(alpha, t) -> mp.mpf:
    """Eq. (52): G/mu h = t (1 - cos alpha) + (t - 1)**2 / 2 with t = sqrt(1 + C2/a**2)."""
    return t * 2 * mp.sin(alpha / 2) ** 2 + (t - 1) ** 2 / 2


def no_slip_profile(kap, a, alpha, c, rs) -> Solution:
    """No slip (sec. 3.2.1): c = C2/a**2; D from eq. (39) times kappa: D = sin(theta_a) sqrt(a**2+C2) - kappa a**2."""
    if c <= -1:
        raise Inadmissible("C2 <= -a**2")
    t = mp.sqrt(1 + c)
    D = a * (sin_theta_a(alpha, a, rs) * t - kap * a)
    folded = theta_a(alpha, a, rs) > mp.pi / 2
    J0, J1 = integrals(kap, D, c * a * a, a, folded)
    return Solution(a, alpha, kap, D, c * a * a, folded, J0, J1, _no_slip_G(alpha, t), rs)


def alpha_from_G(w, c) -> mp.mpf:
    """Contact angle for which eq. (62) holds, G = w, given t = sqrt(1 + C2/a**2).

    1 - cos(alpha) = 2 sin(alpha/2)**2 = (w - (t-1)**2/2) / t, inverted without cancellation.
    """
    if c <= -1:
        raise Inadmissible("C2 <= -a**2")
    t = mp.sqrt(1 + c)
    x = (w - (t - 1) ** 2 / 2) / t
    if not (0 <= x <= 2):
        raise Inadmissible("G = w has no contact angle in [0, pi] for this C2")
    return 2 * mp.asin(mp.sqrt(x / 2))


def frictionless_profile(kap, a, alpha, rs) -> Solution:
    """Frictionless (sec. 3.2.2): C2 = a**2 tan**2 alpha (eq. 55); eq. (56) times kappa for D; eq. (60) for G."""
    x = _ratio(a, rs)
    ta = mp.tan(alpha)
    D = a * mp.sqrt(1 - x * x) * ta - (kap + _ratio(mp.mpf(1), rs)) * a * a
    J0, J1 = integrals(kap, D, (a * ta) ** 2, a)
    return Solution(a, alpha, kap, D, (a * ta) ** 2, False, J0, J1, ta * ta / 2, rs)


def rho_log_ratio(a_d, a_m, rs) -> mp.mpf:
    """ln(rho_am / rho_ad) from eq. (61) (no slip: the bonded membrane keeps its contact-stage stretch)."""
    x_m, x_d = _ratio(a_m, rs), _ratio(a_d, rs)
    return mp.log((a_m / a_d) * (1 + mp.sqrt(1 - x_d * x_d)) / (1 + mp.sqrt(1 - x_m * x_m)))


# --------------------------------------------------------------------------------------------------
# Root solves
# --------------------------------------------------------------------------------------------------
def _newton(fun, x0: list, maxiter: int = 40):
    """Damped Newton with a forward-difference Jacobian.

    ``fun(x)`` returns ``(residuals, solution)`` and may raise Inadmissible; a trial step that leaves
    the admissible set or does not reduce the residual is halved. The Jacobian is only good to about
    1e-13, so convergence is linear with that ratio near the root: two or three extra steps.
    """
    x = list(x0)
    res, sol = fun(x)
    for _ in range(maxiter):
        norm = max(abs(r) for r in res)
        if norm < NEWTON_FTOL:
            return x, sol
        jac = mp.matrix(len(x), len(x))
        for j in range(len(x)):
            h = mp.mpf("1e-13") * (1 + abs(x[j]))
            for sign in (1, -1):  # backward difference if the forward point is inadmissible
                xj = list(x)
                xj[j] += sign * h
                try:
                    rj, _ = fun(xj)
                    break
                except Inadmissible:
                    continue
            else:
                raise NoConvergence(f"no admissible neighbour for a Jacobian at x = {x}")
            for i in range(len(x)):
                jac[i, j] = (rj[i] - res[i]) / (sign * h)
        step = mp.lu_solve(jac, mp.matrix([-r for r in res]))
        lam = mp.mpf(1)
        while True:
            xn = [x[i] + lam * step[i] for i in range(len(x))]
            try:
                rn, soln = fun(xn)
                if max(abs(r) for r in rn) < max(norm, 10 * NEWTON_FTOL):
                    break
            except Inadmissible:
                pass
            lam /= 2
            if lam < mp.mpf("1e-8"):
                raise NoConvergence(f"line search failed at x = {x}, |res| = {mp.nstr(norm, 3)}")
        x, res, sol = xn, rn, soln
    raise NoConvergence(f"Newton did not converge from x0 = {x0}")


# --------------------------------------------------------------------------------------------------
# One loading history: the three stages, by continuation
# --------------------------------------------------------------------------------------------------
class History:
    """All equilibria of one test, solved on demand by continuation along each stage.

    Unknowns per stage (kappa is appended under pressure control, where the gap is the extra equation):
    making contact: none; no-slip pinning and delamination: c = C2/a**2; frictionless pinning: ln a;
    frictionless delamination: none. Equations: J0 = L_m (pinning), J0 = L_d(a) (no-slip
    delamination), gap = d (pressure control).
    """

    #: largest continuation step: radians for pinning, ln a otherwise
    MAX_STEP = {"making_contact": mp.mpf("0.5"), "pinning": mp.mpf("0.1"), "delamination": mp.mpf("0.25")}

    def __init__(self, control, slip, p, d, w, rs, a_max):
        if control not in CONTROLS or slip not in SLIPS:
            raise ValueError(f"control must be one of {CONTROLS}, slip one of {SLIPS}")
        self.control, self.slip = control, slip
        self.pressure = control == "pressure"
        self.no_slip = slip == "no-slip"
        self.p = None if p is None else _mpf(p)
        self.d = None if d is None else _mpf(d)
        if (self.p is None) != self.pressure or (self.d is None) != (not self.pressure):
            raise ValueError("displacement control needs p (not d); pressure control needs d (not p)")
        self.w, self.rs, self.a_max = _mpf(w), _mpf(rs), _mpf(a_max)
        self._cache = {s: [] for s in STAGES}
        self.end = self.solve("making_contact", self.a_max)
        self.L_m = self.end.J0
        self._seed_pinning()
        self._onset = None

    # ---- stage equations ----------------------------------------------------------------------
    def _kappa(self, x):
        return x[-1] if self.pressure else self.p

    def _build(self, stage: str, loc, x) -> Solution:
        kap = self._kappa(x)
        if stage == "making_contact":
            return contact_profile(kap, loc, self.rs)
        if stage == "pinning":
            if self.no_slip:
                return no_slip_profile(kap, self.a_max, loc, x[0], self.rs)
            return frictionless_profile(kap, mp.exp(x[0]), loc, self.rs)
        if self.no_slip:
            return no_slip_profile(kap, loc, alpha_from_G(self.w, x[0]), x[0], self.rs)
        return frictionless_profile(kap, loc, self.alpha_fr, self.rs)

    def _residual(self, stage: str, loc, sol: Solution) -> list:
        res = []
        if stage == "pinning":
            res.append(sol.J0 - self.L_m)  # eqs. (41)/(42), (57): rho_a stays rho_am
        elif stage == "delamination" and self.no_slip:
            res.append(sol.J0 - self.L_m - rho_log_ratio(loc, self.a_max, self.rs))  # eq. (61)
        if self.pressure:
            res.append(sol.gap - self.d)  # eqs. (25), (48), (58) at the fixed gap
        return res

    @property
    def alpha_fr(self) -> mp.mpf:
        """Frictionless delamination angle, eq. (63)."""
        return mp.atan(mp.sqrt(2 * self.w))

    def _coord(self, stage: str, loc):
        return loc if stage == "pinning" else mp.log(loc)

    # ---- continuation -------------------------------------------------------------------------
    def _solve_from(self, stage, loc, guess) -> tuple[list, Solution]:
        def fun(x):
            sol = self._build(stage, loc, x)
            return self._residual(stage, loc, sol), sol

        if not guess:
            sol = self._build(stage, loc, [])
            return [], sol
        return _newton(fun, guess)

    def _predict(self, stage, s):
        """Linear predictor from the two cached solutions nearest to s."""
        near = sorted(self._cache[stage], key=lambda e: abs(e[0] - s))[:2]
        if len(near) == 1 or near[0][0] == near[1][0]:
            return near[0][0], list(near[0][1])
        (s1, x1, _), (s2, x2, _) = near
        return s1, [x1[i] + (x1[i] - x2[i]) * (s - s1) / (s1 - s2) for i in range(len(x1))]

    def solve(self, stage: str, loc) -> Solution:
        """Equilibrium at a locator (alpha for pinning, a otherwise), continued from cached ones."""
        loc = _mpf(loc)
        cache = self._cache[stage]
        s_target = self._coord(stage, loc)
        for s, _, sol in cache:
            if s == s_target:
                return sol
        if not self.pressure and (stage == "making_contact" or (stage == "delamination" and not self.no_slip)):
            return self._solve_from(stage, loc, [])[1]  # explicit in a: nothing to continue
        if not cache:  # pressure-control loading starts near point contact, kappa ~ p_cr(d) + O(a**2)
            a0 = min(loc, self.a_max / 10)
            x, sol = self._solve_from(stage, a0, [p_cr(self.d)])
            cache.append((self._coord(stage, a0), x, sol))
        h = self.MAX_STEP[stage]
        while True:
            s_near = min((e[0] for e in cache), key=lambda s: abs(s - s_target))
            if s_near == s_target:
                return next(e[2] for e in cache if e[0] == s_target)
            s_next = s_near + max(-h, min(h, s_target - s_near))
            loc_next = s_next if stage == "pinning" else mp.exp(s_next)
            if s_next == s_target:
                loc_next = loc
            _, guess = self._predict(stage, s_next)
            try:
                x, sol = self._solve_from(stage, loc_next, guess)
            except (Inadmissible, NoConvergence):
                h /= 2
                if h < mp.mpf("1e-7"):
                    raise NoConvergence(f"continuation stalled in {stage} near {mp.nstr(s_near, 10)}")
                continue
            cache.append((s_next, x, sol))
            h = min(self.MAX_STEP[stage], 2 * h)

    # ---- stage boundaries ---------------------------------------------------------------------
    def _seed_pinning(self):
        """Pinning starts where loading ended: alpha = 0, C2 = 0, a = a_max, kappa = p_m."""
        x = [mp.mpf(0)] if self.no_slip else [mp.log(self.a_max)]
        if self.pressure:
            x.append(self.end.kap)
        sol = self._build("pinning", mp.mpf(0), x)
        self._cache["pinning"].append((mp.mpf(0), x, sol))

    def _find_onset(self) -> Solution:
        """End of pinning, G = w (eqs. 52/62, or 60/63)."""
        if not self.no_slip:
            sol = self.solve("pinning", self.alpha_fr)
            x = [sol.kap] if self.pressure else []
            self._cache["delamination"].append((mp.log(sol.a), x, sol))
            return sol
        # No slip: walk alpha until G passes w, then solve the delamination system at a = a_max
        # (eq. 62 with rho_ad = rho_am) from the interpolated pinning unknowns.
        alpha, prev = mp.mpf(0), self._cache["pinning"][0]
        while True:
            alpha += self.MAX_STEP["pinning"]
            if alpha > mp.pi:
                raise NoConvergence("G stays below w for every alpha in [0, pi]")
            sol = self.solve("pinning", alpha)
            cur = next(e for e in self._cache["pinning"] if e[0] == alpha)
            if sol.G >= self.w:
                break
            prev = cur
        g0, g1 = prev[2].G, cur[2].G
        lam = (self.w - g0) / (g1 - g0)
        guess = [prev[1][i] + lam * (cur[1][i] - prev[1][i]) for i in range(len(cur[1]))]
        x, sol = self._solve_from("delamination", self.a_max, guess)
        self._cache["delamination"].append((mp.log(self.a_max), x, sol))
        self._cache["pinning"].append((sol.alpha, x, sol))
        return sol

    @property
    def onset(self) -> Solution:
        """End of pinning (G = w), found on first use: making-contact states do not need it."""
        if self._onset is None:
            self._onset = self._find_onset()
        return self._onset

    @property
    def a_onset(self) -> mp.mpf:
        return self.onset.a

    @property
    def alpha_onset(self) -> mp.mpf:
        return self.onset.alpha


@functools.lru_cache(maxsize=64)
def _history(control, slip, p, d, w, rs, a_max) -> History:
    return History(control, slip, p, d, w, rs, a_max)


def history(control, slip, *, p=None, d=None, w, rs, a_max) -> History:
    """The (cached) History for these inputs, built at DPS digits."""
    with mp.workdps(DPS):
        return _history(control, slip, p, d, w, rs, a_max)


# --------------------------------------------------------------------------------------------------
# Observables, states and summaries
# --------------------------------------------------------------------------------------------------
def observables(h: History, sol: Solution, stage: str) -> dict:
    """The A2 quantities of one equilibrium, plus profile constants for diagnosis."""
    p = h.p if not h.pressure else sol.kap
    d = h.d if h.pressure else sol.gap  # the solved gap equals the fixed d to ~1e-25
    dd = d0(p)
    return {
        "stage": stage, "a": sol.a, "alpha": sol.alpha, "p": p, "d": d,
        "delta": None if dd is None else dd - d, "f": sol.f, "G": sol.G,
        "C2": sol.C2, "D": sol.D, "L": sol.J0, "theta_a": theta_a(sol.alpha, sol.a, sol.rs),
        "folded": sol.folded,
    }


def state(control, slip, stage, *, p=None, d=None, w, rs, a_max, a=None, alpha=None) -> dict:
    """One equilibrium at a stage locator, to DPS digits.

    Parameters
    ----------
    control : {'displacement', 'pressure'}
        Displacement control fixes p (kappa), pressure control fixes the gap d.
    slip : {'no-slip', 'frictionless'}
    stage : {'making_contact', 'pinning', 'delamination'}
        Locators: making contact a in (0, a_max]; pinning alpha in [0, alpha_onset];
        delamination a in (0, a_onset].
    p, d, w, rs, a_max : float or mpf
        Dimensionless inputs (docs/contracts.md A1); rs may be inf.

    Returns
    -------
    dict
        mpf values for a, alpha, p, d, delta (None where |p| > 1), f, G; also stage, C2, D,
        L = ln(beta/rho_a), theta_a and folded (theta_a > pi/2) for diagnosis.
    """
    with mp.workdps(DPS):
        h = _history(control, slip, p, d, w, rs, a_max)
        if stage == "pinning":
            loc, hi = _mpf(alpha), h.alpha_onset
            if not 0 <= loc <= hi * (1 + mp.mpf("1e-12")):
                raise ValueError(f"alpha must be in [0, {mp.nstr(hi, 12)}]. Got {alpha}.")
        elif stage in ("making_contact", "delamination"):
            loc = _mpf(a)
            hi = h.a_max if stage == "making_contact" else h.a_onset
            if not 0 < loc <= hi * (1 + mp.mpf("1e-12")):
                raise ValueError(f"a must be in (0, {mp.nstr(hi, 12)}] for {stage}. Got {a}.")
        else:
            raise ValueError(f"stage must be one of {STAGES}. Got {stage!r}.")
        return observables(h, h.solve(stage, loc), stage)


class RetractionPath:
    """Pinning then delamination on one parameter s in [0, 2].

    s in [0, 1]: pinning at alpha = s alpha_onset; s in [1, 2]: delamination at
    a = a_onset (a_lo/a_onset)**(s-1), log-spaced down to a_lo = 1e-3 a_max.
    """

    def __init__(self, h: History):
        self.h = h
        self.a_lo = h.a_max / 1000

    def locate(self, s) -> tuple[str, mp.mpf]:
        if s <= 1:
            return "pinning", s * self.h.alpha_onset
        return "delamination", self.h.a_onset * (self.a_lo / self.h.a_onset) ** (s - 1)

    def at(self, s) -> Solution:
        return self.h.solve(*self.locate(s))

    def minimize(self, objective, n_pin: int = 10, n_del: int = 40) -> mp.mpf:
        """Abscissa s of the least objective(solution): a grid, then Brent, then a Newton polish."""
        grid = [mp.mpf(k) / n_pin for k in range(n_pin)] + [1 + mp.mpf(k) / n_del for k in range(n_del + 1)]
        vals = [objective(self.at(s)) for s in grid]
        i = min(range(len(grid)), key=lambda k: vals[k])
        if i in (0, len(grid) - 1):
            return grid[i]
        fun = lambda s: objective(self.at(s))  # noqa: E731
        s = _brent_min(fun, grid[i - 1], grid[i + 1], mp.mpf("1e-11"))
        if abs(s - 1) < mp.mpf("1e-9") and fun(mp.mpf(1)) <= fun(s):
            return mp.mpf(1)  # the least value sits on the kink at the onset of delamination
        return _polish_min(fun, s, grid[i - 1], grid[i + 1])


def _brent_min(fun, a, b, xtol):
    """Brent's localmin (golden section with parabolic steps) on [a, b] to absolute xtol."""
    c = (3 - mp.sqrt(5)) / 2
    x = w = v = a + c * (b - a)
    fx = fw = fv = fun(x)
    d = e = mp.mpf(0)
    for _ in range(300):
        m = (a + b) / 2
        if abs(x - m) <= 2 * xtol - (b - a) / 2:
            return x
        p = q = r = mp.mpf(0)
        if abs(e) > xtol:
            r = (x - w) * (fx - fv)
            q = (x - v) * (fx - fw)
            p = (x - v) * q - (x - w) * r
            q = 2 * (q - r)
            if q > 0:
                p = -p
            q = abs(q)
            r, e = e, d
        if abs(p) < abs(q * r / 2) and q * (a - x) < p < q * (b - x):
            d = p / q
            if (x + d) - a < 2 * xtol or b - (x + d) < 2 * xtol:
                d = xtol if x < m else -xtol
        else:
            e = (b - x) if x < m else (a - x)
            d = c * e
        u = x + (d if abs(d) >= xtol else (xtol if d > 0 else -xtol))
        fu = fun(u)
        if fu <= fx:
            a, b = (a, x) if u < x else (x, b)
            v, fv, w, fw, x, fx = w, fw, x, fx, u, fu
        else:
            a, b = (u, b) if u < x else (a, u)
            if fu <= fw or w == x:
                v, fv, w, fw = w, fw, u, fu
            elif fu <= fv or v == x or v == w:
                v, fv = u, fu
    raise NoConvergence("Brent minimisation did not converge")


def _polish_min(fun, s, lo, hi):
    """Newton on central differences of the objective: Brent alone stops at ~sqrt(noise) ~ 1e-12.

    Skipped at a kink (the pinning/delamination boundary s = 1) or where the curvature is not positive.
    """
    step = mp.mpf("1e-7")
    for _ in range(3):
        if abs(s - 1) < 4 * step or s - 2 * step < lo or s + 2 * step > hi:
            return s
        fm, f0, fp = fun(s - step), fun(s), fun(s + step)
        d2 = (fp - 2 * f0 + fm) / step**2
        if d2 <= 0:
            return s
        ds = -(fp - fm) / (2 * step) / d2
        if abs(ds) > mp.mpf("1e-6"):
            return s
        s += ds
        if abs(ds) < mp.mpf("1e-16"):
            break
    return s


def _point(h: History, path: RetractionPath, s) -> dict:
    stage, loc = path.locate(s)
    obs = observables(h, h.solve(stage, loc), stage)
    return {"f": obs["f"], "delta": obs["delta"], "p": obs["p"], "a": obs["a"],
            "stage": stage, "alpha": obs["alpha"], "s": s}


def summary(control, slip, *, p=None, d=None, w, rs, a_max) -> dict:
    """The A2 ``--json`` summary to DPS digits.

    Returns
    -------
    dict
        ``f_max`` (force at the end of loading); ``onset`` (G reaches w), ``f_min`` (most negative force)
        and ``turning_point`` (least delta under displacement control, least p under pressure control),
        each a dict with f, delta, p, a (plus stage, alpha and the path parameter s for diagnosis).
        Extrema are searched over pinning and delamination down to a = 1e-3 a_max.
    """
    with mp.workdps(DPS):
        h = _history(control, slip, p, d, w, rs, a_max)
        path = RetractionPath(h)
        s_fmin = path.minimize(lambda sol: sol.f)
        # least delta = greatest gap at fixed p; least p directly under pressure control
        s_turn = path.minimize((lambda sol: sol.kap) if h.pressure else (lambda sol: -sol.gap))
        return {
            "f_max": h.end.f,
            "onset": _point(h, path, mp.mpf(1)),
            "f_min": _point(h, path, s_fmin),
            "turning_point": _point(h, path, s_turn),
        }
