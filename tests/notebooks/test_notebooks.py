"""The example notebooks (examples/notebooks/) run from top to bottom in a kernel of this Python
environment, each in a fresh folder, and draw their figures."""
from __future__ import annotations

from pathlib import Path

import nbformat
import pytest
from nbclient import NotebookClient

ROOT = Path(__file__).resolve().parents[2]
NOTEBOOKS = ROOT / "examples" / "notebooks"


@pytest.fixture(autouse=True)
def _kernel_backend(monkeypatch):
    """The kernel picks its own (inline) matplotlib backend, as in a notebook, not the suite's Agg."""
    monkeypatch.delenv("MPLBACKEND", raising=False)


def _execute(name: str, cwd: Path) -> nbformat.NotebookNode:
    """The notebook ``name`` run in ``cwd`` (each cell at most 300 s), with its outputs."""
    nb = nbformat.read(NOTEBOOKS / name, as_version=4)
    NotebookClient(nb, timeout=300, kernel_name="python3", resources={"metadata": {"path": str(cwd)}}).execute()
    return nb


def _images(nb: nbformat.NotebookNode) -> int:
    return sum(1 for cell in nb.cells if cell.cell_type == "code"
               for out in cell.get("outputs", []) if "image/png" in out.get("data", {}))


def test_the_notebooks_folder_holds_the_notebooks_tested_here():
    assert sorted(p.name for p in NOTEBOOKS.glob("*.ipynb")) == ["run-quick.ipynb", "small-study.ipynb"]


def test_the_run_notebook_runs_and_plots_the_run(tmp_path):
    nb = _execute("run-quick.ipynb", tmp_path)
    assert _images(nb) == 1
    assert "tracking" in str(nb.cells[2].outputs)


def test_the_study_notebook_runs_the_study_and_shows_its_table_and_figure(tmp_path):
    nb = _execute("small-study.ipynb", tmp_path)
    assert _images(nb) == 1
    assert any("text/html" in out.get("data", {}) for out in nb.cells[2].outputs)  # the table
    assert (tmp_path / "studies_out" / "quick-comparison" / "runs").is_dir()


@pytest.mark.parametrize("name", ["run-quick.ipynb", "small-study.ipynb"])
def test_the_notebooks_are_stored_without_outputs(name):
    nb = nbformat.read(NOTEBOOKS / name, as_version=4)
    assert all(not cell.get("outputs") and cell.get("execution_count") is None
               for cell in nb.cells if cell.cell_type == "code")
