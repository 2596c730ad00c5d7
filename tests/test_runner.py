"""One runner for compare and stability (rebound_pfvi.runner, issue 13): a run that crashes its
worker or outlives its budget is that run's verdict, and the sweep goes on."""
import ctypes
import time

import pytest

from rebound_pfvi import compare, runner, scenes, verdict

pytestmark = pytest.mark.slow  # spawns processes: skipped by `pytest -m "not slow"`


class SegfaultingPfvi(scenes.Kepler):
    """A Kepler scene whose pfvi runs crash their process (a segfault, as a bug in C would)."""

    def configure_pfvi(self, sim, frequency):
        ctypes.string_at(0)  # reads address 0: SIGSEGV


class HangingPfvi(scenes.Kepler):
    """A Kepler scene whose pfvi runs hang where the budget's timer cannot stop them (outside integrate())."""

    def configure_pfvi(self, sim, frequency):
        time.sleep(600.0)


# The seed's pfvi line: the scene sets its frequency (configure_pfvi), where these scenes fail.
SETTINGS = [compare.Setting("ias15", 1e-9), compare.Setting("pfvi", 1e-6, (("fitting", "phase"),)),
            compare.Setting("whfast", 100)]


def test_a_run_that_crashes_its_worker_is_recorded_as_crashed(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)  # a core file, if the system writes one, lands here
    seen = []
    results = compare.run(SegfaultingPfvi(e=0.5, periods=1), SETTINGS, repeats=1, samples=3, workers=2,
                          progress=lambda done, total, run: seen.append(run.name))
    assert not results.interrupted and results.finished == 3 and len(seen) == 3
    ias15, pfvi, whfast = results.rows
    assert pfvi.verdict == verdict.CRASHED and pfvi.status.startswith("crashed: process exit code ")
    assert pfvi.label == "pfvi seed s=8 phase" and pfvi.wall_s is None
    assert ias15.verdict == whfast.verdict == verdict.ACCURATE  # the workers after the crash went on
    assert results.verdict_counts()["pfvi seed s=8 phase"][verdict.CRASHED] == 1


def test_a_run_its_budget_cannot_stop_is_killed_and_over_budget(monkeypatch):
    monkeypatch.setattr(runner, "GRACE_SECONDS", 1.0)  # killed 1 s after its budget, not a minute
    tick = time.monotonic()
    results = compare.run(HangingPfvi(e=0.5, periods=1), SETTINGS, repeats=1, samples=3, workers=2, budget=2.0)
    assert time.monotonic() - tick < 60.0
    ias15, pfvi, whfast = results.rows
    assert pfvi.status == "killed: no result 3 s after the start"
    assert pfvi.verdict == verdict.OVER_BUDGET and pfvi.verdict_detail == pfvi.status
    assert ias15.verdict == whfast.verdict == verdict.ACCURATE


def test_tasks_in_this_process_and_in_workers_give_the_same_outcomes():
    tasks = [runner.Task(divmod, (7, 2)), runner.Task(divmod, (1, 0))]
    expected = [("ok", (3, 1)), ("error", "ZeroDivisionError: integer division or modulo by zero")]
    assert runner.run_tasks(tasks, processes=False) == expected
    assert runner.run_tasks(tasks, workers=2) == expected
    assert runner.run_tasks(tasks, workers=2, fresh=True) == expected
