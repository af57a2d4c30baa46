"""Every teaching notebook executes top to bottom without raising (its own asserts included).

A notebook's experiment sizes sit in one cell tagged ``parameters`` (papermill's convention).
The test runs each notebook with smaller sizes (:data:`SMALLER`), injected as a cell right
after that one, so the default ``pytest -q`` stays fast; every assert of the notebook runs
on the smaller experiment. The documentation build (``python docs/build.py``) executes the
notebooks as written, at full size.
"""

from __future__ import annotations

from pathlib import Path

import nbformat
import pytest
from conftest import ROOT
from nbclient import NotebookClient

NOTEBOOKS = sorted((ROOT / "notebooks").glob("*.ipynb"))

#: Smaller sizes per notebook, overriding names of its ``parameters`` cell.
SMALLER: dict[str, dict[str, object]] = {
    "02_drift_routing.ipynb": {"STUDY_SCENARIOS": 3, "STUDY_GA_GENERATIONS": 20},
    "03_obstacles_capabilities.ipynb": {
        "FIGURE_CELL": 2.0,
        "GAP_TARGETS": 10,
        "GAP_GA_GENERATIONS": 30,
    },
    "04_limited_communication.ipynb": {"RANGE_SCENARIOS": 4},
    "05_truck_drone.ipynb": {"GA_GENERATIONS": 50},
    "06_budgeted.ipynb": {"GA_GENERATIONS": 20, "TIGHTNESS": (0.4, 0.5, 1.0)},
    "07_fleet.ipynb": {"FLEET_CUSTOMERS": 4, "SEARCH_ITERATIONS": 3},
}


def parameters_cell(nb: nbformat.NotebookNode) -> int | None:
    """Index of the cell tagged ``parameters``, or None."""
    for k, cell in enumerate(nb.cells):
        if cell.cell_type == "code" and "parameters" in cell.metadata.get("tags", []):
            return k
    return None


def with_smaller_sizes(nb: nbformat.NotebookNode, sizes: dict[str, object]) -> None:
    """Insert ``NAME = value`` lines after the parameters cell (each name must be defined there)."""
    where = parameters_cell(nb)
    assert where is not None, "a notebook with smaller test sizes needs a 'parameters' cell"
    defined = nb.cells[where].source
    for name in sizes:
        assert f"\n{name} = " in f"\n{defined}", f"{name} is not set in the parameters cell"
    source = "\n".join(f"{name} = {value!r}" for name, value in sizes.items())
    nb.cells.insert(where + 1, nbformat.v4.new_code_cell(source))


def test_notebooks_exist() -> None:
    """notebooks/ holds at least one notebook."""
    assert NOTEBOOKS, "notebooks/ holds no notebook"


def test_smaller_sizes_name_real_notebooks() -> None:
    """Every notebook named in SMALLER exists and sets each overridden name in its parameters."""
    names = {p.name: p for p in NOTEBOOKS}
    for notebook, sizes in SMALLER.items():
        assert notebook in names, f"{notebook} is not in notebooks/"
        nb = nbformat.read(names[notebook], as_version=4)
        with_smaller_sizes(nb, sizes)  # asserts every name is a parameter


@pytest.mark.parametrize("path", NOTEBOOKS, ids=[p.name for p in NOTEBOOKS])
def test_notebook_executes(path: Path) -> None:
    """The notebook (with its smaller test sizes) runs every cell and every assert cleanly."""
    nb = nbformat.read(path, as_version=4)
    # Outputs are stripped before commit (STYLE.md).
    for cell in nb.cells:
        if cell.cell_type == "code":
            assert not cell.get("outputs"), f"{path.name}: commit notebooks without outputs"
    if path.name in SMALLER:
        with_smaller_sizes(nb, SMALLER[path.name])
    client = NotebookClient(
        nb, timeout=300, kernel_name="python3", resources={"metadata": {"path": str(path.parent)}}
    )
    client.execute()
