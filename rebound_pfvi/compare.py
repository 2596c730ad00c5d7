"""Error against run time: pfvi beside REBOUND's integrators on one scene.

A sweep is a list of :class:`Setting` s (one integrator, one accuracy knob:
pfvi's and IAS15's epsilon, BS's tolerance, WHFast's and LEAPFROG's step).
Each setting is run by :func:`run_setting`, which

1. times ``sim.integrate(t_end)`` from a fresh simulation ``repeats`` times
   and keeps the best (least) wall time; the final state of the timed run
   gives the final relative energy error and the position error against the
   scene's reference (a scene with ``output_times()``, the solar system,
   integrates to each output instead and reads every position there, inside
   the timed loop: its ``output_errors`` become the run's ``bodies``);
2. runs once more, untimed, stopping at ``samples`` evenly spaced times
   without changing the steps (``exact_finish_time=0``: at the first step's
   end at or past each, a time already passed sampled where the run is; exactly at them for
   a scene whose energy holds only within the run) to find the largest
   relative energy error, with a callback in ``additional_forces`` that adds
   nothing and counts force evaluations;
3. gives the run its verdict (:mod:`rebound_pfvi.verdict`: accurate,
   inaccurate, refused, crashed) against the scene's tolerance.

:func:`run` sends the settings to local worker processes (default; see
:mod:`rebound_pfvi.runner`: a run that crashes its process is recorded as
"crashed", one still busy a minute after its budget is killed and recorded as
"over budget"), to a Dask ``distributed`` scheduler
(``scheduler="tcp://..."``), or runs them in this process (``workers=1``).
Every run is a :class:`rebound_pfvi.runs.Run`. Runs that share cores are timed
under the same load; compare wall times within one sweep, not across machines
or sweeps.

Everything here is unitless (AU, yr, Msun); :class:`Results` converts to
astropy Quantities at the boundary.
"""
from __future__ import annotations

import functools
import math
import numbers
import os
import time
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Callable, Dict, List, Optional, Sequence, Tuple

from . import DEFAULTS, checks, runner, runs, verdict
from .integrators import FAMILIES, WHFAST_CORRECTED, pfvi_label, pfvi_options
from .integrators import configure as configure_integrator
from .runs import ProgressCallback, Run

if TYPE_CHECKING:
    import rebound

    from .scenes import Scene

#: Each family's name on the pages.
FAMILY_NAMES = {"pfvi": "pfvi", "ias15": "IAS15", "whfast": "WHFast", "leapfrog": "LEAPFROG", "bs": "BS",
                "trace": "TRACE", "mercurius": "MERCURIUS"}
#: The accuracy knob of each family, as the table and plot call it.
KNOBS = {"pfvi": "epsilon", "ias15": "epsilon", "bs": "eps", "whfast": "steps/period",
         "leapfrog": "steps/period", "trace": "steps/period", "mercurius": "steps/period"}


#: The fields each family's knob sets (configure() sets them from a setting's value).
KNOB_FIELDS = {"pfvi": ("epsilon",), "ias15": ("epsilon",), "bs": ("eps_abs", "eps_rel")}


@functools.lru_cache(maxsize=None)
def _pfvi_statistics() -> Tuple[str, ...]:
    """pfvi's read-only statistics (in its field list beside the options)."""
    from . import _STATISTICS

    return tuple(_STATISTICS)


def family_fields(family: str) -> Tuple[str, ...]:
    """The settable fields of a family's integrator, as REBOUND lists them."""
    import rebound

    from .integrators import integrator_fields

    sim = rebound.Simulation()
    sim.integrator = family
    return tuple(sorted(integrator_fields(sim)))


def _check_option_values(family: str, options: Tuple[Tuple[str, Any], ...]) -> None:
    """Each option set on a new simulation of the family, and pfvi's checked as
    its next step would check them, so that a bad value is refused when the
    setting is made, naming it, not as a failed row of the sweep."""
    import ctypes

    import rebound

    from . import _lib

    sim = rebound.Simulation()
    try:
        configure_integrator(sim, family, **dict(options))
    except (TypeError, ValueError, AttributeError, OverflowError) as error:
        raise ValueError(f"options: {error}") from None
    if family == "pfvi" and _lib.pfvi_options_check(ctypes.addressof(sim)) == 0:
        try:
            sim.process_messages()
        except RuntimeError as error:
            raise ValueError(f"options: {error}") from None


@dataclass(frozen=True)
class Setting:
    """One run of a sweep: `family` with `options`, at knob value `value`."""

    family: str
    value: float
    #: (name, value) pairs, e.g. (("stages", 6),); an option not named is the
    #: integrator's default (pfvi's: :data:`rebound_pfvi.DEFAULTS`; the seed's
    #: fittings "phase" and "phase-literal" bring the seed's frequency and centre).
    options: Tuple[Tuple[str, Any], ...] = ()
    line: str = field(default="", compare=False)  # plot line and table group

    def __post_init__(self) -> None:
        if self.family not in FAMILIES:
            raise ValueError(f"family={self.family!r} is not an integrator family; allowed: {', '.join(FAMILIES)}")
        # (a hostile trial: True was taken as epsilon 1, numpy's float32 refused,
        # a dict of options failed to unpack naming nothing, a statistic taken for an option)
        value = self.value
        if isinstance(value, bool) or not isinstance(value, numbers.Real) or not (value > 0 and math.isfinite(value)):
            raise ValueError(f"{KNOBS[self.family]}={self.value!r} for {self.family} must be a positive number")
        object.__setattr__(self, "value", float(value) if not isinstance(value, int) else value)
        options = self.options
        if isinstance(options, dict):
            options = tuple(options.items())
        try:
            options = tuple((name, option) for name, option in options)
        except (TypeError, ValueError):
            raise ValueError(f"options={self.options!r}: give (name, value) pairs, e.g. (('stages', 6),), "
                             f"or a dict") from None
        object.__setattr__(self, "options", options)
        fields = family_fields(self.family)
        for name, _ in self.options:
            if self.family == "pfvi" and name in _pfvi_statistics():
                raise ValueError(f"options: {name} is a statistic pfvi counts (read-only), not an option")
            if name in KNOB_FIELDS.get(self.family, ()):
                raise ValueError(f"options: {name} is {self.family}'s accuracy knob, the setting's value; "
                                 f"not an option here")
            if name not in fields:
                raise ValueError(f"options: {name!r} is not an option of {self.family}; it has: "
                                 f"{', '.join(sorted(fields))}")
        _check_option_values(self.family, self.options)
        if not self.line:
            if self.family == "pfvi":
                label = pfvi_label(dict(self.options))
            else:
                label = FAMILY_NAMES[self.family]
                if self.options:
                    label += " " + " ".join(f"{k}={v}" for k, v in self.options)
            object.__setattr__(self, "line", label)

    @property
    def knob(self) -> str:
        return KNOBS[self.family]


#: Default sweeps. "quick" is what `rebound-pfvi compare` runs without --full.
PFVI_EPSILONS = {"quick": (1e-4, 1e-6, 1e-8, 1e-10), "full": tuple(10.0 ** -k for k in range(4, 12))}
#: The symmetric control's epsilon (the error per orbit) reaches further down:
#: to 1e-14, where s = 8 reaches 1e-10 AU on the comet (docs/results.md).
PFVI_SYMMETRIC_EPSILONS = {"quick": (1e-4, 1e-6, 1e-8, 1e-10, 1e-12, 1e-14), "full": tuple(10.0 ** -k for k in range(4, 15))}
#: pfvi's lines, each the options it changes from pfvi's defaults: the
#: defaults first (s = 8, no fitting, symmetric steps), beside s = 6 (and s =
#: 4 and "exact" in the full sweep), and the seed's scheme (its fitting,
#: frequency and centre at s = 4) under the osculating-circle control, the
#: default before the symmetric one, for comparison. (s = 2 is left out:
#: second order, it needs 1e6 steps per orbit for 1e-9.)
_SEED_LINE = (("stages", 4), ("fitting", "phase"), ("step_control", "reversible"))
PFVI_LINES: Dict[str, Tuple[Tuple[Tuple[str, Any], ...], ...]] = {
    "quick": ((), (("stages", 6),), _SEED_LINE),
    "full": ((), (("stages", 6),), (("stages", 4),), (("stages", 4), ("fitting", "exact")), _SEED_LINE,
             (("stages", 4), ("step_control", "reversible")))}
#: With a given frequency (the oscillator's): the seed's scheme at s = 2 and
#: 4, and s = 4 "exact" (exact on the oscillator at its frequency).
PFVI_FIXED_LINES = ((("stages", 2), ("fitting", "phase"), ("step_control", "reversible")),
                    (("stages", 4), ("fitting", "phase"), ("step_control", "reversible")),
                    (("stages", 4), ("fitting", "exact")))
IAS15_EPSILONS = {"quick": (1e-3, 1e-5, 1e-7, 1e-9), "full": tuple(10.0 ** -k for k in range(2, 10))}
BS_EPS = {"quick": (1e-4, 1e-7, 1e-10, 1e-13), "full": tuple(10.0 ** -k for k in range(4, 14))}
FIXED_STEPS = {"quick": (100, 1000, 10000), "full": (30, 100, 300, 1000, 3000, 10000, 30000)}


def default_settings(scene: Scene, size: str = "quick",
                     families: Optional[Sequence[str]] = None) -> List[Setting]:
    """The sweep for `scene`: pfvi stages x fitting x epsilon (and the scene's
    frequency options), IAS15 epsilon, BS tolerance, WHFast (plain and with
    corrector 11), LEAPFROG, TRACE and MERCURIUS steps per period; or the
    scene's own (``scene.sweep``, the solar system's). `families` restricts it."""
    if size not in ("quick", "full"):
        raise ValueError(f"size={size!r} is not valid; allowed: quick, full")
    families = tuple(scene.families if not families else
                     checks.names(families, FAMILIES, "families", "an integrator family"))
    settings = []
    for family in families:
        if family not in scene.families:
            continue
        if scene.sweep is not None:  # the scene's own sweep (its size fixed: it fits the scene's budget)
            settings += [Setting(family, value, tuple(options))
                         for options, values in scene.sweep.get(family, ()) for value in values]
        elif family == "pfvi":
            for frequency in scene.pfvi_frequencies:
                lines = PFVI_LINES[size] if frequency is None else PFVI_FIXED_LINES
                for line in lines:
                    options = line + ((("frequency", frequency),) if frequency is not None else ())
                    control = pfvi_options(dict(options)).get("step_control", DEFAULTS["step_control"])
                    epsilons = PFVI_SYMMETRIC_EPSILONS if control == "symmetric" else PFVI_EPSILONS
                    for epsilon in epsilons[size]:
                        settings.append(Setting("pfvi", epsilon, options))
        elif family == "ias15":
            settings += [Setting("ias15", x) for x in IAS15_EPSILONS[size]]
        elif family == "bs":
            settings += [Setting("bs", x) for x in BS_EPS[size]]
        elif family == "whfast":
            # plain, and with its symplectic corrector of order 11 (same steps, a little more per output)
            settings += [Setting("whfast", n) for n in FIXED_STEPS[size]]
            settings += [Setting("whfast", n, WHFAST_CORRECTED) for n in FIXED_STEPS[size]]
        else:
            settings += [Setting(family, n) for n in FIXED_STEPS[size]]
    return settings


def configure(sim: rebound.Simulation, scene: Scene, setting: Setting) -> None:
    """Sets the integrator of `sim` as `setting` asks."""
    if setting.family == "pfvi":
        # dt: the cap on the first step (adaptive steps need none). Options
        # not named stay pfvi's defaults; the seed's fittings bring the
        # seed's frequency and centre; the scene sets a frequency it knows
        # (the oscillator's omega for "fixed").
        opts = pfvi_options(dict(setting.options))
        frequency = opts.pop("frequency", None)
        configure_integrator(sim, "pfvi", dt=scene.period / 10.0, epsilon=setting.value, **opts)
        if frequency is not None:
            scene.configure_pfvi(sim, frequency)
    elif setting.family == "ias15":  # dt: the first trial step
        configure_integrator(sim, "ias15", dt=scene.period / 100.0, epsilon=setting.value, **dict(setting.options))
    elif setting.family == "bs":
        configure_integrator(sim, "bs", dt=scene.period / 100.0, eps=setting.value, **dict(setting.options))
    else:
        configure_integrator(sim, setting.family, dt=scene.period / setting.value, **dict(setting.options))


def _install_counter(sim: rebound.Simulation, scene: Scene, counter: List[int]) -> None:
    if not scene.counts_own_forces:
        def count(simp: Any) -> None:
            counter[0] += 1

        sim.additional_forces = count


def run_setting(scene: Scene, setting: Setting, reference: Dict[str, Any], repeats: int = 3,
                samples: int = 100, budget: Optional[float] = None) -> Run:
    """The run of `setting` on `scene` (see the module docstring).

    budget: seconds of wall time for the whole setting (its timed repeats and
    the sampled rerun); a run still integrating then is stopped from a timer
    thread (``sim.stop()``, after the step under way) and gets the verdict
    "over budget". None: no limit.

    Warnings raised during the runs (IAS15's "predictor corrector loops did
    not converge" at loose tolerances) are kept in the run's ``warnings``, not
    printed from the worker process."""
    import warnings

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        run = _run_setting(scene, setting, reference, repeats, samples, budget)
    run.warnings = sorted({str(w.message) for w in caught})
    return run


def _identity(scene: Scene, setting: Setting) -> Run:
    """A run of `setting` on `scene` before it has run."""
    return Run(runs.COMPARE, scene.name, setting.family, setting.line, options=dict(setting.options),
               knob=setting.knob, value=setting.value)


class _OverBudget(Exception):
    """A run stopped by its budget: how far it got, as a fraction of the run."""


def _integrate(sim: rebound.Simulation, t: float, exact_finish_time: int, deadline: Optional[float],
               progress: Callable[[], float]) -> None:
    """sim.integrate(t), stopped at the deadline (time.perf_counter()) if there is one."""
    if deadline is None:
        sim.integrate(t, exact_finish_time=exact_finish_time)
        return
    import threading

    remaining = deadline - time.perf_counter()
    if remaining <= 0.0:
        raise _OverBudget(progress())
    stopped = threading.Event()

    def stop() -> None:
        stopped.set()
        sim.stop()

    # REBOUND releases the GIL while it integrates, so the timer can stop it mid-run.
    timer = threading.Timer(remaining, stop)
    timer.start()
    try:
        sim.integrate(t, exact_finish_time=exact_finish_time)
    finally:
        timer.cancel()
    if stopped.is_set():
        raise _OverBudget(progress())


def _positions(sim: rebound.Simulation) -> List[Tuple[float, float, float]]:
    """Every particle's position, as a run with outputs reads them."""
    return [(p.x, p.y, p.z) for p in sim.particles]


def _run_setting(scene: Scene, setting: Setting, reference: Dict[str, Any], repeats: int, samples: int,
                 budget: Optional[float] = None) -> Run:
    run = _identity(scene, setting)
    run.status = "ok"
    t_end = scene.t_end
    deadline = None if budget is None else time.perf_counter() + budget
    t0 = 0.0

    def fraction() -> float:
        return (sim.t - t0) / (t_end - t0)

    try:
        sim = scene.build()
        t0 = sim.t
        walls = []
        outputs = scene.output_times()
        for _ in range(max(1, int(repeats))):
            sim = scene.build()
            configure(sim, scene, setting)
            E0 = scene.energy(sim)
            states = []
            tick = time.perf_counter()
            if outputs is None:
                _integrate(sim, t_end, 1, deadline, fraction)
            else:  # as a user takes outputs: to each time exactly, reading the positions there
                for t_out in outputs:
                    _integrate(sim, t_out, 1, deadline, fraction)
                    states.append(_positions(sim))
            walls.append(time.perf_counter() - tick)
        if outputs is not None:
            run.bodies = scene.output_errors(states, reference)
        final = abs(scene.energy(sim) / E0 - 1.0)
        position = scene.position_error(sim, reference)
        relative = scene.relative_position_error(sim, reference)
        run.wall_s, run.walls_s, run.steps, run.t = min(walls), walls, int(sim.steps_done), float(sim.t)
        run.energy_error_final, run.position_error, run.relative_position_error = final, position, relative
        if setting.family == "pfvi":
            run.pfvi = runs.pfvi_counts(sim)
        # Untimed: sampled energy error and counted force evaluations.
        counter = [0]
        sim = scene.build(counter=counter)
        _install_counter(sim, scene, counter)
        configure(sim, scene, setting)
        worst = 0.0
        # A scene whose energy holds only within the run is sampled at the
        # sampling times exactly (BS with exact_finish_time = 0 was seen to stop
        # far beyond t_end, and before t0, where a body has wrapped).
        exact = 1 if scene.energy_until_t_end else 0
        direction = 1.0 if t_end >= t0 else -1.0
        for k in range(1, samples):
            t_k = t0 + (t_end - t0) * k / samples
            # A time the run's last step passed is not gone back to: REBOUND's
            # integrate() with exact_finish_time = 0 steps backwards to it (up
            # to 42 of 99 samples of a run on the comet and sungrazer pages
            # did, counting their force evaluations: a hostile trial).
            if exact or (t_k - sim.t) * direction > 0.0:
                _integrate(sim, t_k, exact, deadline, fraction)
            worst = max(worst, abs(scene.energy(sim) / E0 - 1.0))
            if not math.isfinite(worst):
                break
        else:
            if exact or (t_end - sim.t) * direction > 0.0:
                _integrate(sim, t_end, 1, deadline, fraction)
        worst = max(worst, abs(scene.energy(sim) / E0 - 1.0))
        run.energy_error_max, run.force_evaluations = worst, counter[0]
        if not all(math.isfinite(v) for v in (final, position, worst)):
            run.status = "diverged (non-finite energy or position)"
    except _OverBudget as stopped:
        run.status = f"over budget: stopped by the budget of {budget:g} s at {stopped.args[0]:.3g} of a run"
    except Exception as error:  # noqa: BLE001 - a refused or failed run is a result, recorded with its message
        run.status = f"failed: {type(error).__name__}: {error}"
    run.verdict, run.verdict_detail = judge(scene, run)
    return run


def judge(scene: Scene, run: Run) -> Tuple[str, str]:
    """(verdict, detail) of a run (:func:`rebound_pfvi.runs.judge`), against
    the scene's ``tolerance`` if it has one, else the default."""
    return runs.judge(run, getattr(scene, "tolerance", verdict.DEFAULT))


class NoRunFinished(RuntimeWarning):
    """Issued by :func:`run` when no run of the sweep got to its end with finite errors."""


@dataclass
class Results:
    """The runs of a sweep and what is needed to read them."""

    scene: Scene
    settings: List[Setting]
    rows: List[Run]
    reference: Dict[str, Any]
    repeats: int
    samples: int
    workers: int
    scheduler: str
    wall_s: float
    interrupted: bool = False
    budget: Optional[float] = None  # seconds per setting, None: no limit

    @property
    def finished(self) -> int:
        return len(self.rows)

    @property
    def failure(self) -> str:
        """"" when some run got to its end with finite errors (what the
        tables, the plot and the conclusions read); else one line saying that
        no run did, with what became of them: "no run finished with finite
        errors (30 crashed, 4 refused)"."""
        if not self.rows or any(r.status == "ok" for r in self.rows):
            return ""
        what: Dict[str, int] = {}
        for r in self.rows:
            word = "diverged" if r.status.startswith("diverged") else r.verdict or r.status.split(":")[0]
            what[word] = what.get(word, 0) + 1
        return f"no run finished with finite errors ({', '.join(f'{n} {w}' for w, n in what.items())})"

    def verdict_counts(self) -> Dict[str, Dict[str, int]]:
        """{line: {verdict: runs}} (a line is an integrator with its options, e.g. "pfvi s=4 phase")."""
        return runs.count(self.rows)

    def to_dict(self) -> Dict[str, Any]:
        """Everything the sweep found, as JSON-ready data (the page's .json)."""
        from .units import REBOUND_UNITS

        unit_names = getattr(self.scene, "unit_names", REBOUND_UNITS)  # a custom simulation's: its own
        if unit_names is None:
            unit_names = ("the simulation's own",) * 3
        return {"scene": self.scene.name, "params": self.scene.params, "description": self.scene.describe(),
                "t_end": self.scene.t_end, "period": self.scene.period,
                "units": {"length": unit_names[0], "time": unit_names[1], "mass": unit_names[2],
                          "wall_s": "s"},
                "reference": {k: v for k, v in self.reference.items() if k in ("how", "uncertainty")},
                "repeats": self.repeats, "samples": self.samples, "workers": self.workers,
                "scheduler": self.scheduler, "budget_s": self.budget, "settings": len(self.settings),
                "finished": self.finished,
                "interrupted": self.interrupted, "sweep_wall_s": self.wall_s,
                "rows": [r.to_dict() for r in self.rows]}

    def table(self) -> Any:
        """The rows as an astropy QTable, with Quantities: position error in AU
        and km, wall time in s, the knob's step in yr for fixed-step runs."""
        import astropy.units as u
        from astropy.table import QTable

        ok = [r for r in self.rows if r.status == "ok"]
        t = QTable()
        t["line"] = [r.label for r in ok]
        t["knob"] = [r.knob for r in ok]
        t["value"] = [r.value for r in ok]
        t["steps"] = [r.steps for r in ok]
        t["force_evaluations"] = [r.force_evaluations for r in ok]
        t["wall_time"] = [r.wall_s for r in ok] << u.s
        t["energy_error_max"] = [r.energy_error_max for r in ok]
        t["energy_error_final"] = [r.energy_error_final for r in ok]
        errors = [r.position_error for r in ok]
        in_au = getattr(self.scene, "length_in_au", 1.0)  # a custom simulation's: its length unit's
        if in_au is None:  # a custom simulation without sim.units: its own units
            t["position_error"] = errors
        else:
            t["position_error"] = (errors << u.AU) * in_au
            t["position_error_km"] = t["position_error"].to(u.km)
        return t


def run(scene: Scene, settings: Optional[Sequence[Setting]] = None, repeats: int = 3, samples: int = 100,
        workers: Optional[int] = None, scheduler: Any = None,
        progress: Optional[ProgressCallback] = None, budget: Any = None) -> Results:
    """Runs a sweep; returns :class:`Results` (runs in the order of `settings`).

    workers: processes of the local pool (default: the machine's cores; 1 runs
    here). scheduler: the address of a Dask distributed scheduler, or a
    ``distributed.Client``. progress(done, total, run) is called after each run.
    budget: wall time per setting, in seconds or as a time Quantity (``5 *
    u.s``; see :func:`run_setting`; None: no limit); in the local pool a run still busy
    :data:`rebound_pfvi.runner.GRACE_SECONDS` after its budget is killed
    ("over budget"), and a run whose process dies is "crashed".
    Ctrl-C stops the sweep and returns the finished runs with
    ``interrupted=True``.

    A sweep in which no run got to its end with finite errors (all refused,
    crashed, over budget or diverged: e.g. an oscillator with omega = 1e300
    /yr) is still returned, so that :func:`rebound_pfvi.report.write` can
    write every run's verdict; its ``failure`` says so in one line (it is ""
    otherwise), and a :class:`NoRunFinished` warning with the same words is
    issued (``warnings.simplefilter("error", NoRunFinished)`` makes it an
    exception). The command line writes the page and exits with status 1.
    """
    given = settings is not None
    settings = list(settings) if settings is not None else list(default_settings(scene))
    if not settings:
        raise ValueError("settings: the sweep is empty (an empty list was given)" if given
                         else "settings: the sweep is empty (no integrator family applies to this scene)")
    # The command line's checks (rebound_pfvi.checks), with the arguments' names.
    repeats, samples = checks.positive_int(repeats, "repeats"), checks.positive_int(samples, "samples")
    workers = None if workers is None else checks.positive_int(workers, "workers")
    budget = None if budget is None else checks.seconds(budget, "budget")
    reference = scene.reference()
    # The hard limit: a run still busy GRACE_SECONDS after its budget is killed (in a worker process;
    # nothing can kill a run in this one).
    limit = None if budget is None else budget + runner.GRACE_SECONDS
    tasks = [runner.Task(run_setting, (scene, s, reference, repeats, samples, budget), limit)
             for s in settings]
    done: Dict[int, Run] = {}
    interrupted = False
    tick = time.perf_counter()

    def record(index: int, outcome: runner.Outcome) -> None:
        run = runs.from_outcome(_identity(scene, settings[index]), outcome)
        if not run.verdict:  # its process did not return it
            run.verdict, run.verdict_detail = judge(scene, run)
        done[index] = run
        if progress:
            progress(len(done), len(tasks), run)

    if scheduler is None:
        workers = int(workers or os.cpu_count() or 1)
        where = "local pool" if workers > 1 else "this process"
    else:
        workers, where = 0, "dask"  # known once connected
    try:
        if scheduler is not None:
            _, workers, where = runner.run_tasks_dask(tasks, scheduler, record)
        else:
            runner.run_tasks(tasks, workers, processes=workers > 1, done=record)
    except runner.WorkerStartError as error:
        raise RuntimeError("workers: a worker process died before returning its run (a script that calls "
                           "compare.run() needs an `if __name__ == '__main__':` guard, since workers import "
                           "it; workers=1 runs in this process)") from error
    except KeyboardInterrupt:
        interrupted = True
    rows = [done[i] for i in sorted(done)]
    results = Results(scene, settings, rows, reference, repeats, samples, workers, where,
                      time.perf_counter() - tick, interrupted, budget)
    if results.failure:
        import warnings

        warnings.warn(f"{scene.name}: {results.failure}; each run's verdict is in results.rows",
                      NoRunFinished, stacklevel=2)
    return results
