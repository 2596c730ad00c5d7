"""Command line: ``rebound-pfvi`` or ``python -m rebound_pfvi``.

Commands: ``demo`` (default), ``compare`` (error against run time on a
scene), ``stability`` (stiff and extreme cases), ``paper fig1|fig2|fig3``
(the seed's figures). Heavy imports
(astropy, matplotlib, dask) happen only in the command that needs them.
"""
import argparse
import math
import os
import shlex
import sys
import threading
import time
import warnings
from typing import TYPE_CHECKING, Any, Dict, List, Optional, Sequence, TextIO

from . import checks, units
from . import scenes as scenes_module

if TYPE_CHECKING:
    from .runs import Run

# Scene parameters: option -> (scene keyword, kind of quantity, scenes that take it, help).
SCENE_OPTIONS = {
    "--e": ("e", "number", ("kepler", "comet", "triple", "sungrazer"),
            "eccentricity (triple: of the inner binary; sungrazer: of the comet)"),
    "--periods": ("periods", "number", ("kepler", "comet", "triple", "oscillator", "mercury-gr", "jupiter-comet",
                                        "retrograde", "sungrazer", "circumbinary", "outer-solar-system", "periodic-box"),
                  "length of the run in periods (comet, jupiter-comet, sungrazer: of the comet; triple: of the "
                  "outer orbit; retrograde: of the crosser; circumbinary: of the planet; outer-solar-system: of "
                  "the Pluto-like body; periodic-box: of 1.5 yr)"),
    "--a": ("a", "length", ("kepler", "comet"), 'semi-major axis, e.g. "1 AU" or "1.5e8 km"'),
    "--mass": ("mass", "mass", ("kepler",), 'central mass, e.g. "1 Msun"'),
    "--m": ("m", "mass", ("kepler",), 'orbiter mass, e.g. "1 Mjup" or "0 kg"'),
    "--a-inner": ("a_inner", "length", ("triple",), "inner binary's semi-major axis"),
    "--a-outer": ("a_outer", "length", ("triple",), "companion's semi-major axis"),
    "--omega": ("omega", "frequency", ("oscillator",), 'angular frequency, e.g. "6.283 1/yr"'),
    "--amplitude": ("amplitude", "length", ("oscillator",), "semi-major axis of the oscillator's ellipse"),
    "--epoch": ("epoch", "epoch", ("solar-system",),
                'start: an ISO date (TDB), e.g. "1900-01-01", or a Julian date (TDB); default J2000'),
    "--years": ("years", "number or time", ("solar-system",),
                'length of the run: Julian years, or a time such as "0.5 yr" (default 10)'),
    "--every": ("every", "number or time", ("solar-system",),
                'time between outputs: days, or a time such as "12 h" (default 10)'),
    "--no-gr": ("gr", "off", ("solar-system",), "leave out GR (default: REBOUNDx's gr_full where it is installed)"),
}


def _argument(check: Any, kind: str) -> Any:
    """An argparse type from a check that the Python API makes too
    (:mod:`rebound_pfvi.checks`, :mod:`rebound_pfvi.units`): the same rule,
    its error without the Python argument's name (argparse names the option)."""
    def parse(text: str) -> Any:
        try:
            return check(text, "value")
        except ValueError as error:
            raise argparse.ArgumentTypeError(str(error).replace("value: ", "").replace("value=", "")) from None
    parse.__name__ = kind
    return parse


def _quantity(kind: str) -> Any:
    from .units import parse

    return _argument(lambda text, name: parse(text, kind, name), kind)


_number = _argument(units.plain_number, "number")


def _number_or_time(text: str, name: str) -> Any:
    """A plain number (in the option's own unit), or else a time with its unit."""
    try:
        float(text)
    except ValueError:
        return units.parse(text, "time", name)
    return units.plain_number(text, name)
_positive_int = _argument(checks.positive_int, "integer")
_positive_float = _argument(checks.positive_number, "number")


def _names(allowed: Any, what: str, lower: bool = False) -> Any:
    """An argparse type for a comma-separated list of names: checks.names's rule (each allowed, each once)."""
    def check(text: str, name: str) -> List[str]:
        given = [n.strip().lower() if lower else n.strip() for n in text.split(",") if n.strip()]
        try:
            return checks.names(given, allowed(), name, what)
        except ValueError as error:
            raise ValueError(f"{error} (comma-separated)") from None
    return _argument(check, "names")


def _compare_families() -> Any:
    from .compare import FAMILIES

    return FAMILIES


def _stability_cases() -> Any:
    from .stability import cases

    return cases()


def _stability_integrators() -> Any:
    from .stability import FAMILIES

    return FAMILIES


_families = _names(_compare_families, "an integrator family", lower=True)
_case_names = _names(_stability_cases, "a case")
_stability_families = _names(_stability_integrators, "an integrator", lower=True)


def version_text() -> str:
    """The package's version, the running rebound's, and the one the C core was compiled against."""
    import rebound

    import rebound_pfvi
    from rebound_pfvi._core import lib

    compiled = lib.pfvi_rebound_version_compiled().decode()
    return (f"rebound-pfvi {rebound_pfvi.__version__} (rebound {rebound.__version__}; C core compiled against "
            f"rebound {compiled})")


class _Version(argparse.Action):
    """--version, computed when asked for: importing rebound_pfvi loads the C core."""

    def __init__(self, option_strings: List[str], dest: str = argparse.SUPPRESS, **kwargs: Any) -> None:
        super().__init__(option_strings, dest, nargs=0, default=argparse.SUPPRESS, **kwargs)

    def __call__(self, parser: argparse.ArgumentParser, namespace: argparse.Namespace, values: Any,
                 option_string: Optional[str] = None) -> None:
        print(version_text())
        parser.exit()


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="rebound-pfvi",
                                     description="Phase-fitted discrete Lagrangian integrator for REBOUND.")
    parser.add_argument("--version", action=_Version, help="print the versions of rebound-pfvi and rebound, and exit")
    commands = parser.add_subparsers(dest="command")
    demo = commands.add_parser("demo", help="circular and e = 0.95 orbits with pfvi, IAS15 and WHFast (default)")
    demo.add_argument("--orbits", type=_positive_int, default=100, help="orbits to integrate (default 100)")

    compare = commands.add_parser(
        "compare", help="error against run time: pfvi, IAS15, WHFast, LEAPFROG, BS, TRACE, MERCURIUS on a scene",
        description="Sweeps every integrator's accuracy knob on a scene and writes <name>.md (who is fastest "
                    "at each accuracy and why, a verdict on every run, the tables), .json, .csv and .png "
                    "(work-precision diagram) to --output; <name> is the scene's, with its e where it has "
                    "one (comet-e0.95, kepler-e0.99, outer-solar-system).")
    compare.add_argument("--scene", default="comet", choices=tuple(scenes_module.SCENES),
                         help="default comet (Sun, Jupiter and an e = 0.95 comet, 3 comet periods: no "
                              "integrator is exact on it); kepler: two bodies, e = 0.95, 100 periods; "
                              "triple: a hierarchical stellar triple; oscillator: a 2-D harmonic oscillator "
                              "(no gravity); mercury-gr: Mercury with REBOUNDx's \"gr\" (the [reboundx] extra); "
                              "the step control's hard cases (docs/step-control.md): jupiter-comet (a comet "
                              "passing Jupiter at 0.34 AU), retrograde (a body crossing Jupiter's orbit), "
                              "sungrazer (q = 0.02 AU beside Jupiter), circumbinary (a Kepler-16-like planet), "
                              "outer-solar-system (the giant planets and a Pluto-like body), periodic-box "
                              "(softened bodies meeting through a periodic boundary); solar-system: the Sun, "
                              "planets, Moon and Pluto from JPL's DE421, 10 yr with an output every 10 days, "
                              "measured against DE421 (the [ephemeris] extra). The parameters each takes "
                              "are in brackets below")
    for option, (_, kind, scenes, text) in SCENE_OPTIONS.items():
        if kind == "off":  # a switch: the scene's keyword set to False
            compare.add_argument(option, action="store_const", const=False, default=None,
                                 help=f"{text} [{', '.join(scenes)}]")
            continue
        parse = (_number if kind == "number" else str if kind == "epoch"
                 else _argument(_number_or_time, "number or time") if kind == "number or time" else _quantity(kind))
        compare.add_argument(option, type=parse, default=None, help=f"{text} [{', '.join(scenes)}]")
    compare.add_argument("--integrators", type=_families, default=None,
                         help="comma-separated families to run (default: all that apply to the scene)")
    compare.add_argument("--full", action="store_true", help="the full sweep (more settings, s = 6 too)")
    compare.add_argument("--repeats", type=_positive_int, default=3, help="timed repeats, best kept (default 3)")
    compare.add_argument("--samples", type=_positive_int, default=100,
                         help="times at which the energy error is sampled (default 100)")
    compare.add_argument("--budget", type=_positive_float, default=None, metavar="SECONDS",
                         help="wall time per setting (its repeats and the sampled rerun); a run still going then "
                              "is stopped with the verdict 'over budget' (default: no limit)")
    compare.add_argument("--workers", type=_positive_int, default=None,
                         help="processes of the local pool (default: the number of cores; 1: no pool)")
    compare.add_argument("--scheduler", default=None, metavar="ADDRESS",
                         help="send the runs to this Dask distributed scheduler (needs the [dask] extra)")
    compare.add_argument("--output", default="rebound-pfvi-results",
                         help="folder for the results (default: %(default)s, in the current folder)")

    stability = commands.add_parser(
        "stability", help="stiff and extreme cases: pfvi (its defaults, then the seed's fittings and 'none' at "
                     "s = 2 and 4) beside IAS15 and WHFast",
        description="Runs each extreme case (e up to 0.9999, flybys, radial infall, Burrau's problem, a "
                    "close encounter, mass ratios, fixed steps beyond u_max, 1e5 periods, a stiff triple) "
                    "with every integrator, each in its own process with a wall-time budget, and writes "
                    "stability.md and stability.json to --output, with a verdict on every run (accurate, "
                    "inaccurate, refused, crashed, over budget).")
    stability.add_argument("--cases", type=_case_names, default=None,
                           help="comma-separated case names (default: all; --list shows them)")
    stability.add_argument("--list", action="store_true", help="list the cases and exit")
    stability.add_argument("--integrators", type=_stability_families, default=("pfvi", "ias15", "whfast"),
                           help="comma-separated, from pfvi, ias15, whfast (default: all three)")
    stability.add_argument("--epsilon", type=_positive_float, default=1e-6,
                           help="pfvi's tolerance on adaptive cases (default 1e-6, pfvi's default)")
    stability.add_argument("--budget", type=_positive_float, default=60.0,
                           help="seconds of integration per run before it is stopped (default 60)")
    stability.add_argument("--workers", type=_positive_int, default=2, help="runs at once (default 2)")
    stability.add_argument("--output", default="rebound-pfvi-stability",
                           help="folder for the report (default: %(default)s, in the current folder)")

    paper = commands.add_parser("paper", help="rerun a figure of the seed paper")
    # Errors found after parsing are reported by the subcommand's parser, with its usage.
    for sub in (demo, compare, stability, paper):
        sub.set_defaults(subparser=sub)
    paper.add_argument("figure", choices=("fig1", "fig2", "fig3"),
                       help="fig1: steps against energy error, phase vs none; fig2: energy and position error "
                            "over 1e5 periods at e = 0.95; fig3: the curvature frequency over 10 periods")
    # The same default as compare's and stability's: a folder in the current
    # one, never a docs/paper that happens to be below it (the project's own
    # pages are rewritten with --output docs/paper from the source tree).
    paper.add_argument("--output", default="rebound-pfvi-paper",
                       help="folder for the page, data and PNG (default: %(default)s, in the current folder; "
                            "the project's pages: --output docs/paper in the source tree)")
    paper.add_argument("--stages", type=int, default=None,
                       help="Gauss-Lobatto nodes, one of rebound_pfvi.STAGES (default: 2 for fig1, as in the seed; "
                            "4 for fig2 and fig3)")
    paper.add_argument("--step-control", default=None, choices=("seed", "reversible"),
                       help="default: seed for fig1, reversible for fig2 and fig3")
    paper.add_argument("--epsilon", type=_positive_float, default=None, help="fig2/fig3 tolerance (default 1e-6)")
    paper.add_argument("--periods", type=_positive_float, default=None,
                       help="fig2: default 1e5; fig3: default 10")
    paper.add_argument("--samples", type=_positive_int, default=None, help="fig2: sampled times (default 2000)")
    return parser


class Progress:
    """Progress on stderr: a bar with the elapsed time and the time left
    (tqdm) on a terminal; elsewhere (a log file, a pipe, CI) one line per
    finished run, or per tenth of the work when the steps are not runs.

    It shows what finished last and how many runs did not finish, never a
    run's message: the command lists those in full at the end. tqdm is
    imported here, when a long command starts, not with the package."""

    def __init__(self, total: int, unit: str = "run", stream: Optional[TextIO] = None) -> None:
        self.stream = stream or sys.stderr
        self.total, self.unit, self.done = int(total), unit, 0
        self.not_finished = 0
        self._last: Optional[str] = None  # a finished run not yet written (line mode)
        self._start = time.perf_counter()
        self.bar: Any = None
        isatty = getattr(self.stream, "isatty", None)
        if not (callable(isatty) and isatty()):
            return  # line mode
        from tqdm import tqdm

        self.bar = tqdm(total=total, unit=unit, file=self.stream, dynamic_ncols=True, mininterval=0.5,
                        smoothing=0.1, bar_format="{l_bar}{bar}| {n_fmt}/{total_fmt} [{elapsed}<{remaining}{postfix}]")
        # Redraw every second, so that the elapsed time moves while a long run is under way.
        self._stop = threading.Event()
        self._ticker = threading.Thread(target=self._tick, daemon=True)
        self._ticker.start()

    def _tick(self) -> None:
        while not self._stop.wait(1.0):
            self.bar.refresh()

    def __call__(self, done: int, total: int, run: Optional["Run"] = None) -> None:
        """compare's, stability's and paper's callback: `done` of `total` finished, `run` the last one."""
        if run is not None:
            # The verdict, or the status's first word ("refused"): never the message.
            self.finished_one(f"{run.name}: {run.verdict or run.status.split(':')[0]}", not run.finished)
        self.advance(done - self.done)
        if done >= total:
            self.close()

    def finished_one(self, what: str, failed: bool) -> None:
        """Names the run that finished last; counts it if it did not finish."""
        self.not_finished += bool(failed)
        if self.bar is None:
            self._last = what
            return
        postfix = f"last: {what}"
        if self.not_finished:
            postfix += f"; not finished: {self.not_finished} (listed at the end)"
        self.bar.set_postfix_str(postfix, refresh=False)

    def advance(self, n: int = 1) -> None:
        """`n` more of the total are done."""
        before, self.done = self.done, self.done + n
        if self.bar is not None:
            self.bar.update(n)
            return
        tenth = max(1, self.total // 10)
        if self._last is None and self.done < self.total and self.done // tenth == before // tenth:
            return
        line = f"[{self.done}/{self.total} {self.unit}s, {time.perf_counter() - self._start:.1f} s]"
        if self._last is not None:
            line += f" {self._last}"
            self._last = None
        print(line, file=self.stream, flush=True)

    def close(self) -> None:
        if self.bar is None:
            return
        self._stop.set()
        self._ticker.join()  # no redraw after the bar is closed
        self.bar.close()


def invocation(argv: List[str]) -> str:
    """The command as it was run, for the pages it writes: the installed
    ``rebound-pfvi`` script or ``python3 -P -m rebound_pfvi``, and the arguments."""
    program = "rebound-pfvi" if os.path.basename(sys.argv[0]) == "rebound-pfvi" else "python3 -P -m rebound_pfvi"
    return " ".join([program] + [shlex.quote(a) for a in argv])


def check_output(parser: argparse.ArgumentParser, folder: str, names: Sequence[str] = (),
                 option: str = "--output") -> None:
    """Creates `folder` and checks that the files `names` can be written in
    it (an existing one is opened for appending, which changes nothing; a
    new one is made and removed), before any run starts: a folder that
    cannot be written is an error now, not a traceback after the sweep, when
    its results would be lost. Folders it made are removed again if the
    check fails."""
    import shutil
    import tempfile

    if not folder:
        parser.error(f"argument {option}: the folder's name is empty")
    # The outermost folder this check creates, so that a failed check leaves nothing behind.
    first_new = None
    path = os.path.abspath(folder)
    while not os.path.lexists(path):
        first_new, path = path, os.path.dirname(path)
    try:
        if os.path.lexists(folder) and not os.path.isdir(folder):
            raise NotADirectoryError("it exists and is not a folder")
        os.makedirs(folder, exist_ok=True)
        with tempfile.TemporaryFile(dir=folder):
            pass
        for name in names:
            target = os.path.join(folder, name)
            if os.path.lexists(target) and not os.path.isfile(target):
                raise IsADirectoryError(f"{target!r} exists and is not a file")
            existed = os.path.exists(target)
            with open(target, "a"):
                pass
            if not existed:
                os.remove(target)
    except OSError as error:
        if first_new is not None:
            shutil.rmtree(first_new, ignore_errors=True)
        reason = error.strerror if error.strerror else str(error)
        if error.filename and error.filename != folder and error.strerror:
            reason += f" ({error.filename})"
        parser.error(f"argument {option}: cannot write to the folder {folder!r}: {reason}")


def _write_elsewhere(write: Any, output: str, error: OSError) -> Any:
    """The results into a new temporary folder, when writing them to
    `output` failed after the runs (the disk filled, a file was replaced
    meanwhile): they are not lost, and the command says where they went."""
    import tempfile

    folder = tempfile.mkdtemp(prefix="rebound-pfvi-")
    print(f"error: could not write the results to {output!r} ({error.strerror or error}); "
          f"writing them to {folder} instead", file=sys.stderr)
    return write(folder)


def _scene_from_args(parser: argparse.ArgumentParser, args: argparse.Namespace) -> Any:
    from . import scenes

    params = {}
    for option, (keyword, _, applies, _) in SCENE_OPTIONS.items():
        value = getattr(args, option[2:].replace("-", "_"))
        if value is None:
            continue
        if args.scene not in applies:
            parser.error(f"argument {option}: not a parameter of scene {args.scene!r} "
                         f"(it applies to: {', '.join(applies)})")
        params[keyword] = value
    try:
        scene = scenes.make(args.scene, **params)
    except ValueError as error:
        # The scene names its keyword ("m=-1 Mjup is negative"); the user wrote an option.
        for option, (keyword, _, _, _) in SCENE_OPTIONS.items():
            if str(error).startswith(f"{keyword}="):
                parser.error(f"argument {option}: {error}")
        parser.error(f"scene {args.scene}: {error}")
    # Values each fine alone can still make a scene no integrator can run
    # (a = 1e300 pc: a period that overflows; a = 1e-320 AU: bodies at one point).
    try:
        duration = scene.t_end
        if not (math.isfinite(duration) and duration > 0.0):
            raise ValueError(f"its run would last {duration!r} yr")
        scene.build()
    except (ArithmeticError, ValueError, RuntimeError) as error:
        # (an OverflowError from math carries an errno tuple: its text is the words)
        reason = (f"a value overflows ({error.args[1]})" if isinstance(error, OverflowError) and len(error.args) == 2
                  else error)
        parser.error(f"scene {args.scene}: these parameters give no scene to integrate: {reason}")
    return scene


#: Seconds to wait for a Dask scheduler before --scheduler is an error.
CONNECT_TIMEOUT_S = 10.0


def _connect(parser: argparse.ArgumentParser, address: str) -> Any:
    """A ``distributed.Client`` on `address`, or a one-line error: the
    [dask] extra missing, or no scheduler answering there."""
    try:
        from distributed import Client
    except ImportError:
        parser.error("argument --scheduler: sending runs to Dask needs the [dask] extra: "
                     "pip install \"rebound_pfvi[dask]\" (from a clone: pip install \".[dask]\")")
    outcome: Dict[str, Any] = {}

    def connect() -> None:
        try:
            outcome["client"] = Client(address, timeout=CONNECT_TIMEOUT_S)
        except BaseException as error:  # noqa: BLE001 - whatever stops it is the answer, reported below
            outcome["error"] = error

    # Dask's own timeout does not cover a peer that accepts and never answers
    # as a scheduler would (an HTTP server): the connection gets its own deadline.
    attempt = threading.Thread(target=connect, daemon=True)
    attempt.start()
    attempt.join(CONNECT_TIMEOUT_S + 5.0)
    if "client" in outcome:
        return outcome["client"]
    error = outcome.get("error")
    if error is None:
        reason = f"no answer as a Dask scheduler within {CONNECT_TIMEOUT_S + 5.0:g} s"
    elif isinstance(error, (OSError, TimeoutError)):
        reason = str(error).splitlines()[0] if str(error) else type(error).__name__
    elif isinstance(error, (MemoryError, OverflowError)):
        reason = "the peer's answer is not Dask's protocol (is it a Dask scheduler?)"
    else:
        reason = f"not a usable Dask address ({type(error).__name__}: {str(error).splitlines()[0] if str(error) else ''})"
    parser.error(f"argument --scheduler: could not connect to a Dask scheduler at {address!r}: {reason}")


def run_compare(parser: argparse.ArgumentParser, args: argparse.Namespace, argv: List[str]) -> int:
    from . import compare, report

    scene = _scene_from_args(parser, args)
    try:
        settings = compare.default_settings(scene, "full" if args.full else "quick", args.integrators)
    except ValueError as error:
        parser.error(f"argument --integrators: {error}")
    if not settings:
        parser.error(f"argument --integrators: none of {', '.join(args.integrators)} applies to scene "
                     f"{scene.name!r} (it takes: {', '.join(scene.families)})")
    left_out = [f for f in (args.integrators or ()) if f not in scene.families]
    if left_out:
        print(f"--integrators: {', '.join(left_out)} left out: scene {scene.name!r} takes "
              f"{', '.join(scene.families)}", file=sys.stderr)
    scheduler = args.scheduler
    if scheduler is not None:
        scheduler = _connect(parser, scheduler)
    check_output(parser, args.output, [scene.slug + ext for ext in (".md", ".json", ".csv", ".png")])
    print(f"{scene.describe()}: {len(settings)} runs, best of {args.repeats}", flush=True)
    bar = Progress(len(settings))
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", compare.NoRunFinished)  # said below, as the error it is here
            results = compare.run(scene, settings, repeats=args.repeats, samples=args.samples,
                                  workers=args.workers, scheduler=scheduler, progress=bar, budget=args.budget)
    finally:
        bar.close()
        if scheduler is not None:
            scheduler.close()
    command = invocation(argv)
    failed = False
    try:
        paths = report.write(results, args.output, command=command)
    except OSError as error:
        failed = True
        paths = _write_elsewhere(lambda folder: report.write(results, folder, command=command), args.output, error)
    if results.interrupted:
        print(f"\nInterrupted: {results.finished} of {len(settings)} runs finished and kept.", file=sys.stderr)
    print(f"Wrote {', '.join(paths.values())} ({results.wall_s:.1f} s)")
    _print_verdicts(results.verdict_counts(), results.rows)
    warned = [r for r in results.rows if r.warnings]
    if warned:
        print(f"REBOUND warned in {len(warned)} run(s), explained in the page's Warnings section:")
        print(report.warnings_section(warned))
    if results.failure and not results.interrupted:  # nothing measured: the page shows why, the command fails
        print(f"error: {results.failure}; each run's verdict: {paths['md']}", file=sys.stderr)
        return 1
    print("Fastest to a position error (wall time, best of the sweep):")
    length = report.length_unit(results)
    for sentence in report.conclusions(results, results.reference.get("uncertainty", 0.0), length):
        print("- " + sentence)
    caveat = report.whfast_caveat(results)
    if caveat:
        print(caveat.replace("**", "").replace("`", ""))
    return 130 if results.interrupted else 1 if failed else 0


def _written(output: str, name: str) -> str:
    """The files a paper figure wrote (its .png only with the [plot] extra)."""
    import os

    kinds = [k for k in (".md", ".png", ".json") if os.path.exists(os.path.join(output, name + k))]
    return f"{output}/{name}" + ", ".join(kinds)


def run_paper(args: argparse.Namespace, argv: List[str]) -> int:
    from . import STAGES
    from . import paper as seed_paper

    if args.stages is not None and args.stages not in STAGES:
        args.subparser.error(f"argument --stages: {args.stages} is not one of {', '.join(map(str, STAGES))}")
    # An option the figure does not use is an error, not ignored (as
    # compare's scene parameters are).
    uses = {"fig1": (), "fig2": ("epsilon", "periods", "samples"), "fig3": ("epsilon", "periods")}[args.figure]
    for option in ("epsilon", "periods", "samples"):
        if getattr(args, option) is not None and option not in uses:
            args.subparser.error(f"argument --{option}: {args.figure} does not use it (options for {args.figure}: "
                                 f"{', '.join('--' + o for o in uses) or 'none of --epsilon, --periods, --samples'})")
    args.epsilon = 1e-6 if args.epsilon is None else args.epsilon
    args.samples = 2000 if args.samples is None else args.samples

    check_output(args.subparser, args.output, [f"figure{args.figure[-1]}{ext}" for ext in (".md", ".json", ".png")])
    if args.figure == "fig1":
        stages, control = args.stages or 2, args.step_control or "seed"
        bar = Progress(len(seed_paper.ECCENTRICITIES) * len(seed_paper.EPSILONS), unit="tolerance")

        def progress(row):
            bar.finished_one(f"e = {row['e']}, epsilon = {row['epsilon']:.0e}: phase {row['phase_steps']} steps, "
                             f"none {row['none_steps']} steps", False)
            bar.advance(1)

        command = invocation(argv)
        try:
            rows = seed_paper.figure1(args.output, stages=stages, step_control=control, progress=progress,
                                      command=command)
        except KeyboardInterrupt:
            print("\nInterrupted: nothing written.", file=sys.stderr)
            return 130
        finally:
            bar.close()
        print(f"Figure 1: {len(rows)} tolerances; wrote {_written(args.output, 'figure1')}")
        return 0
    stages, control = args.stages or 4, args.step_control or "reversible"
    if args.figure == "fig2":
        samples_bar = Progress(args.samples, unit="sample")
        periods = args.periods or 1e5
        command = invocation(argv)
        try:
            rows, wall = seed_paper.figure2(args.output, periods=periods, samples=args.samples, stages=stages,
                                            epsilon=args.epsilon, step_control=control,
                                            progress=samples_bar, command=command)
        except KeyboardInterrupt:
            print("\nInterrupted: nothing written.", file=sys.stderr)
            return 130
        finally:
            samples_bar.close()
        print(f"Figure 2: {rows[-1]['steps']} steps, run time {wall:.1f} s; wrote {_written(args.output, 'figure2')}")
        return 0
    periods = args.periods or 10
    command = invocation(argv)
    rows, wall = seed_paper.figure3(args.output, periods=periods, stages=stages, epsilon=args.epsilon,
                                    step_control=control, command=command)
    print(f"Figure 3: {len(rows)} steps, run time {wall:.1f} s; wrote {_written(args.output, 'figure3')}")
    return 0


def run_stability(args: argparse.Namespace, argv: List[str]) -> int:
    from . import report as report_module
    from . import stability

    if args.list:
        for name, case in stability.cases().items():
            print(f"{name:20s} {case.title}")
        return 0
    check_output(args.subparser, args.output, ["stability.md", "stability.json"])
    configs = stability.default_configs(args.integrators, epsilon=args.epsilon)
    names = args.cases or list(stability.cases())
    total = len(names) * len(configs)
    print(f"{len(names)} cases x {len(configs)} integrators = {total} runs, {args.workers} at once, "
          f"budget {args.budget:g} s each", flush=True)
    bar = Progress(total)
    try:
        report = stability.run_all(names, configs, budget=args.budget, workers=args.workers, progress=bar)
    except KeyboardInterrupt:
        print("\nInterrupted: nothing written.", file=sys.stderr)
        return 130
    finally:
        bar.close()
    command = invocation(argv)
    failed = False
    try:
        paths = report_module.write_stability(report, args.output, command=command)
    except OSError as error:
        failed = True
        paths = _write_elsewhere(lambda folder: report_module.write_stability(report, folder, command=command),
                                 args.output, error)
    print(f"Wrote {', '.join(map(str, paths))} ({report.wall_s:.0f} s)")
    _print_verdicts(report_module.stability_verdict_counts(report), report.rows)
    return 1 if failed else 0


def _print_verdicts(counts: Dict[str, Dict[str, int]], rows: Sequence["Run"]) -> None:
    """The verdicts counted per integrator, then every run that did not finish, with its whole message."""
    from .verdict import text_counts

    print("Verdicts (accurate: finished within the tolerance; see the report):")
    for line in text_counts(counts):
        print("  " + line)
    failed = [r for r in rows if not r.finished]
    if failed:
        print(f"{len(failed)} run(s) did not finish:")
        for r in failed:
            print(f"- {r.name}: {r.verdict}: {r.verdict_detail}")


def main(argv: Optional[List[str]] = None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    parser = build_parser()
    args = parser.parse_args(argv)
    if args.command == "compare":
        return run_compare(args.subparser, args, argv)
    if args.command == "paper":
        return run_paper(args, argv)
    if args.command == "stability":
        return run_stability(args, argv)
    from .demo import run_demo

    run_demo(getattr(args, "orbits", 100))
    return 0


if __name__ == "__main__":
    sys.exit(main())
