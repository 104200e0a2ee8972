"""Every notebook in notebooks/ runs top to bottom (a notebook that does not run is a defect).

Executed with nbclient on the ``python3`` kernel of this interpreter's ipykernel, from the notebooks/
directory, with ``ADHFIT_FAST=1`` so that each finishes in well under a minute. Committed notebooks carry
no outputs.
"""
from __future__ import annotations

from pathlib import Path

import pytest

nbformat = pytest.importorskip("nbformat")
nbclient = pytest.importorskip("nbclient")
pytest.importorskip("ipykernel")

NOTEBOOKS = Path(__file__).resolve().parents[1] / "notebooks"
PATHS = sorted(NOTEBOOKS.glob("*.ipynb"))
CELL_TIMEOUT = 300  # s per cell: generous for loaded CI machines; FAST cells take seconds


def test_the_seven_notebooks_are_there():
    names = [p.stem for p in PATHS]
    for prefix in ("01_forward_model_tour", "02_fit_least_squares", "03_mcmc_uncertainty",
                   "04_parameter_recovery", "05_runtime_vs_error", "06_planning", "07_exact_membrane"):
        assert prefix in names


@pytest.mark.parametrize("path", PATHS, ids=[p.stem for p in PATHS])
def test_committed_without_outputs(path):
    nb = nbformat.read(path, as_version=4)
    for cell in nb.cells:
        if cell.cell_type == "code":
            assert not cell.outputs and cell.execution_count is None, f"{path.name}: clear the outputs"
    assert nb.metadata["kernelspec"]["name"] == "python3"


@pytest.mark.parametrize("path", PATHS, ids=[p.stem for p in PATHS])
def test_notebook_runs(path, monkeypatch):
    monkeypatch.setenv("ADHFIT_FAST", "1")
    monkeypatch.setenv("MPLBACKEND", "module://matplotlib_inline.backend_inline")
    # the kernel must be this interpreter's: jupyter_client replaces a kernelspec argv "python" by
    # sys.executable, and preferring the environment's data path keeps a stale user-level "python3"
    # kernelspec (pointing to another Python) from shadowing it
    monkeypatch.setenv("JUPYTER_PREFER_ENV_PATH", "1")
    nb = nbformat.read(path, as_version=4)
    client = nbclient.NotebookClient(nb, timeout=CELL_TIMEOUT, kernel_name="python3",
                                     resources={"metadata": {"path": str(NOTEBOOKS)}})
    client.execute()
    errors = [o for c in nb.cells if c.cell_type == "code" for o in c.outputs if o.output_type == "error"]
    assert not errors
