"""One runner for compare and stability (rebound_pfvi.runner, issue 13)."""
import pytest

from rebound_pfvi import runner

pytestmark = pytest.mark.slow  # spawns processes: skipped by `pytest -m "not slow"`


def test_tasks_in_this_process_and_in_workers_give_the_same_outcomes():
    tasks = [runner.Task(divmod, (7, 2)), runner.Task(divmod, (1, 0))]
    expected = [("ok", (3, 1)), ("error", "ZeroDivisionError: integer division or modulo by zero")]
    assert runner.run_tasks(tasks, processes=False) == expected
    assert runner.run_tasks(tasks, workers=2) == expected
    assert runner.run_tasks(tasks, workers=2, fresh=True) == expected
