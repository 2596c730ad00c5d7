"""One run of one integrator on one scene: the row that ``compare`` and
``stability`` produce, :mod:`rebound_pfvi.runner` carries back from the
workers, :mod:`rebound_pfvi.verdict` judges and :mod:`rebound_pfvi.report`
writes.

A :class:`Run` is read by attribute. Its :meth:`Run.to_dict` is the row of
the JSON and CSV files, with the keys each report has always written
(``compare``: scene, line, knob, value, options, t_final, ...; ``stability``:
case, integrator, fitting, stages, epsilon, t, fraction, ...), and
:meth:`Run.from_dict` reads such a row back (``docs/results/*.json``,
``docs/stability/stability.json``). ``run[key]`` and ``run.get(key)`` read the
same keys, as the rows were dicts before.

Statuses, as each runner writes them: ``compare`` "ok", "diverged (...)",
"over budget: ...", "failed: <exception>: <message>"; ``stability``
"finished", "stopped by the budget of ...", "refused: <message>", "error:
<exception>: <message>"; both, for a run whose process did not return it
(:func:`failed_status`), "crashed: process exit code <n>" and "killed: no
result <n> s after the start". :func:`judge` reads every one of them.
"""
from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING, Any, Callable, Dict, List, Mapping, Optional, Sequence, Tuple

from . import verdict

if TYPE_CHECKING:
    import rebound

    from .runner import Outcome

COMPARE = "compare"
STABILITY = "stability"
#: Statuses of a run that got to its end (its errors are measured).
FINISHED = ("ok", "finished")

Vector = Tuple[float, float, float]
#: progress(done, total, run), called after each run of compare.run and stability.run_all.
ProgressCallback = Callable[[int, int, "Run"], None]

#: compare's JSON keys for what pfvi counted -> the keys of Run.pfvi.
_COMPARE_PFVI = {"pfvi_force_evaluations": "n_force_evaluations", "attempts_per_step": "attempts_per_step",
                 "iterations_mean": "iterations_mean", "n_rejected": "n_rejected"}
#: stability's JSON keys for what pfvi counted (the same in Run.pfvi).
_STABILITY_PFVI = ("n_steps", "n_attempts", "n_rejected", "n_asymmetric", "n_unresolved", "n_u_limited",
                   "iterations_max")


def pfvi_counts(sim: rebound.Simulation) -> Dict[str, float]:
    """What pfvi counted over a run (``sim.integrator``'s statistics), for :attr:`Run.pfvi`."""
    ri = sim.integrator
    steps, attempts = int(ri.n_steps), int(ri.n_attempts)
    return {"n_steps": steps, "n_attempts": attempts, "attempts_per_step": attempts / max(1, steps),
            "n_rejected": int(ri.n_rejected), "n_asymmetric": int(ri.n_asymmetric),
            "n_unresolved": int(ri.n_unresolved), "n_u_limited": int(ri.n_u_limited),
            "iterations_max": int(ri.iterations_max),
            "iterations_mean": float(ri.iterations_mean), "n_force_evaluations": int(ri.n_force_evaluations)}


@dataclass
class Run:
    """One run: which integrator on which scene, what became of it, what it measured.

    Measurements are None where the run did not get to them (a refused or
    crashed run, or one stopped by its budget)."""

    kind: str  # COMPARE or STABILITY: the runner that made it, and so the keys of to_dict()
    scene: str  # the scene's name (compare) or the case's (stability)
    family: str  # pfvi, ias15, whfast, leapfrog, bs
    label: str  # the integrator with its options: compare's "line", stability's "integrator"
    options: Dict[str, Any] = field(default_factory=dict)  # compare: the setting's; stability: fitting, stages, epsilon
    knob: str = ""  # compare: the accuracy knob's name (epsilon, eps, steps/period) ...
    value: Optional[float] = None  # ... and its value
    status: str = ""  # what happened, in the runner's words (module docstring)
    verdict: str = ""  # rebound_pfvi.verdict's word ("" until judged) ...
    verdict_detail: str = ""  # ... and its detail
    budget_s: Optional[float] = None  # stability: seconds of integration allowed
    wall_s: Optional[float] = None  # wall time of the run (compare: the best of its repeats)
    walls_s: Optional[List[float]] = None  # compare: every repeat's wall time
    steps: Optional[int] = None
    t: Optional[float] = None  # the time reached
    fraction: Optional[float] = None  # stability: t reached as a fraction of t_end
    energy_error_final: Optional[float] = None  # relative energy error at the end ...
    energy_error_max: Optional[float] = None  # ... and the largest at the checkpoints
    position_error: Optional[float] = None  # against the reference at t
    relative_position_error: Optional[float] = None  # the one the verdict reads (rebound_pfvi.verdict)
    force_evaluations: Optional[int] = None  # compare: counted through additional_forces
    pfvi: Optional[Dict[str, float]] = None  # what pfvi counted (pfvi_counts); None for other families
    positions: Optional[List[Vector]] = None  # stability: every particle's position at t (not written)
    finite: Optional[bool] = None  # stability: whether that state is finite
    warnings: List[str] = field(default_factory=list)  # compare: REBOUND's warnings during the run
    #: compare, a scene with outputs (the solar system): each body's largest
    #: error over the outputs, {against: {body: km}} (Scene.output_errors)
    bodies: Optional[Dict[str, Any]] = None
    what_happened: str = ""  # stability: the verdict's detail and what pfvi counted, for the page

    @property
    def name(self) -> str:
        """The run in a few words, for progress bars: "pfvi s=4 phase epsilon=1e-08", "kepler-e0.99: IAS15"."""
        if self.kind == COMPARE:
            return f"{self.label} {self.knob}={self.value:g}"
        return f"{self.scene}: {self.label}"

    @property
    def finished(self) -> bool:
        """Whether the run got to its end: its verdict is accurate or inaccurate (before it is judged: its status)."""
        if self.verdict:
            return self.verdict in (verdict.ACCURATE, verdict.INACCURATE)
        return self.status in FINISHED

    def to_dict(self) -> Dict[str, Any]:
        """The run as a row of the JSON and CSV files, with the keys its report has always written."""
        if self.kind == COMPARE:
            row: Dict[str, Any] = {"scene": self.scene, "family": self.family, "line": self.label, "knob": self.knob,
                                   "value": self.value, "options": dict(self.options), "status": self.status}
            if self.wall_s is not None:  # the timed runs finished
                row.update(wall_s=self.wall_s, walls_s=self.walls_s, steps=self.steps, t_final=self.t,
                           energy_error_final=self.energy_error_final, position_error=self.position_error,
                           relative_position_error=self.relative_position_error)
            if self.pfvi is not None:
                row.update({key: self.pfvi[name] for key, name in _COMPARE_PFVI.items()})
            if self.energy_error_max is not None:  # the sampled rerun finished
                row.update(energy_error_max=self.energy_error_max, force_evaluations=self.force_evaluations)
            if self.bodies is not None:
                row["bodies"] = self.bodies
            row.update(verdict=self.verdict, verdict_detail=self.verdict_detail, warnings=list(self.warnings))
            return row
        row = {"case": self.scene, "integrator": self.label, "family": self.family,
               "fitting": self.options.get("fitting"), "stages": self.options.get("stages"),
               "epsilon": self.options.get("epsilon"), "status": self.status, "budget_s": self.budget_s,
               "t": self.t, "fraction": self.fraction, "wall_s": self.wall_s, "steps": self.steps,
               "energy_error": self.energy_error_final, "energy_error_max": self.energy_error_max,
               "finite": self.finite}
        if self.pfvi is not None:
            row.update({key: self.pfvi[key] for key in _STABILITY_PFVI})
        row.update(position_error=self.position_error, relative_position_error=self.relative_position_error,
                   verdict=self.verdict, verdict_detail=self.verdict_detail, what_happened=self.what_happened)
        return row

    @classmethod
    def from_dict(cls, row: Mapping[str, Any]) -> Run:
        """A row of a JSON file (:meth:`to_dict`) as a Run; to_dict() gives the row back."""
        if "line" in row:
            pfvi = ({name: row[key] for key, name in _COMPARE_PFVI.items()} if "pfvi_force_evaluations" in row
                    else None)
            return cls(COMPARE, row["scene"], row["family"], row["line"], options=dict(row["options"]),
                       knob=row["knob"], value=row["value"], status=row["status"],
                       verdict=row.get("verdict", ""), verdict_detail=row.get("verdict_detail", ""),
                       wall_s=row.get("wall_s"), walls_s=row.get("walls_s"), steps=row.get("steps"),
                       t=row.get("t_final"), energy_error_final=row.get("energy_error_final"),
                       energy_error_max=row.get("energy_error_max"), position_error=row.get("position_error"),
                       relative_position_error=row.get("relative_position_error"),
                       force_evaluations=row.get("force_evaluations"), pfvi=pfvi,
                       warnings=list(row.get("warnings", ())), bodies=row.get("bodies"))
        # (n_unresolved: reports written before it existed have none)
        pfvi = {key: row.get(key, 0) for key in _STABILITY_PFVI} if "n_steps" in row else None
        options = {"fitting": row.get("fitting"), "stages": row.get("stages"), "epsilon": row.get("epsilon")}
        return cls(STABILITY, row["case"], row["family"], row["integrator"], options=options, status=row["status"],
                   verdict=row.get("verdict", ""), verdict_detail=row.get("verdict_detail", ""),
                   budget_s=row.get("budget_s"), wall_s=row.get("wall_s"), steps=row.get("steps"), t=row.get("t"),
                   fraction=row.get("fraction"), energy_error_final=row.get("energy_error"),
                   energy_error_max=row.get("energy_error_max"), position_error=row.get("position_error"),
                   relative_position_error=row.get("relative_position_error"), pfvi=pfvi,
                   finite=row.get("finite"), what_happened=row.get("what_happened", ""))

    def __getitem__(self, key: str) -> Any:
        """run[key]: the value of `key` in :meth:`to_dict` (KeyError if the row has no such key)."""
        return self.to_dict()[key]

    def get(self, key: str, default: Any = None) -> Any:
        """run.get(key, default): as a dict's, on :meth:`to_dict`."""
        return self.to_dict().get(key, default)


#: What REBOUND's warnings mean for a run, for the page and the command line.
WARNING_MEANINGS = {
    "predictor corrector loops in IAS15 did not converge":
        "IAS15's predictor-corrector iteration hit its limit in 10 or more steps, REBOUND's sign that the "
        "steps are too long for the tolerance; the run went on, and its error is measured like any other",
    "Passing a velocity-dependent force to WHFAST":
        "REBOUNDx's warning that WHFast's kick assumes forces that do not depend on velocity, so it takes GR "
        "only approximately and its error grows with the force; the runs went on, and their errors are "
        "measured like any other",
}


def explain_warning(message: str) -> str:
    """A REBOUND warning in the words of :data:`WARNING_MEANINGS` (else the message itself)."""
    for key, meaning in WARNING_MEANINGS.items():
        if key in message:
            return meaning
    return message


def failed_status(outcome: Outcome) -> str:
    """The status of a run whose process did not return it (:data:`rebound_pfvi.runner.Outcome`)."""
    kind, detail = outcome
    if kind == "crashed":
        return f"crashed: process exit code {detail}"
    if kind == "killed":
        return f"killed: no result {detail:g} s after the start"
    return f"error: {detail}"


def from_outcome(run: Run, outcome: Outcome) -> Run:
    """The run that came back, or `run` (which integrator on which scene) with
    the status of what became of its process."""
    if outcome[0] == "ok":
        result: Run = outcome[1]
        return result
    return replace(run, status=failed_status(outcome))


def judge(run: Run, tolerance: verdict.Tolerance = verdict.DEFAULT) -> Tuple[str, str]:
    """(verdict, detail) of a run from its status (either runner's, see the
    module docstring) and, if it finished, its errors against `tolerance`."""
    status = run.status
    if status in FINISHED:
        return verdict.judge(run.energy_error_max, run.relative_position_error, tolerance,
                             finite=run.finite is not False)
    if status.startswith("diverged"):
        return verdict.INACCURATE, status
    if status.startswith("over budget: "):
        return verdict.OVER_BUDGET, status[len("over budget: "):]
    if status.startswith(("stopped by the budget", "killed")):
        detail = status
        if run.fraction is not None:
            detail += f", at {run.fraction:.3g} of the run"
            if run.finite and run.relative_position_error is not None:
                detail += (f" (so far: energy error {run.energy_error_max:.2g}, position error "
                           f"{run.relative_position_error:.2g} of the distance)")
        return verdict.OVER_BUDGET, detail
    if status.startswith("refused: "):
        return verdict.REFUSED, status[len("refused: "):]
    if status.startswith("failed: "):  # compare: the exception the run raised
        error = status[len("failed: "):]
        kind = verdict.of_exception(error)
        if kind == verdict.REFUSED:
            return kind, error[len("RuntimeError: "):]
        return kind, error
    return verdict.CRASHED, status


def count(runs: Sequence[Run]) -> Dict[str, Dict[str, int]]:
    """{label: {verdict: runs}} (a label is an integrator with its options, e.g. "pfvi s=4 phase")."""
    return verdict.count(({"label": r.label, "verdict": r.verdict} for r in runs), "label")
