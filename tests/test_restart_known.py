"""A restart of one slip condition from the other's optimum (``fit_slip(..., known=...)``).

When the restart's free-split stage lands where the first fit's did, its fixed-split stage would only
repeat the first fit's from the same points: the first fit is returned as it is (its object), without
the fixed stage's minimisations.  When it lands elsewhere, the restart runs in full and is a new fit.
"""
from __future__ import annotations

import numpy as np

import adhfit.fitting.lsq as lsq
from adhfit.fitting.lsq import fit_slip
from adhfit.fitting.model import CurveModel
from adhfit.scene import Scene
from adhfit.synthetic import synthetic_curve


def _model():
    scene = Scene(membrane_radius="2 mm", substrate_radius="1 mm", control="displacement", pressure="1.2 kPa",
                  slip="auto", membrane_model="large-stretch")
    curve, _ = synthetic_curve(scene, "no-slip", work_of_adhesion=0.4, mu_h=2.0, x_max=6e-4, rows=120,
                               noise=0.01, approach=0.25, tail=0.3, rng=np.random.default_rng(31))
    return CurveModel(curve, scene, "no-slip")


def _counting(monkeypatch) -> list:
    calls = []
    real = lsq.minimise

    def counted(*a, **kw):
        calls.append(1)
        return real(*a, **kw)

    monkeypatch.setattr(lsq, "minimise", counted)
    return calls


def test_a_restart_from_the_same_optimum_returns_the_known_fit(monkeypatch):
    model = _model()
    first = fit_slip(model)
    assert first.free, "the fit keeps its free-split optimum"
    calls = _counting(monkeypatch)
    free_si = first.par.si(dict(first.free))
    again = fit_slip(model, n_runs=0, extra_starts=[free_si], known=first)
    assert again is first
    assert len(calls) == 1  # the restart's own free-split minimisation, and no fixed stage


def test_a_restart_that_lands_elsewhere_is_fitted_in_full(monkeypatch):
    model = _model()
    first = fit_slip(model)
    free_si = first.par.si(dict(first.free))
    # a known fit whose free stage ended elsewhere: the restart must not be mistaken for it
    elsewhere = lsq.dataclasses.replace(first, free=tuple((k, v + 0.01) for k, v in first.free))
    calls = _counting(monkeypatch)
    again = fit_slip(model, n_runs=0, known=elsewhere, extra_starts=[free_si])
    assert again is not elsewhere
    assert len(calls) >= 3  # the free split, then the fixed split's candidate rows
    assert again.best.chisqr <= first.best.chisqr * (1 + 1e-4)  # from the first fit's free optimum: its result
