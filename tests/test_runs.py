"""One row type for compare and stability (rebound_pfvi.runs.Run, issue 13): it reads the
committed outputs back with their keys, and every runner's status gets its verdict."""
import json
from pathlib import Path

import pytest

from rebound_pfvi import runs, verdict
from rebound_pfvi.runs import COMPARE, STABILITY, Run

ROOT = Path(__file__).resolve().parent.parent
COMMITTED = sorted((ROOT / "docs" / "results").glob("*.json")) + sorted((ROOT / "docs" / "stability").glob("*.json"))


@pytest.mark.skipif(not COMMITTED, reason="no docs/ beside the tests (an installed package)")
@pytest.mark.parametrize("path", COMMITTED, ids=lambda p: p.name)
def test_committed_rows_read_back_with_their_keys(path):
    rows = json.loads(path.read_text())["rows"]
    assert rows
    for row in rows:
        run = Run.from_dict(row)
        assert run.kind == (COMPARE if "line" in row else STABILITY)
        again = run.to_dict()
        if "verdict" in row:
            assert again == row and list(again) == list(row)  # the same keys, in the same order
        else:  # a page from before the verdicts (mercury-gr): its keys, and the ones added since
            assert {k: again[k] for k in row} == row and [k for k in again if k in row] == list(row)
            assert set(again) - set(row) <= {"relative_position_error", "verdict", "verdict_detail", "warnings"}
        assert run["status"] == row["status"] and run.get("no such key", "-") == "-"


def _identity(kind):
    if kind == COMPARE:
        return Run(COMPARE, "kepler", "pfvi", "pfvi seed s=4 phase reversible", knob="epsilon", value=1e-8,
                   options={"stages": 4, "fitting": "phase"})
    return Run(STABILITY, "kepler-e0.99", "pfvi", "pfvi seed s=4 phase", budget_s=60.0, finite=False,
               options={"fitting": "phase", "stages": 4, "epsilon": 1e-6})


@pytest.mark.parametrize("kind", [COMPARE, STABILITY])
@pytest.mark.parametrize("outcome, status, expected", [
    (("crashed", -11), "crashed: process exit code -11", verdict.CRASHED),
    (("killed", 120.0), "killed: no result 120 s after the start", verdict.OVER_BUDGET),
    (("error", "SystemExit: 3"), "error: SystemExit: 3", verdict.CRASHED),
])
def test_a_run_its_process_did_not_return_is_kept_with_its_verdict(kind, outcome, status, expected):
    run = runs.from_outcome(_identity(kind), outcome)
    assert run.status == status and not run.finished
    assert runs.judge(run) == (expected, status)
    assert run.to_dict()["status"] == status
    # Which integrator on which scene stays: the row is complete.
    assert run.to_dict()["line" if kind == COMPARE else "integrator"] == _identity(kind).label


def test_a_returned_run_is_the_run_itself():
    run = _identity(COMPARE)
    run.status = "ok"
    assert runs.from_outcome(_identity(COMPARE), ("ok", run)) is run


def test_names_and_counts():
    compare_run, stability_run = _identity(COMPARE), _identity(STABILITY)
    assert compare_run.name == "pfvi seed s=4 phase reversible epsilon=1e-08"
    assert stability_run.name == "kepler-e0.99: pfvi seed s=4 phase"
    compare_run.verdict = verdict.INACCURATE
    stability_run.verdict = verdict.REFUSED
    assert compare_run.finished and not stability_run.finished
    counts = runs.count([compare_run, stability_run, compare_run])
    assert counts["pfvi seed s=4 phase reversible"][verdict.INACCURATE] == 2 and counts["pfvi seed s=4 phase"][verdict.REFUSED] == 1
