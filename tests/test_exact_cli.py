"""``adhfit simulate --membrane exact``: the A2 CSV and JSON, lambda0 matters, errors in one line."""
from __future__ import annotations

import json

import pandas as pd
import pytest

from adhfit.cli import main

ARGS = ["simulate", "--control", "displacement", "--slip", "frictionless", "--p", "0.6", "--w", "0.2",
        "--rs", "0.5", "--a-max", "0.25", "--points", "30"]


def test_exact_csv_json_and_lambda0(tmp_path, capsys):
    out = {}
    for lam0 in ("1.2", "3"):
        path = tmp_path / f"c{lam0}.csv"
        assert main([*ARGS, "--membrane", "exact", "--lambda0", lam0, "-o", str(path), "--json"]) == 0
        out[lam0] = json.loads(capsys.readouterr().out)
        frame = pd.read_csv(path)
        assert list(frame.columns) == ["stage", "a", "alpha", "p", "d", "delta", "f", "G", "stable"]
        assert frame["f"].max() == pytest.approx(out[lam0]["f_max"], abs=1e-12)
    assert main([*ARGS, "--json"]) == 0
    ls = json.loads(capsys.readouterr().out)
    # issue 11: the exact loading force is ~15 % below the approximation at lambda0 = 1.2, <1 % at 3
    assert out["1.2"]["f_max"] / ls["f_max"] == pytest.approx(0.85, abs=0.01)
    assert abs(out["3"]["f_max"] / ls["f_max"] - 1) < 0.01


def test_exact_bad_lambda0(capsys):
    assert main([*ARGS, "--membrane", "exact", "--lambda0", "0.9"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "lambda0" in err[0] and "0.9" in err[0]
