"""The compiled (numba) backend against the numpy reference path of the engine.

Why these tolerances:
- Carlson R_F / R_D: both ours and scipy's are duplication algorithms good to a few ulp, so real
  values (and complex ones, by modulus) must agree to 2e-15 relative. The imaginary part carried by
  a complex step is a derivative; it is compared on one perturbed argument at a time (as the engine
  uses it) to 1e-13 relative, the conditioning of that derivative, not of the algorithm.
- States: the two backends run the same formulas and the same solver rules in a different order of
  floating-point operations; roots are converged to xtol = 4e-15 (1 + |x|), so states agree to 1e-12.
  Derivatives along a branch grow without bound toward a turning point, so they are held to 1e-12
  relative to max(1, |value|).
- Histories: rows to 1e-11, summaries (extrema located by brentq on the derivative) to 1e-9.

Every comparison selects the backend explicitly with ``backend.use`` (restored after the block).
"""
from __future__ import annotations

import math
import subprocess
import sys

import numpy as np
import pytest
from scipy.special import elliprd, elliprf

from adhfit.core import backend, branches
from adhfit.core.branches import BRANCHES, Context
from adhfit.core.solve import STEP
from adhfit.errors import ConvergenceError
from adhfit.loading import history

numba = pytest.importorskip("numba")
K = pytest.importorskip("adhfit.core.compiled")

INF = math.inf
KEYS = ("a", "alpha", "p", "d", "f", "G", "J0")


def _both(fn, *args, **kwargs):
    """fn(*args, **kwargs) under the numpy and the numba backend: (numpy result, numba result)."""
    out = []
    for name in ("numpy", "numba"):
        with backend.use(name):
            out.append(fn(*args, **kwargs))
    return out


# ----------------------------------------------------------------------------------------------
# Carlson integrals


def _draw_args(rng, n, lo=-12, hi=12):
    return [10.0 ** rng.uniform(lo, hi, n) for _ in range(3)]


@pytest.mark.parametrize("name", ["rf", "rd"])
def test_carlson_real_matches_scipy(name):
    ours, ref = (K.carlson_rf, elliprf) if name == "rf" else (K.carlson_rd, elliprd)
    rng = np.random.default_rng(11)
    x, y, z = _draw_args(rng, 3000)
    got = np.array([ours(a, b, c) for a, b, c in zip(x, y, z)])
    want = ref(x, y, z)
    assert np.max(np.abs(got - want) / np.abs(want)) <= 2e-15


@pytest.mark.parametrize("name", ["rf", "rd"])
def test_carlson_complex_step_matches_scipy(name):
    ours, ref = (K.carlson_rf, elliprf) if name == "rf" else (K.carlson_rd, elliprd)
    rng = np.random.default_rng(12)
    x, y, z = _draw_args(rng, 1500, -8, 8)
    for k in range(3):  # perturb one argument, as a complex step does
        args = [v.astype(complex) for v in (x, y, z)]
        args[k] = args[k] + 1j * 1e-30 * args[k].real
        got = np.array([ours(a, b, c) for a, b, c in zip(*args)])
        want = ref(*args)
        assert np.max(np.abs(got - want) / np.abs(want)) <= 2e-15
        assert np.max(np.abs(got.imag - want.imag) / np.abs(want.imag)) <= 1e-13


@pytest.mark.parametrize("name", ["rf", "rd"])
def test_carlson_general_complex_and_domain(name):
    ours, ref = (K.carlson_rf, elliprf) if name == "rf" else (K.carlson_rd, elliprd)
    rng = np.random.default_rng(13)
    args = [10.0 ** rng.uniform(-6, 6, 1500) * np.exp(1j * rng.uniform(-3.1, 3.1, 1500))
            for _ in range(3)]
    got = np.array([ours(a, b, c) for a, b, c in zip(*args)])
    want = ref(*args)
    assert np.max(np.abs(got - want) / np.abs(want)) <= 2e-15
    # outside the cut plane both give NaN: a negative real argument (real or complex type)
    assert math.isnan(ours(-1.0, 2.0, 3.0)) and np.isnan(ref(-1.0, 2.0, 3.0))
    assert np.isnan(ours(-1.0 + 0j, 2.0 + 0j, 3.0 + 0j)) and np.isnan(ref(-1.0 + 0j, 2, 3))
    # one zero argument is allowed
    assert ours(0.0, 2.0, 3.0) == pytest.approx(ref(0.0, 2.0, 3.0), rel=2e-15)


# ----------------------------------------------------------------------------------------------
# branch states: random locators inside the ranges a history visits

SCENES = {
    "displacement": [dict(p=0.6, w=0.2, rs=0.5), dict(p=0.0, w=0.5, rs=0.5),
                     dict(p=-0.5, w=0.1, rs=0.5), dict(p=0.3, w=0.3, rs=2.0),
                     dict(p=0.4, w=0.2, rs=INF)],
    "pressure": [dict(d=0.0, w=0.2, rs=0.5), dict(d=-0.2, w=0.3, rs=0.5),
                 dict(d=0.1, w=0.1, rs=2.0), dict(d=0.2, w=0.2, rs=INF),
                 dict(d=0.3, w=0.5, rs=INF)],
}
A_MAX = 0.25
PER_SCENE = 45  # 5 scenes x 45 > 200 states per branch and control


def _scene_rows(control, slip, scene):
    """A numpy history of the scene, its context and per-stage (locator, p, a) rows."""
    with backend.use("numpy"):
        h = history(control, slip, a_max=A_MAX, points=60, **scene)
        cols = h.columns
        c = 0.0 if math.isinf(scene["rs"]) else 1.0 / scene["rs"]
        mc = cols["stage"] == "making_contact"
        kappa_m = float(cols["p"][mc][-1])
        e = branches.evaluate(BRANCHES[("making_contact", slip)], None, np.array([kappa_m]),
                              np.array([A_MAX]), Context(c, scene["w"]))
    ctx = Context(c, scene["w"], A_MAX, float(e["J0"][0]))
    rows = {}
    for stage in ("making_contact", "pinning", "delamination"):
        m = cols["stage"] == stage
        key = "a" if stage != "pinning" else ("G" if slip == "no-slip" else "alpha")
        loc = cols[key][m]
        order = np.argsort(loc)
        rows[stage] = (loc[order], cols["p"][m][order], cols["a"][m][order])
    return ctx, rows


def _draw(rng, stage, slip, ctx, rows):
    """Random locators as loading.py places them: a in (0, a_m] while making contact, G in (0, w]
    or alpha in (0, atan sqrt(2w)] while pinned, a in [1e-3 a_m, a_onset] while delaminating."""
    u = rng.uniform(0.02, 0.98, PER_SCENE)
    if stage == "making_contact":
        return ctx.a_m * u
    if stage == "pinning":
        return u * (ctx.w if slip == "no-slip" else math.atan(math.sqrt(2.0 * ctx.w)))
    a_end, a_on = 1e-3 * ctx.a_m, float(rows["delamination"][0][-1])
    return a_end + (a_on - a_end) * u


def _close(a, b, tol):
    a, b = np.asarray(a), np.asarray(b)
    assert a.shape == b.shape
    np.testing.assert_allclose(a, b, rtol=0, atol=tol)


@pytest.mark.parametrize("control", ["displacement", "pressure"])
@pytest.mark.parametrize("stage,slip", [("making_contact", "no-slip"), ("pinning", "no-slip"),
                                        ("pinning", "frictionless"), ("delamination", "no-slip"),
                                        ("delamination", "frictionless")])
def test_branch_states_match_numpy(control, stage, slip):
    rng = np.random.default_rng(abs(hash((control, stage, slip))) % 2**32)
    pc = control == "pressure"
    branch = BRANCHES[(stage, slip)]
    n_states = 0
    for scene in SCENES[control]:
        ctx, rows = _scene_rows(control, slip, scene)
        locs = _draw(rng, stage, slip, ctx, rows)
        r_loc, r_p, r_a = rows[stage]
        k_guess = np.interp(locs, r_loc, r_p)
        x_guess = np.interp(locs, r_loc, r_a) if (stage, slip) == ("pinning", "frictionless") else None
        kw = dict(d_fix=scene["d"], kappa0=k_guess) if pc else dict(kappa=scene["p"])
        solved = []
        for x0 in ((None,) if x_guess is None else (None, x_guess)):
            try:
                (xn, kn), (xc, kc) = _both(backend.solve_state, branch, locs, ctx, x0=x0, **kw)
            except ConvergenceError:  # then the compiled path must fail as well
                with backend.use("numba"), pytest.raises(ConvergenceError):
                    backend.solve_state(branch, locs, ctx, x0=x0, **kw)
                continue
            assert (xn is None) == (xc is None)
            if xn is not None:
                _close(xc, xn, 1e-12)
            _close(kc, kn, 1e-12)
            n_states += locs.size
            solved.append((xn, kn))
        if not solved:
            continue
        # observables at the numpy solution, real and along a complex step in every argument
        x, k = solved[-1]
        en, ec = _both(backend.evaluate, branch, x, k, locs, ctx)
        assert np.array_equal(en["ok"], ec["ok"])
        for key in KEYS:
            _close(ec[key], en[key], 1e-12)
        for xs, ks, ls in ((None if x is None else x + 1j * STEP, k + 0j, locs + 0j),
                           (None if x is None else x + 0j, k + 1j * STEP, locs + 0j),
                           (None if x is None else x + 0j, k + 0j, locs + 1j * STEP)):
            en, ec = _both(backend.evaluate, branch, xs, ks, ls, ctx)
            for key in KEYS:
                _close(ec[key].real, en[key].real, 1e-12)
                scale = np.maximum(1.0, np.abs(en[key].imag / STEP))
                assert np.all(np.abs(ec[key].imag - en[key].imag) / STEP <= 1e-12 * scale)
        dn, dc = _both(backend.derivative, branch, locs, ctx, x, k, pressure_control=pc)
        for key in KEYS:
            scale = np.maximum(1.0, np.abs(dn[key]))
            assert np.all(np.abs(dc[key] - dn[key]) <= 1e-12 * scale), key
    assert n_states >= 200


def test_failed_rows_raise_not_nan():
    """A row without a sign change on its bracket raises ConvergenceError with its inputs."""
    c, w, p = 2.0, 0.2, -0.5
    e = branches.evaluate(BRANCHES[("making_contact", "frictionless")], None, np.array([p]),
                          np.array([A_MAX]), Context(c, w))
    ctx = Context(c, w, A_MAX, float(e["J0"][0]))
    pin = BRANCHES[("pinning", "frictionless")]
    locs = np.array([0.3, 0.0114218197, 0.3])  # the middle row has no sign change on [0, rs)
    for name in ("numpy", "numba"):
        with backend.use(name), pytest.raises(ConvergenceError) as info:
            backend.solve_state(pin, locs, ctx, kappa=p)
        assert info.value.inputs["index"] == 1


def test_check_ok_matches():
    ctx = Context(2.0, 0.2)
    mc = BRANCHES[("making_contact", "no-slip")]
    state = branches.evaluate(mc, None, np.array([0.6, 0.6]), np.array([0.1, 0.2]), ctx)
    for name in ("numpy", "numba"):
        with backend.use(name):
            backend.check_ok(state, "x", {})
            bad = dict(state, f=np.array([state["f"][0], np.nan]))
            with pytest.raises(ConvergenceError) as info:
                backend.check_ok(bad, "x", {"w": 0.2})
            assert info.value.inputs == {"w": 0.2, "index": 1}


# ----------------------------------------------------------------------------------------------
# whole histories

HISTORIES = [
    (control, slip, kw)
    for control in ("displacement", "pressure")
    for slip in ("frictionless", "no-slip")
    for kw in ((dict(p=0.6, rs=0.5), dict(p=0.6, rs=INF), dict(p=0.0, rs=0.5), dict(p=-0.5, rs=0.5))
               if control == "displacement" else
               (dict(d=0.0, rs=0.5), dict(d=0.2, rs=INF), dict(d=-0.2, rs=0.5), dict(d=-0.2, rs=2.0)))
]


@pytest.mark.parametrize("control,slip,kw", HISTORIES,
                         ids=[f"{c}-{s}-{'-'.join(f'{k}{v}' for k, v in kw.items())}"
                              for c, s, kw in HISTORIES])
def test_histories_match_numpy(control, slip, kw):
    hn, hc = _both(history, control, slip, w=0.2, a_max=A_MAX, points=100, **kw)
    assert np.array_equal(hn.columns["stage"], hc.columns["stage"])
    assert np.array_equal(hn.columns["stable"], hc.columns["stable"])
    for key in ("a", "alpha", "p", "d", "delta", "f", "G"):
        np.testing.assert_allclose(hc.columns[key], hn.columns[key], rtol=0, atol=1e-11,
                                   equal_nan=True, err_msg=key)
    assert hc.summary["f_max"] == pytest.approx(hn.summary["f_max"], abs=1e-9)
    for name in ("onset", "f_min", "turning_point"):
        for key, value in hn.summary[name].items():
            if value is None:
                assert hc.summary[name][key] is None
            else:
                assert hc.summary[name][key] == pytest.approx(value, abs=1e-9), (name, key)


# ----------------------------------------------------------------------------------------------
# backend selection


def test_use_restores_and_validates():
    before = backend.active()
    with backend.use("numpy"):
        assert backend.active() == "numpy"
        with backend.use("numba"):
            assert backend.active() == "numba"
        assert backend.active() == "numpy"
    assert backend.active() == before
    with pytest.raises(ValueError, match="ADHFIT_BACKEND"):
        with backend.use("fortran"):
            pass


def test_env_var_selects_numpy_and_import_is_lazy():
    code = ("import sys, adhfit; assert 'numba' not in sys.modules; "
            "from adhfit.core import backend; print(backend.active()); "
            "assert 'numba' not in sys.modules")
    env = {**__import__("os").environ, "ADHFIT_BACKEND": "numpy"}
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True,
                         check=True)
    assert out.stdout.strip() == "numpy"
