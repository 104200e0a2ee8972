"""Shared pytest configuration: ``--runslow`` runs the full statistical/reference tests; without it
their reduced CI variants run and the full ones are skipped."""
from __future__ import annotations

import pytest


def pytest_addoption(parser):
    parser.addoption("--runslow", action="store_true", default=False,
                     help="run tests marked slow (full statistical and reference runs)")


def pytest_collection_modifyitems(config, items):
    if config.getoption("--runslow"):
        return
    skip = pytest.mark.skip(reason="slow: run with --runslow (a reduced variant runs in CI)")
    for item in items:
        if "slow" in item.keywords:
            item.add_marker(skip)


@pytest.fixture
def runslow(request) -> bool:
    """True when the full (slow) variants were requested."""
    return bool(request.config.getoption("--runslow"))
