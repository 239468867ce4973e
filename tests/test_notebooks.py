"""The tutorials in notebooks/ are stored without outputs and run from top to bottom on small settings.

Each notebook reads FINGERTIP_QUICK=1 (coarse meshes, short simulations) and writes its pictures into
FINGERTIP_NOTEBOOK_OUT. Executed with nbclient in a fresh ipykernel; skipped only if those are not installed.
"""

import json
from pathlib import Path

import pytest

NOTEBOOKS = sorted((Path(__file__).parents[1] / "notebooks").glob("*.ipynb"))
CELL_TIMEOUT = 240          # s per cell: the quick FEM solves take 5-10 s here; leaves room for a slow CI machine
PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


def test_there_are_at_least_three_tutorials():
    assert len(NOTEBOOKS) >= 3, [path.name for path in NOTEBOOKS]


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda path: path.stem)
def test_notebook_is_stored_without_outputs(path):
    cells = json.loads(path.read_text())["cells"]
    code = [cell for cell in cells if cell["cell_type"] == "code"]
    assert code
    assert all(cell["outputs"] == [] and cell["execution_count"] is None for cell in code)
    assert "FINGERTIP_QUICK" in "".join(code[0]["source"])        # the small-settings switch, in the first cell


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda path: path.stem)
def test_notebook_runs_on_small_settings(path, tmp_path, monkeypatch):
    nbformat = pytest.importorskip("nbformat")
    nbclient = pytest.importorskip("nbclient")
    pytest.importorskip("ipykernel", reason="the notebooks run in an ipykernel (pip install ipykernel)")
    monkeypatch.setenv("FINGERTIP_QUICK", "1")
    monkeypatch.setenv("FINGERTIP_NOTEBOOK_OUT", str(tmp_path))
    monkeypatch.setenv("MPLBACKEND", "Agg")
    notebook = nbformat.read(path, as_version=4)
    client = nbclient.NotebookClient(notebook, timeout=CELL_TIMEOUT, kernel_name="python3",
                                     resources={"metadata": {"path": str(tmp_path)}})
    client.execute()                                     # raises CellExecutionError with the failing cell
    errors = [output for cell in notebook.cells for output in cell.get("outputs", ())
              if output.get("output_type") == "error"]
    assert not errors
    for picture in tmp_path.glob("*.png"):              # what the notebook saved is a real image
        assert picture.read_bytes()[:8] == PNG_SIGNATURE, picture.name
    if path.stem.startswith("01"):
        assert (tmp_path / "01_gel_state_3d.png").stat().st_size > 10_000     # the PyVista off-screen rendering
