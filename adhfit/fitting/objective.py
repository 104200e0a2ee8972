"""The objective of a fit: one or more curves (members) of one membrane, one slip condition.

A curve is a series of one.  Every member keeps its own :class:`~.model.CurveModel` (its own scene: its
own pressure or gap), its own offsets (parametrised as :class:`~.lsq.Parametrisation` does: the control
offset over the curve's control range, the load-cell zero over its largest force) and its own noise
level per observable; W_ad and μh are shared.  The residual is the concatenation, per member, of its
force block (:func:`~.lsq.residual_function`: every row and the pull-off term) and one block per
secondary observable it has (:data:`.observables.OBSERVABLES`), each in units of its own σ.

:class:`ObjectiveFit` is one slip condition's optimum.  With one block (one curve, force only) it is
the member's own least-squares fit (:func:`~.lsq.fit_slip`): residual in units of the fit's scale,
σ estimated through lmfit's scaled covariance or given.  With several blocks the σ's are settled by
reweighting (:mod:`.lsq`), and the residual is in units of those fixed σ's.  The likelihood with every
estimated σ profiled out, -2 ln L = Σ_g n_g ln(RSS_g/n_g) (+ Σ χ²_g for a given σ), is the same
formula in both cases, and it is what the slip comparison uses (:mod:`.selection`).
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field

import lmfit
import numpy as np

from .lsq import PENALTY, Parametrisation, RawFit, residual_function
from .model import CurveModel, ModelDomainError
from .observables import PRIMARY, Observable, ObservedRows

__all__ = ["SIGMA_FLOOR", "Block", "Member", "SharedParametrisation", "ObjectiveFit", "objective_residual", "Values",
           "block_sizes", "split_blocks"]

_SHARED = ("ln_work_of_adhesion", "ln_mu_h")
#: least noise level, as a fraction of the largest value of its block: noise-free data must not get an
#: unbounded weight, and the model's own precision (the history interpolated at the rows) is ~1e-5 of it
SIGMA_FLOOR = 1e-5
_OFFSETS = ("x_offset", "force_offset", "force_drift")


class Values(dict):
    """A dict that answers ``valuesdict()`` like lmfit Parameters (what :func:`residual_function` needs)."""

    def valuesdict(self) -> dict:
        return self


@dataclass
class Block:
    """One secondary observable of one member: its rows, its noise σ (SI) and whether σ was given."""

    observable: Observable
    data: ObservedRows
    sigma: float
    given: bool = False


@dataclass
class Member:
    """One curve of an objective.

    Attributes
    ----------
    model : CurveModel
    par : Parametrisation
        The curve's parametrisation (its offsets' scales).
    sigma_f : float
        The unit of the force block's residual, N: the noise σ_i of a joint fit, the single fit's scale.
    blocks : list of Block
        Its secondary observables.
    label : str
    single : RawFit or None
        The curve's own least-squares fit (its start values and row split).
    """

    model: CurveModel
    par: Parametrisation
    sigma_f: float
    blocks: list = field(default_factory=list)
    label: str = ""
    single: RawFit | None = None
    _residual: object = field(default=None, repr=False)

    def force_residual(self):
        """The single-curve residual closure of this member at its current σ_i."""
        if self._residual is None or self._residual[0] != self.sigma_f:
            self._residual = (self.sigma_f, residual_function(self.model, self.par, self.sigma_f, self.sigma_f))
        return self._residual[1]

    @property
    def n_force(self) -> int:
        """Force residuals: every row, plus the pull-off term when the split shows the jump."""
        return self.model.force.size + (self.model.jump is not None)

    @property
    def size(self) -> int:
        return self.n_force + sum(b.data.rows.size for b in self.blocks)

    def block_residuals(self, sub: Values, rf: np.ndarray) -> list[np.ndarray]:
        """Each secondary block's residual (units of its σ) at internal values ``sub``."""
        if not self.blocks:
            return []
        if np.all(rf == PENALTY):
            return [np.full(b.data.rows.size, PENALTY) for b in self.blocks]
        si = self.par.si(sub)
        out = []
        for b in self.blocks:
            try:
                pred = b.observable.predict(self.model, si["work_of_adhesion"], si["mu_h"], si["x_offset"], b.data.rows)
                out.append((b.data.values - pred) / b.sigma)
            except ModelDomainError:
                out.append(np.full(b.data.rows.size, PENALTY))
        return out

    def cost(self, sub: Values) -> float:
        """χ² of this member (all its blocks) at internal values ``sub``."""
        rf = self.force_residual()(sub)
        return float(sum(float(r @ r) for r in [rf, *self.block_residuals(sub, rf)]))


@dataclass(frozen=True)
class SharedParametrisation:
    """lmfit names of an objective: shared ``ln_work_of_adhesion``, ``ln_mu_h``; per member its offsets,
    suffixed ``_i`` when there are several members (one member keeps the single-curve names)."""

    pars: tuple

    def name(self, base: str, i: int) -> str:
        return base if len(self.pars) == 1 else f"{base}_{i}"

    def member_values(self, v: dict, i: int) -> Values:
        """Internal values of member i under the single-curve names."""
        out = Values(ln_work_of_adhesion=v["ln_work_of_adhesion"], ln_mu_h=v["ln_mu_h"])
        for base in _OFFSETS:
            if self.name(base, i) in v:
                out[base] = v[self.name(base, i)]
        return out

    def params(self, shared: dict, offsets: list[dict]) -> lmfit.Parameters:
        """lmfit Parameters from SI values: ``shared`` (W_ad, μh) and per-member SI offsets."""
        p = lmfit.Parameters()
        for i, (par, off) in enumerate(zip(self.pars, offsets)):
            one = par.params({**shared, **off})
            if i == 0:
                for name in _SHARED:
                    p.add(name, value=one[name].value, min=one[name].min, max=one[name].max)
            for base in _OFFSETS:
                if base in one:
                    q = one[base]
                    p.add(self.name(base, i), value=q.value, min=q.min, max=q.max)
        return p

    def si(self, params) -> tuple[dict, list[dict]]:
        """(shared SI values, per-member SI offsets) of lmfit Parameters or a values dict."""
        v = {k: float(getattr(params[k], "value", params[k])) for k in params}
        per = [par.si(self.member_values(v, i)) for i, par in enumerate(self.pars)]
        shared = {"work_of_adhesion": per[0]["work_of_adhesion"], "mu_h": per[0]["mu_h"]}
        return shared, [{k: s[k] for k in _OFFSETS} for s in per]


def block_sizes(members: list[Member]) -> list[tuple[int, int]]:
    """(force block length incl. the pull-off term, secondary blocks' length) per member."""
    return [(m.n_force, m.size - m.n_force) for m in members]


def objective_residual(members: list[Member], spar: SharedParametrisation):
    """The joint residual (params -> array): per member its force block, then its secondary blocks."""
    def residual(params):
        v = params.valuesdict()
        out = []
        for i, m in enumerate(members):
            sub = spar.member_values(v, i)
            rf = m.force_residual()(sub)
            out.append(rf)
            out.extend(m.block_residuals(sub, rf))
        return np.concatenate(out)
    return residual


def split_blocks(r: np.ndarray, members: list[Member]) -> list[tuple[np.ndarray, list[np.ndarray]]]:
    """Split a joint residual vector into per-member (force rows without the pull-off term, [secondary
    blocks]), each in units of its block's σ."""
    out, k = [], 0
    for m in members:
        rf = r[k:k + m.model.force.size]
        k += m.n_force
        sec = []
        for b in m.blocks:
            sec.append(r[k:k + b.data.rows.size])
            k += b.data.rows.size
        out.append((rf, sec))
    return out


class ObjectiveFit:
    """One slip condition's optimum of an objective (module docstring).

    Attributes
    ----------
    slip : str
    members : list of Member
    spar : SharedParametrisation
    best : lmfit.minimizer.MinimizerResult
    given : dict
        Observable name -> whether its σ was given.
    joint : bool
        Minimised over several blocks with settled σ's (else: one member's own fit).
    """

    def __init__(self, slip: str, members: list[Member], spar: SharedParametrisation, best, given: dict,
                 joint: bool) -> None:
        self.slip, self.members, self.spar, self.best = slip, members, spar, best
        self.given, self.joint = dict(given), bool(joint)
        self.secant_steps = None

    @classmethod
    def from_single(cls, raw: RawFit, label: str = "") -> "ObjectiveFit":
        """The objective of one curve and its force alone: its own fit."""
        member = Member(model=raw.model, par=raw.par, sigma_f=raw.scale, label=label, single=raw)
        return cls(raw.slip, [member], SharedParametrisation((raw.par,)), raw.best,
                   {PRIMARY: raw.sigma_given}, joint=False)

    @property
    def single(self) -> RawFit | None:
        """The one member's own fit when this objective is that fit (one block)."""
        return None if self.joint else self.members[0].single

    @property
    def sigma_given(self) -> bool:
        """Whether the residual is in units of a fixed σ (given, or settled by a joint fit)."""
        return True if self.joint else bool(self.given[PRIMARY])

    @property
    def residual(self):
        if self.joint:
            return objective_residual(self.members, self.spar)
        raw = self.single
        return residual_function(raw.model, raw.par, raw.scale, self.sigma)

    @property
    def sigma(self) -> float:
        """Force noise of a one-block fit, N: given, or sqrt(RSS/(n - k)); NaN for a joint fit."""
        if self.joint:
            return float("nan")
        raw = self.single
        return raw.scale if raw.sigma_given else raw.scale * math.sqrt(max(raw.best.redchi, 0.0))

    def si(self) -> tuple[dict, list[dict]]:
        return self.spar.si(self.best.params)

    def replace_best(self, best) -> None:
        """A better optimum (a restart from a profile's sub-fit): for a one-block fit the member's own fit
        follows, so everything that reads it sees the new optimum."""
        self.best = best
        if not self.joint and self.members[0].single is not None:
            m = self.members[0]
            m.single = dataclasses.replace(m.single, best=best, won=f"{m.single.won}; restarted from a "
                                           "likelihood-profile sub-fit below the optimum", alternatives=())

    def start(self, i: int) -> int:
        """Index of member i's first residual."""
        return sum(m.size for m in self.members[:i])

    def groups(self) -> list[dict]:
        """Per (member, observable): n, RSS (physical units²), σ (the block's residual unit), given?"""
        r = np.asarray(self.best.residual, float)
        out = []
        for i, m in enumerate(self.members):
            lo = self.start(i)
            rfull = r[lo:lo + m.n_force]
            out.append({"curve": i, "obs": PRIMARY, "n": m.n_force, "rss": float(rfull @ rfull) * m.sigma_f ** 2,
                        "sigma": m.sigma_f, "given": self.given[PRIMARY]})
            k = lo + m.n_force
            for b in m.blocks:
                rb = r[k:k + b.data.rows.size]
                k += b.data.rows.size
                out.append({"curve": i, "obs": b.observable.name, "n": rb.size, "rss": float(rb @ rb) * b.sigma ** 2,
                            "sigma": b.sigma, "given": b.given})
        return out

    def criteria(self) -> tuple[float, float]:
        """(AIC, BIC) with every estimated σ profiled out (module docstring)."""
        m2lnl, n = 0.0, 0
        for g in self.groups():
            n += g["n"]
            m2lnl += g["rss"] / g["sigma"] ** 2 if g["given"] else g["n"] * math.log(max(g["rss"], 1e-300) / g["n"])
        k = self.best.nvarys
        return m2lnl + 2 * k, m2lnl + k * math.log(n)

    def chisqr(self) -> float:
        """χ² in residual units (what the optimiser minimised)."""
        return float(self.best.chisqr)

    def predicted(self, i: int) -> np.ndarray:
        """Model force of member i at every row, N."""
        m = self.members[i]
        shared, offs = self.si()
        try:
            return m.model.predict(shared["work_of_adhesion"], shared["mu_h"], offs[i]["x_offset"],
                                   offs[i]["force_offset"], offs[i]["force_drift"])
        except ModelDomainError:
            return np.full(m.model.force.shape, np.nan)


def fixed_model(model: CurveModel, j: int) -> CurveModel:
    """``model`` with the detachment fixed before row ``j`` (its histories shared)."""
    return model.split_before(j)


def check_splits(fit: ObjectiveFit, segs: list) -> bool:
    """Put each member's pull-off row where the joint optimum puts it; True when one moved.

    The free split's row at the joint optimum and its two neighbours (the row split is discrete: one
    row off costs a many-σ residual) are compared with the current split by the member's χ² at the
    joint optimum; the cheapest wins."""
    shared, offsets = fit.si()
    v = fit.best.params.valuesdict()
    changed = False
    for i, m in enumerate(fit.members):
        base = m.model
        free = CurveModel(base.curve, base.scene, base.slip, points=base.points, segments=segs[i],
                          membrane=base.membrane)
        try:
            j = free.split(shared["work_of_adhesion"], shared["mu_h"], offsets[i]["x_offset"])
        except ModelDomainError:
            continue
        now = base.segments.i_jump if base.fixed_split else None
        if j == now:
            continue
        sub = fit.spar.member_values(v, i)
        best_model, best_cost = base, m.cost(sub)
        cands = [free] if j is None else [fixed_model(free, jj) for jj in (j - 1, j, j + 1)
                                          if segs[i].i_turn + 1 < jj < free.x.size - 1 and jj != now]
        for model in cands:
            trial = Member(model=model, par=m.par, sigma_f=m.sigma_f, blocks=m.blocks)
            try:
                cost = trial.cost(sub)
            except ModelDomainError:
                continue
            if cost < best_cost:
                best_model, best_cost = model, cost
        if best_model is not base:
            m.model, m._residual, changed = best_model, None, True
    return changed
