"""Outcome classification of ``benchmarks/stress.py`` on synthetic histories (no engine run).

A no-slip history whose quasi-static delamination branch ends early (``inputs["delamination_ends_at_a"]``)
is a valid outcome of its own kind; anything else that breaks a contract stays an invariant violation.
"""
from __future__ import annotations

import argparse
import importlib.util
import math
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def stress():
    spec = importlib.util.spec_from_file_location("stress_script", ROOT / "benchmarks" / "stress.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


W, A_MAX = 0.5, 0.4
SCENE = {"control": "displacement", "slip": "no-slip", "p": 0.3, "w": W, "rs": math.inf, "a_max": A_MAX,
         "lambda0": 2.0}


def _history(a_last: float) -> tuple[pd.DataFrame, dict]:
    """A consistent no-slip history (making contact, pinning, delamination) ending at ``a_last``."""
    a_dl = np.linspace(0.34, a_last, 4)
    fr = pd.DataFrame({
        "stage": ["making_contact"] * 4 + ["pinning"] * 3 + ["delamination"] * 4,
        "a": np.r_[0.0, 0.1, 0.3, A_MAX, [A_MAX] * 3, a_dl],
        "alpha": np.r_[[0.0] * 4, 0.43, 0.65, 0.71, [0.70] * 4],
        "p": 0.3, "d": 0.1,
        "delta": np.linspace(0.0, -0.3, 11),
        "f": np.r_[0.0, 0.01, 0.08, 0.15, -0.47, -0.93, -1.09, -0.96, -0.83, -0.61, -0.25],
        "G": np.r_[[0.0] * 4, 0.125, 0.375, W, [W] * 4],
        "stable": [True] * 9 + [False] * 2,
    })
    pt = {"f": -1.09, "delta": -0.3, "p": 0.3, "a": A_MAX}
    summary = {"f_max": 0.15, "onset": dict(pt), "f_min": dict(pt), "turning_point": dict(pt)}
    return fr, summary


def _inputs(**extra) -> dict:
    return {**SCENE, "points": 12, **extra}


def test_history_near_detachment_is_success(stress):
    fr, s = _history(1e-4)
    assert stress.classify(fr, s, _inputs(), SCENE)["kind"] == "success"


def test_early_end_has_its_own_kind(stress):
    fr, s = _history(0.2)
    out = stress.classify(fr, s, _inputs(delamination_ends_at_a=0.2), SCENE)
    assert out["kind"] == stress.EARLY
    assert out["ends_at_over_a_max"] == pytest.approx(0.2 / A_MAX)


def test_stopping_early_without_the_record_is_a_violation(stress):
    fr, s = _history(0.2)
    out = stress.classify(fr, s, _inputs(), SCENE)
    assert out["kind"] == "invariant_violation" and "not near detachment" in out["detail"]


@pytest.mark.parametrize("case", ["wrong_radius", "G_above_w", "frictionless", "outside_onset",
                                  "last_row_pinning"])
def test_early_end_still_meets_every_other_contract(stress, case):
    fr, s = _history(0.2)
    ends_at, scene = 0.2, dict(SCENE)
    if case == "wrong_radius":
        ends_at = 0.25
    elif case == "G_above_w":
        fr.loc[8, "G"] = 1.01 * W
    elif case == "frictionless":
        scene["slip"] = "frictionless"
    elif case == "outside_onset":
        fr.loc[fr.index[-1], "a"] = ends_at = 0.45
    else:
        fr.loc[fr.index[-1], "stage"] = "pinning"
    out = stress.classify(fr, s, _inputs(delamination_ends_at_a=ends_at), scene)
    assert out["kind"] == "invariant_violation", out


def test_early_end_with_nonfinite_output_is_nan(stress):
    fr, s = _history(0.2)
    assert stress.classify(fr, s, _inputs(delamination_ends_at_a=math.nan), SCENE)["kind"] == "nan_in_output"
    fr.loc[9, "f"] = math.inf
    assert stress.classify(fr, s, _inputs(delamination_ends_at_a=0.2), SCENE)["kind"] == "nan_in_output"


def test_report_counts_and_spread(stress, tmp_path, monkeypatch):
    scenes = [dict(SCENE, a_max=0.1 * (i + 1)) for i in range(4)]
    outcomes = [{"kind": "success", "time": 0.001, "rows": 11},
                {"kind": stress.EARLY, "time": 0.002, "rows": 11, "ends_at_over_a_max": 0.5},
                {"kind": stress.EARLY, "time": 0.002, "rows": 11, "ends_at_over_a_max": 0.9},
                {"kind": "invariant_violation", "time": 0.003, "rows": 11, "detail": "x"}]
    monkeypatch.setattr(stress, "machine_info", lambda: {"python": "test"})
    args = argparse.Namespace(seed=1, timeout=60.0, workers=2, other_ends=0.1)
    rep = stress.summarize(scenes, outcomes, args, 1.0)
    assert rep["counts"]["success"] == 1 and rep["counts"][stress.EARLY] == 2
    assert rep["counts"]["invariant_violation"] == 1
    assert stress.EARLY not in rep["failures"] and len(rep["failures"]["invariant_violation"]) == 1
    early = rep["branch_ends_early"]
    assert early["count"] == 2 and [e["index"] for e in early["examples"]] == [1, 2]
    assert early["ends_at_over_a_max"] == {"min": 0.5, "median": pytest.approx(0.7), "max": 0.9}
    stress.write_markdown(rep, tmp_path / "stress.md")
    md = (tmp_path / "stress.md").read_text()
    assert "| success (delamination branch ends early) | 2 | 50.00 % |" in md
    assert "min 0.5, median 0.7, max 0.9" in md
