"""examples/tour.ipynb runs from top to bottom in a fresh kernel of this interpreter, in a
scratch folder, as a user would start it; it draws the figures it promises, its comparison
with the analytical model gives finite numbers, and its first impacts agree with the impact law
within the tolerances it states. The repository keeps it without outputs."""

import json
import math
import sys
from pathlib import Path

import nbformat
import pytest
from ipykernel.kernelspec import write_kernel_spec
from jupyter_client.kernelspec import KernelSpecManager
from jupyter_client.manager import KernelManager
from nbclient import NotebookClient

NOTEBOOK = Path(__file__).resolve().parents[1] / "examples" / "tour.ipynb"
CELL_TIMEOUT = 600
"""s per cell: the longest, the run, takes 8 s on the 2-core development machine, 24 s with
numba compiling from cold."""

PROBE = """
import json, sys
print(json.dumps({
    "executable": sys.executable,
    "compared": table[["simulated", "analytic"]].to_numpy().tolist(),
    "first_impacts": len(errors),
    "median": float(np.median(errors)),
    "worst": float(errors.max()),
    "tolerances": [MEDIAN_TOLERANCE, WORST_TOLERANCE],
}))
"""
"""A cell run after the notebook's own: the values its cells left, as JSON on stdout."""


def kernel(folder: Path) -> KernelManager:
    """A kernel manager for an IPython kernel of ``sys.executable``, from a kernel spec written
    in ``folder``: no ``python3`` spec elsewhere (the user's, the system's, JUPYTER_PATH's)
    can put another interpreter in its place."""
    write_kernel_spec(folder / "tour")
    specs = KernelSpecManager(kernel_dirs=[str(folder)], ensure_native_kernel=False)
    return KernelManager(kernel_name="tour", kernel_spec_manager=specs)


def stdout(cell: nbformat.NotebookNode) -> str:
    """What an executed cell printed."""
    return "".join(o.text for o in cell.outputs if o.get("name") == "stdout")


@pytest.fixture(scope="module")
def executed(tmp_path_factory) -> nbformat.NotebookNode:
    """The notebook, executed with the probe cell appended, in a scratch working folder."""
    nb = nbformat.read(NOTEBOOK, as_version=4)
    nb.cells.append(nbformat.v4.new_code_cell(PROBE, id="probe"))
    work = tmp_path_factory.mktemp("tour")
    client = NotebookClient(
        nb,
        km=kernel(tmp_path_factory.mktemp("kernels")),
        timeout=CELL_TIMEOUT,
        resources={"metadata": {"path": str(work)}},
    )
    client.execute()  # CellExecutionError, with the cell and its traceback, if a cell raises
    return nb


def test_stored_without_outputs():
    nb = nbformat.read(NOTEBOOK, as_version=4)
    nbformat.validate(nb)
    for cell in nb.cells:
        if cell.cell_type == "code":
            assert not cell.outputs and cell.execution_count is None, cell.id


def test_kernel_is_this_interpreter(executed):
    assert json.loads(stdout(executed.cells[-1]))["executable"] == sys.executable


def test_figure_cells_draw(executed):
    figures = [c for c in executed.cells if "figure" in c.metadata.get("tags", [])]
    assert len(figures) == 3
    for cell in figures:
        assert any("image/png" in o.get("data", {}) for o in cell.outputs), cell.id


def test_compare_table_and_impact_law(executed):
    values = json.loads(stdout(executed.cells[-1]))
    assert values["compared"], "the compare step gave no row"
    assert all(math.isfinite(x) for row in values["compared"] for x in row)
    median, worst = values["tolerances"]
    stated = next(c.source for c in executed.cells if c.id == "law-md")
    for tolerance in (median, worst):  # the tolerances the text states are those checked
        assert f"within {tolerance * 100:g} %" in stated, tolerance
    assert values["first_impacts"] >= 20
    assert values["median"] <= median
    assert values["worst"] <= worst
