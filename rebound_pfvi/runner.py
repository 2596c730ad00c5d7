"""Running many runs: worker processes, and a hard time limit on each run.

``compare.run`` and ``stability.run_all`` hand their runs here as
:class:`Task` s (a module-level function, its arguments, a time limit).
:func:`run_tasks` runs them in worker processes, at most ``workers`` at once,
and gives one :data:`Outcome` per task:

- ``("ok", result)``: the function returned `result`;
- ``("error", "Type: message")``: it raised;
- ``("crashed", exit code)``: its process died under it (a crash in C,
  ``os.abort``); a new worker takes the next task;
- ``("killed", seconds)``: it was still running `limit` seconds after it
  started; its process is killed, and a new worker takes the next task.

So a crash or a hang is the outcome of one task, and the others go on. Workers
are started with "spawn": clean, without this process's ctypes callbacks.
With ``fresh=True`` every task gets a process of its own (nothing a run leaves
in a process reaches the next); otherwise a worker takes task after task.
``processes=False`` runs the tasks one after the other in this process (no
limit is enforced then: nothing can stop this process from outside).

``done(index, outcome)`` is called as each task ends. Ctrl-C, or an exception
raised by ``done``, kills every worker at once and propagates, so what
``done`` recorded is kept. A worker that dies before it can take a task (a
script that starts runs has no ``if __name__ == "__main__":`` guard, and every
worker imports it) raises :class:`WorkerStartError` instead of being replaced
for ever.

:func:`run_tasks_dask` gives the same outcomes from a Dask ``distributed``
scheduler (no hard limit there).
"""
from __future__ import annotations

import math
import multiprocessing
import pickle
import signal
import time
from collections import deque
from dataclasses import dataclass
from multiprocessing.connection import wait as wait_for
from typing import Any, Callable, Deque, List, Optional, Tuple

#: What became of a task: ("ok", result) | ("error", message) | ("crashed", exit code) | ("killed", seconds).
Outcome = Tuple[str, Any]
#: done(index of the task, its outcome), called as each task ends.
DoneCallback = Callable[[int, Outcome], None]

#: A run still busy this long after its budget is killed (the step under way
#: when the budget runs out is finished first: the budget stops a run between
#: steps, from a timer thread).
GRACE_SECONDS = 60.0

_READY = "ready"
#: The longest wait for a message before the workers are looked at again.
_POLL_SECONDS = 1.0


@dataclass(frozen=True)
class Task:
    """function(*args) in a worker; killed once it has run `limit` seconds (None: no limit)."""

    function: Callable[..., Any]  # module-level: a worker imports it by name
    args: Tuple[Any, ...] = ()
    limit: Optional[float] = None


class WorkerStartError(RuntimeError):
    """A worker process died before it could take a task."""


def call(function: Callable[..., Any], args: Tuple[Any, ...]) -> Outcome:
    """("ok", function(*args)), or ("error", "Type: message") if it raises."""
    try:
        return "ok", function(*args)
    except Exception as error:  # noqa: BLE001 - a task's failure is its outcome
        return "error", f"{type(error).__name__}: {error}"


def _worker(conn: Any, max_tasks: Optional[int]) -> None:
    """A worker process: tasks from `conn`, their outcomes back, until the parent closes it."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C belongs to the parent, which stops the workers
    taken = 0
    try:
        conn.send(_READY)
    except OSError:
        return  # the parent ended every task before this worker was up
    while max_tasks is None or taken < max_tasks:
        try:
            message = conn.recv_bytes()
        except (EOFError, OSError):
            return  # the parent has no more tasks
        taken += 1
        try:
            function, args = pickle.loads(message)
            outcome: Outcome = "ok", function(*args)
        except BaseException as error:  # noqa: BLE001 - SystemExit too: reported to the parent, which records it
            outcome = "error", f"{type(error).__name__}: {error}"
        try:
            conn.send(outcome)
        except Exception as error:  # noqa: BLE001 - a result that cannot be pickled
            conn.send(("error", f"the result could not be sent back: {type(error).__name__}: {error}"))
    conn.close()


@dataclass
class _Worker:
    process: Any  # multiprocessing's process and the parent's end of its pipe
    conn: Any
    fresh: bool  # it takes one task, then exits
    ready: bool = False  # it has started and waits for tasks
    index: Optional[int] = None  # the task it runs
    deadline: float = math.inf  # time.monotonic() at which that task is killed
    finished: bool = False  # fresh: it ran its task and exits by itself


def _start(ctx: Any, fresh: bool) -> _Worker:
    parent, child = ctx.Pipe()
    process = ctx.Process(target=_worker, args=(child, 1 if fresh else None), daemon=True)
    process.start()
    child.close()
    return _Worker(process, parent, fresh)


def run_tasks(tasks: List[Task], workers: int = 1, processes: bool = True, fresh: bool = False,
              done: Optional[DoneCallback] = None) -> List[Outcome]:
    """Runs every task (see the module docstring); returns their outcomes, in order."""
    if not processes:
        return _run_here(tasks, done)
    ctx = multiprocessing.get_context("spawn")
    outcomes: List[Outcome] = [("error", "not run")] * len(tasks)  # each replaced when its task ends
    pending: Deque[int] = deque(range(len(tasks)))
    pool: List[_Worker] = []
    exiting: List[_Worker] = []  # fresh workers that ran their task

    def end(worker: _Worker, outcome: Outcome) -> None:
        index = worker.index
        assert index is not None
        worker.index = None
        outcomes[index] = outcome
        if done is not None:
            done(index, outcome)

    completed = False
    try:
        while pending or any(w.index is not None for w in pool):
            # A worker for each task that waits without one, up to `workers`.
            idle = sum(1 for w in pool if w.index is None)
            for _ in range(min(max(1, workers) - len(pool), len(pending) - idle)):
                pool.append(_start(ctx, fresh))
            for worker in pool:
                if worker.ready and worker.index is None and pending:
                    _send(worker, pending.popleft(), tasks, end)
            busy = [w.deadline for w in pool if w.index is not None]
            timeout = min([_POLL_SECONDS] + [max(0.0, d - time.monotonic()) for d in busy])
            wait_for([w.conn for w in pool] + [w.process.sentinel for w in pool], timeout)
            for worker in list(pool):
                exited = not worker.process.is_alive()  # first: what it sent before it exited is read below
                open_ = _receive(worker, end)
                if worker.finished:
                    pool.remove(worker)
                    exiting.append(worker)
                elif exited or not open_:
                    worker.process.join()
                    worker.conn.close()
                    pool.remove(worker)
                    if not worker.ready:
                        raise WorkerStartError(f"a worker process died before it could take a run (exit code "
                                               f"{worker.process.exitcode})")
                    if worker.index is not None:
                        end(worker, ("crashed", worker.process.exitcode))
                elif worker.index is not None and time.monotonic() > worker.deadline:
                    worker.process.kill()
                    worker.process.join()
                    worker.conn.close()
                    pool.remove(worker)
                    end(worker, ("killed", tasks[worker.index].limit))
            for worker in [w for w in exiting if not w.process.is_alive()]:
                worker.process.join()
                worker.conn.close()
                exiting.remove(worker)
        completed = True
    finally:
        _stop(pool + exiting, completed)
    return outcomes


def _send(worker: _Worker, index: int, tasks: List[Task], end: Callable[[_Worker, Outcome], None]) -> None:
    task = tasks[index]
    worker.index = index
    worker.deadline = time.monotonic() + task.limit if task.limit is not None else math.inf
    try:
        payload = pickle.dumps((task.function, task.args))
    except Exception as error:  # noqa: BLE001 - a task that cannot be sent is its outcome
        end(worker, ("error", f"the run could not be sent to a worker: {type(error).__name__}: {error}"))
        return
    try:
        worker.conn.send_bytes(payload)
    except OSError:
        pass  # the worker died: the loop finds it and records the task as crashed


def _receive(worker: _Worker, end: Callable[[_Worker, Outcome], None]) -> bool:
    """Reads what the worker sent; False once its pipe is closed (it exited)."""
    try:
        while not worker.finished and worker.conn.poll():
            message = worker.conn.recv()
            if message == _READY:
                worker.ready = True
            else:
                end(worker, message)
                worker.finished = worker.fresh
    except (EOFError, OSError):
        return False
    return True


def _stop(workers: List[_Worker], completed: bool) -> None:
    """Ends the workers: after the last task, those waiting for one by closing their pipes (they
    exit); any other (still starting; Ctrl-C or an error in this process) at once."""
    for worker in workers:
        if completed and (worker.ready or worker.finished):
            worker.conn.close()
        else:
            worker.process.kill()
    for worker in workers:
        worker.process.join(timeout=10.0)
        if worker.process.is_alive():
            worker.process.kill()
            worker.process.join()
        worker.conn.close()


def _run_here(tasks: List[Task], done: Optional[DoneCallback]) -> List[Outcome]:
    outcomes = []
    for index, task in enumerate(tasks):
        outcome = call(task.function, task.args)
        outcomes.append(outcome)
        if done is not None:
            done(index, outcome)
    return outcomes


def run_tasks_dask(tasks: List[Task], scheduler: Any, done: Optional[DoneCallback] = None
                   ) -> Tuple[List[Outcome], int, str]:
    """Runs every task on a Dask distributed scheduler (an address or a
    ``distributed.Client``); returns their outcomes, the number of workers and
    "dask <address>". Limits are not enforced there."""
    try:
        from distributed import Client, as_completed
    except ImportError:
        raise ImportError("scheduler: sending runs to Dask needs the [dask] extra: "
                          "pip install 'rebound_pfvi[dask]'") from None
    client = scheduler if isinstance(scheduler, Client) else Client(scheduler)
    address = client.scheduler.address
    outcomes: List[Outcome] = [("error", "not run")] * len(tasks)
    try:
        workers = len(client.scheduler_info()["workers"])
        futures = [client.submit(call, task.function, task.args, pure=False) for task in tasks]
        index = {future.key: i for i, future in enumerate(futures)}
        try:
            for future in as_completed(futures):
                try:
                    outcome = future.result()
                except Exception as error:  # noqa: BLE001 - a worker lost with its run: that run's outcome
                    outcome = "error", f"{type(error).__name__}: {error}"
                outcomes[index[future.key]] = outcome
                if done is not None:
                    done(index[future.key], outcome)
        except KeyboardInterrupt:
            client.cancel(futures)
            raise
    finally:
        if client is not scheduler:
            client.close()
    return outcomes, workers, f"dask {address}"
