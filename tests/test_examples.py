"""The examples run as a user would run them, writing only into a temporary folder."""
import json
import pathlib
import runpy

import pytest

pytestmark = pytest.mark.slow  # runners, CLI and pages: skipped by `pytest -m "not slow"`

EXAMPLES = pathlib.Path(__file__).resolve().parent.parent / "examples"


def test_compare_script(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("MPLBACKEND", "Agg")
    runpy.run_path(str(EXAMPLES / "compare_eccentric.py"), run_name="__main__")
    out = capsys.readouterr().out
    assert "pfvi: steps" in out and "position_error_km" in out
    assert "- period 1154.4 d\n" in out  # rounded, not 1154.3552221033613 d
    # Every row, with its knob value: the extra s = 6 run at epsilon 1e-08 and LEAPFROG's 10000 steps/period.
    assert "..." not in out and "pfvi s=6 epsilon 1e-08" in " ".join(out.split())
    assert "LEAPFROG steps/period 1e+04" in " ".join(out.split())
    assert sorted(p.name for p in (tmp_path / "compare-example").iterdir()) == [
        "kepler-e0.9.csv", "kepler-e0.9.json", "kepler-e0.9.md", "kepler-e0.9.png"]


def test_quickstart_script(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    runpy.run_path(str(EXAMPLES / "quickstart.py"), run_name="__main__")
    out = capsys.readouterr().out
    assert "defaults: {'fitting': 'none'" in out and "'stages': 8" in out
    assert "steps retaken: 0" in out
    error = float(out.split("relative energy error after 10 orbits: ")[1].split()[0])
    assert error < 1e-8
    assert list(tmp_path.iterdir()) == []


def test_notebook_cells(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("MPLBACKEND", "Agg")
    notebook = json.loads((EXAMPLES / "work_precision.ipynb").read_text())
    namespace = {}
    for cell in notebook["cells"]:
        if cell["cell_type"] == "code":
            exec(compile("".join(cell["source"]), "work_precision.ipynb", "exec"), namespace)
    assert len(namespace["table"]) == 15
    assert (tmp_path / "comet-results" / "comet-e0.95.png").exists()
    assert namespace["sim"].integrator.n_steps > 0
