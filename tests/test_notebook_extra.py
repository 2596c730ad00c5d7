"""examples/work_precision.ipynb run as a notebook, through a Jupyter kernel,
with what the `notebook` extra installs (skipped without it)."""
import pathlib
import shutil

import pytest

NOTEBOOK = pathlib.Path(__file__).resolve().parent.parent / "examples" / "work_precision.ipynb"


def test_notebook_executes_in_a_kernel(tmp_path, monkeypatch):
    # MPLBACKEND unset: the kernel draws inline, so the plot is an output.
    nbformat = pytest.importorskip("nbformat")
    nbclient = pytest.importorskip("nbclient")
    pytest.importorskip("ipykernel")
    pytest.importorskip("nbconvert")
    monkeypatch.delenv("MPLBACKEND", raising=False)
    copy = tmp_path / NOTEBOOK.name
    shutil.copy(NOTEBOOK, copy)
    notebook = nbformat.read(str(copy), as_version=4)
    # The kernel runs in tmp_path: the notebook's files go there, and the
    # source tree is not on its path (it imports the installed package).
    nbclient.NotebookClient(notebook, timeout=600, kernel_name="python3",
                            resources={"metadata": {"path": str(tmp_path)}}).execute()
    outputs = [o for cell in notebook.cells if cell.cell_type == "code" for o in cell.outputs]
    assert not [o for o in outputs if o.output_type == "error"]
    text = "".join(o.get("text", "") for o in outputs if o.output_type == "stream")
    assert "Comet: Sun, Jupiter" in text and " steps," in text
    assert any("image/png" in o.get("data", {}) for o in outputs)  # the work-precision plot
    assert (tmp_path / "comet-results" / "comet-e0.95.png").stat().st_size > 10000
