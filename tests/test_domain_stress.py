"""A reduced run of ``benchmarks/stress_domain.py`` (issue 24): random scenes from the parameter table
through both engines, every outcome classed. The full run (10,000 large-stretch and 1,000 exact scenes)
and its numbers are in ``benchmarks/results/stress_domain_*.md``; no timing is asserted here."""
from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def sd():
    spec = importlib.util.spec_from_file_location("stress_domain", ROOT / "benchmarks" / "stress_domain.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_stability_invariant_flags_a_stable_row_above_the_loading_end(sd):
    fr = pd.DataFrame({"stage": ["making_contact"] * 3 + ["pinning"] * 3,
                       "delta": [0.0, 0.1, 0.2, 0.19, 0.25, 0.1], "stable": [True] * 5 + [False]})
    assert sd.stability(fr, "displacement")
    fr.loc[4, "stable"] = False
    fr.loc[5, "stable"] = False
    assert sd.stability(fr, "displacement") == []


@pytest.mark.parametrize("membrane,n", [("large-stretch", 40), ("exact", 4)])
def test_reduced_random_run_has_no_silent_failure(sd, membrane, n):
    rng = np.random.default_rng(24)
    scenes = [sd.draw(rng, membrane, 0.2) for _ in range(n)]
    outs = sd.run(scenes, membrane, 60, workers=1)
    kinds = [o["kind"] for o in outs]
    assert set(kinds) <= set(sd.KINDS)
    bad = [(sc, o) for sc, o in zip(scenes, outs)
           if o["kind"] in ("other_exception", "nan_in_output", "invariant_violation")]
    assert bad == []
    for o in outs:  # a DomainError says so, and never "did not converge"
        if o["kind"] == "domain_error":
            assert o["detail"].startswith("no solution exists") and "did not converge" not in o["detail"]
