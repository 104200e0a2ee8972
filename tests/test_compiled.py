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
- The one-call history kernel against the step-by-step reference, both under the numba backend:
  the kernel makes the same solver calls from the same predictors on the same compiled branch
  functions, so only the order of a few floating-point operations differs (typically ~1e-13); rows,
  summaries and the end of the delamination branch are held to 1e-12 (1 + |value|). Where the
  no-slip delamination branch ends early, its end is located by step halving to ~1e-10 of the
  log-span, so a last-bit difference upstream moves it by ~1e-10 relative; near the end the state
  goes like sqrt(a - a_end), so the rows move by up to ~1e-8 and the last row (at the end itself)
  by up to ~1e-5: those histories are held to 1e-7 (end, rows, summary) and 1e-5 (last row).
- The joint (x, kappa) Newton and its nested fallback: the root is converged to XTOL = 4e-15
  (1 + |x|) either way, so a state solved from any predictor matches its history row to 1e-10
  (headroom for the 1e-11 between the backends' histories); anything further is another root.

Every comparison selects the backend explicitly with ``backend.use`` (restored after the block).
"""
from __future__ import annotations

import math
import subprocess
import sys

import numpy as np
import pytest
from scipy.special import elliprd, elliprf

from adhfit import loading
from adhfit.core import backend, branches
from adhfit.core.branches import BRANCHES, Context
from adhfit.core.solve import STEP
from adhfit.errors import ConvergenceError, InputError
from adhfit.loading import STAGES, history

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
# the whole history in one compiled call (loading._history_compiled) against the step-by-step
# reference (loading._history_steps), both under the numba backend

COMBOS = [(control, slip) for control in ("displacement", "pressure")
          for slip in ("no-slip", "frictionless")]
#: random scenes compared (10 per control x slip combination) and the share of them the kernel may
#: leave to the step path although the steps succeed (a fallback costs time, not correctness)
N_KERNEL_SCENES = 40
MAX_FALLBACK_SHARE = 0.10
#: kernel vs steps: same solver calls from the same predictors (module docstring)
KERNEL_TOL = 1e-12
#: ... for histories that end where the no-slip delamination branch ends (module docstring)
BRANCH_END_TOL, BRANCH_END_LAST_ROW_TOL = 1e-7, 1e-5
#: scenes whose no-slip delamination branch ends early, one per control, always in the sample
BRANCH_END_SCENES = [("pressure", "no-slip", dict(d=0.0, w=0.2, rs=0.3, a_max=0.25)),
                     ("displacement", "no-slip", dict(p=0.3, w=0.01, rs=0.5, a_max=0.25))]


def _prepared(control, slip, points=200, **kw):
    """The arguments ``history`` passes to ``_history_compiled`` / ``_history_steps``: (v, c, pc, info).

    Raises InputError for an invalid scene, as ``history`` does.
    """
    v, c, pc = loading._prepare(control, slip, kw.get("p"), kw.get("d"), kw["w"], kw["rs"],
                                kw.get("a_max"), None, None, 2.0, points)
    v["slip"] = slip
    info = {"control": control, "slip": slip, **{k: v[k] for k in v if k != "slip"}}
    return v, c, pc, info


def _random_scene(rng, control):
    """A random scene: w log-uniform in [0.02, 3], rs log-uniform in [0.3, 5] or (one in five) inf,
    a_max in [0.1, min(0.4, 0.9 rs)], p in (-0.5, 0.9) or d in (-0.3, 0.5); may be invalid (the
    caller draws again)."""
    rs = INF if rng.uniform() < 0.2 else float(np.exp(rng.uniform(math.log(0.3), math.log(5.0))))
    kw = dict(w=float(np.exp(rng.uniform(math.log(0.02), math.log(3.0)))), rs=rs,
              a_max=float(rng.uniform(0.1, min(0.4, 0.9 * rs))))
    if control == "displacement":
        kw["p"] = float(rng.uniform(-0.5, 0.9))
    else:  # contact must start at the apex: 2d/(1 + d^2) > -1/rs, so d > 0 on a flat substrate
        kw["d"] = float(rng.uniform(0.0 if math.isinf(rs) else -0.3, 0.5))
    return kw


def _valid_scenes(seed, n, points=200):
    """n valid scenes, round robin over COMBOS: (control, slip, kw, (v, c, pc, info))."""
    rng = np.random.default_rng(seed)
    out = []
    while len(out) < n:
        control, slip = COMBOS[len(out) % len(COMBOS)]
        kw = _random_scene(rng, control)
        try:
            out.append((control, slip, kw, _prepared(control, slip, points, **kw)))
        except InputError:  # e.g. p <= -1/rs (contact would not start at the apex): draw again
            continue
    return out


def _run_both(prepared):
    """(kernel History or None, steps History or the error it raised), both under numba."""
    v, c, pc, info = prepared
    with backend.use("numba"):
        fast = loading._history_compiled(backend.compiled_kernels(), dict(v), c, pc, dict(info))
        try:
            slow = loading._history_steps(dict(v), c, pc, dict(info))
        except (ConvergenceError, InputError) as err:
            slow = err
    return fast, slow


def _assert_same_history(got, want, tol, what="", last_row_tol=None):
    """Same rows (stage, stable exactly; numbers to tol (1 + |value|), the last row to
    ``last_row_tol`` if given), summary and branch end."""
    gc, wc = got.columns, want.columns
    assert gc["a"].size == wc["a"].size, f"row count {what}"
    assert np.array_equal(gc["stage"], wc["stage"]), f"stage {what}"
    assert np.array_equal(gc["stable"], wc["stable"]), f"stable {what}"
    n = gc["a"].size if last_row_tol is None else gc["a"].size - 1
    for key in ("a", "alpha", "p", "d", "delta", "f", "G"):
        np.testing.assert_allclose(gc[key][:n], wc[key][:n], rtol=tol, atol=tol, equal_nan=True,
                                   err_msg=f"{key} {what}")
        if last_row_tol is not None:
            np.testing.assert_allclose(gc[key][n:], wc[key][n:], rtol=last_row_tol,
                                       atol=last_row_tol, equal_nan=True,
                                       err_msg=f"{key} (last row) {what}")
    assert got.summary.keys() == want.summary.keys()
    assert got.summary["f_max"] == pytest.approx(want.summary["f_max"], rel=tol, abs=tol), what
    for name in ("onset", "f_min", "turning_point"):
        assert got.summary[name].keys() == want.summary[name].keys()
        for key, value in want.summary[name].items():
            if value is None:  # delta where |p| > 1
                assert got.summary[name][key] is None, (name, key, what)
            else:
                assert got.summary[name][key] == pytest.approx(value, rel=tol, abs=tol), \
                    (name, key, what)
    end_got = got.inputs.get("delamination_ends_at_a")
    end_want = want.inputs.get("delamination_ends_at_a")
    assert (end_got is None) == (end_want is None), f"delamination_ends_at_a {what}"
    if end_want is not None:
        assert end_got == pytest.approx(end_want, rel=tol, abs=tol), what


def test_history_kernel_matches_steps():
    """Over random valid scenes of all four control x slip combinations, the kernel gives the rows,
    summary and branch end of the steps, fails wherever the steps fail, and rarely falls back."""
    fallbacks = compared = ends = 0
    fixed = [(control, slip, kw, _prepared(control, slip, **kw))
             for control, slip, kw in BRANCH_END_SCENES]
    for control, slip, kw, prepared in fixed + _valid_scenes(4, N_KERNEL_SCENES):
        what = f"{control} {slip} {kw}"
        fast, slow = _run_both(prepared)
        if isinstance(slow, Exception):
            # the kernel must not return a history the reference cannot compute
            assert fast is None, f"the kernel solved a scene the steps fail on ({slow}): {what}"
            continue
        if fast is None:  # allowed: history() then runs the steps
            fallbacks += 1
            continue
        if slow.inputs.get("delamination_ends_at_a") is None:
            _assert_same_history(fast, slow, KERNEL_TOL, what)
        else:
            _assert_same_history(fast, slow, BRANCH_END_TOL, what, BRANCH_END_LAST_ROW_TOL)
            ends += 1
        compared += 1
    assert fallbacks <= MAX_FALLBACK_SHARE * N_KERNEL_SCENES
    # the sample must exercise the comparison (the engine fails on a few per cent of scenes), also
    # of no-slip delamination branches that end before detachment (the fixed scenes)
    assert compared >= 0.75 * N_KERNEL_SCENES
    assert ends >= len(BRANCH_END_SCENES)


#: scenes outside the model (the free membrane would turn past vertical at the clamp: during
#: frictionless pinning, resp. delamination), where the engine must raise; tried first, then random
#: scenes until one fails
FAILING = [("displacement", "frictionless", dict(p=0.8730865449674674, w=0.5724287762117387,
                                                 rs=INF, a_max=0.38867600174120276)),
           ("displacement", "frictionless", dict(p=0.8887974631736837, w=1.0129281610550642,
                                                 rs=0.9537064212966431, a_max=0.3675337521385025))]


def _failing_scene(max_draws=400):
    """(control, slip, kw, kernel result, the steps' error) of a valid scene the steps (numba) raise
    ConvergenceError on; None if there is none among FAILING and max_draws random scenes."""
    rng = np.random.default_rng(7)
    candidates = iter(FAILING)
    for i in range(max_draws):
        item = next(candidates, None)
        if item is None:
            control, slip = COMBOS[i % len(COMBOS)]
            item = (control, slip, _random_scene(rng, control))
        control, slip, kw = item
        try:
            prepared = _prepared(control, slip, **kw)
        except InputError:
            continue
        fast, slow = _run_both(prepared)
        if isinstance(slow, ConvergenceError):
            return control, slip, kw, fast, slow
    return None


def test_history_kernel_failure_falls_back_with_message(monkeypatch):
    """history() asks the kernel first and runs the steps when it returns None; where the engine
    cannot solve a scene, the error is the steps' ConvergenceError, naming the stage."""
    scene = dict(d=0.0, w=0.2, rs=0.5, a_max=0.25)
    calls = []

    def kernel_fails(K, v, c, pc, info):
        calls.append(v)
        return None

    with backend.use("numba"):
        fast = history("pressure", "no-slip", **scene)
        v, c, pc, info = _prepared("pressure", "no-slip", **scene)
        reference = loading._history_steps(v, c, pc, info)
        monkeypatch.setattr(loading, "_history_compiled", kernel_fails)
        slow = history("pressure", "no-slip", **scene)
    assert len(calls) == 1
    # the step path itself: identical; the kernel's history: to KERNEL_TOL
    _assert_same_history(slow, reference, 0.0)
    _assert_same_history(fast, slow, KERNEL_TOL)
    with backend.use("numpy"):  # no kernel to ask under numpy
        history("pressure", "no-slip", **scene)
    assert len(calls) == 1
    monkeypatch.undo()

    found = _failing_scene()
    if found is None:
        pytest.skip("no valid scene found that the engine fails on: no failure to fall back from")
    control, slip, kw, fast, err = found
    assert fast is None, f"the kernel solved a scene the steps fail on: {control} {slip} {kw}"
    with backend.use("numba"), pytest.raises(ConvergenceError) as info:
        history(control, slip, **kw)
    # the steps' full message, which names the stage that failed
    assert str(info.value) == str(err)
    stage_names = STAGES + tuple(s.replace("_", " ") for s in STAGES) + ("end of loading",)
    assert any(name in str(info.value) for name in stage_names), str(info.value)


# ----------------------------------------------------------------------------------------------
# pressure control: the joint (x, kappa) Newton, and the nested solve for the rows it fails on

JOINT_SCENE = dict(d=0.0, w=0.2, rs=0.5, a_max=0.25)
#: a state solved from any predictor must be its history row's (module docstring)
ROOT_TOL = 1e-10


def _joint_setup():
    """Context and numpy history of JOINT_SCENE (pressure control, no slip)."""
    v, c, pc, _ = _prepared("pressure", "no-slip", **JOINT_SCENE)
    with backend.use("numpy"):
        ctx, _ = loading._ctx_after_loading(v, c, pc)
        h = history("pressure", "no-slip", **JOINT_SCENE)
    return ctx, h.columns


def _row_state(cols, i, stage, ctx):
    """(locator, t, kappa) of history row i: no slip, t solves cos(alpha) = 1 - (G - (t-1)^2/2)/t,
    t^2 - 2 cos(alpha) t + 1 - 2G = 0; of its two roots, the one that satisfies the material and gap
    conditions at the row's pressure."""
    branch = BRANCHES[(stage, "no-slip")]
    loc = np.array([cols["G"][i] if stage == "pinning" else cols["a"][i]])
    k = float(cols["p"][i])
    ca, G = math.cos(cols["alpha"][i]), float(cols["G"][i])
    disc = max(ca * ca - 1.0 + 2.0 * G, 0.0)
    best = None
    for t in (ca + math.sqrt(disc), ca - math.sqrt(disc)):
        e = branches.evaluate(branch, np.array([t]), np.array([k]), loc, ctx)
        target = np.broadcast_to(branch.target(loc, ctx), loc.shape)[0]
        res = abs(e["J0"][0] - target) + abs(e["d"][0] - JOINT_SCENE["d"])
        if best is None or res < best[0]:
            best = (res, t)
    assert best[0] <= 1e-12  # the row is a solved state (its alpha rounded to ~1e-16)
    return loc, best[1], k


def _joint_converges(name, branch, loc, ctx, k0, x0):
    """Whether the joint Newton of backend ``name`` converges from (x0, k0) (one row), with its
    Jacobian by differences or, failing that, exact (what runs before the nested solve)."""
    d = JOINT_SCENE["d"]
    for fd in (True, False):
        if name == "numpy":
            good = branches._joint_newton(branch, loc, ctx, d, np.array([k0]), np.array([x0]),
                                          fd=fd)[2][0]
        else:
            good = K._joint_one(backend._CODES[branch.stage, branch.slip], float(loc[0]), ctx.c,
                                ctx.w, ctx.a_m, ctx.L_m, d, float(k0), float(x0), fd)[2]
        if good:
            return True
    return False


@pytest.mark.parametrize("name", ["numpy", "numba"])
def test_joint_newton_falls_back_from_a_bad_predictor(name):
    """From a good predictor the joint Newton solves the row; from a poor one (x at an edge of its
    bracket, kappa off by 0.5) it fails and the nested solve must find the same root, or raise:
    never another finite state."""
    ctx, cols = _joint_setup()
    d = JOINT_SCENE["d"]
    for stage in ("pinning", "delamination"):
        branch = BRANCHES[(stage, "no-slip")]
        rows = np.flatnonzero(cols["stage"] == stage)
        fell_back = 0
        for i in rows[[rows.size // 4, rows.size // 2, (3 * rows.size) // 4, -1]]:
            loc, t, k = _row_state(cols, i, stage, ctx)
            lo, hi = (float(np.ravel(b)[0]) for b in branch.bracket(np.array([k]), loc, ctx))
            predictors = [(t + 1e-4, k + 1e-4)] + [(x0, k + dk) for x0 in (lo, hi)
                                                   for dk in (0.5, -0.5)]
            for j, (x0, k0) in enumerate(predictors):
                joint = _joint_converges(name, branch, loc, ctx, k0, x0)
                if j == 0:
                    assert joint, (stage, i)  # a good predictor needs no fallback
                what = f"{name} {stage} row {i}: x0={x0!r}, kappa0={k0!r}"
                with backend.use(name):
                    try:
                        x, kappa = backend.solve_state(branch, loc, ctx, d_fix=d,
                                                       kappa0=np.array([k0]), x0=np.array([x0]))
                    except ConvergenceError:
                        assert j > 0, what  # only a poor predictor may fail
                        continue
                e = branches.evaluate(branch, x, kappa, loc, ctx)
                assert e["ok"][0], what
                for key in ("a", "alpha", "p", "f", "G"):
                    assert abs(e[key][0] - cols[key][i]) <= ROOT_TOL, (key, what)
                fell_back += not joint
        assert fell_back > 0, stage  # the nested fallback was exercised and found the root


def test_joint_newton_flags_failed_rows():
    """branches._joint_newton: a row with a NaN predictor is not good, a good predictor's row is,
    and the good row's root does not depend on its neighbours."""
    ctx, cols = _joint_setup()
    d = JOINT_SCENE["d"]
    for stage in ("pinning", "delamination"):
        branch = BRANCHES[(stage, "no-slip")]
        rows = np.flatnonzero(cols["stage"] == stage)
        loc, t, k = _row_state(cols, rows[rows.size // 2], stage, ctx)
        locs = np.repeat(loc, 3)
        x, kappa, good = branches._joint_newton(branch, locs, ctx, d, np.array([k + 1e-4, k, np.nan]),
                                                np.array([t + 1e-4, np.nan, t]))
        assert good.tolist() == [True, False, False]
        assert abs(x[0] - t) <= ROOT_TOL and abs(kappa[0] - k) <= ROOT_TOL


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
