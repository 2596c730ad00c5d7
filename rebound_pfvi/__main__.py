"""Command line: ``rebound-pfvi`` or ``python -m rebound_pfvi``.

Commands: ``demo`` (default), ``compare`` (error against run time on a
scene), ``stability`` (stiff and extreme cases), ``paper fig1|fig2|fig3``
(the seed's figures). Heavy imports
(astropy, matplotlib, dask) happen only in the command that needs them.
"""
import argparse
import shlex
import sys
import time

# Scene parameters: option -> (scene keyword, kind of quantity, scenes that take it, help).
SCENE_OPTIONS = {
    "--e": ("e", "number", ("kepler", "comet", "triple"), "eccentricity (triple: of the inner binary)"),
    "--periods": ("periods", "number", ("kepler", "comet", "triple", "oscillator", "mercury-gr"),
                  "length of the run in periods (comet: of the comet; triple: of the outer orbit)"),
    "--a": ("a", "length", ("kepler", "comet"), 'semi-major axis, e.g. "1 AU" or "1.5e8 km"'),
    "--mass": ("mass", "mass", ("kepler",), 'central mass, e.g. "1 Msun"'),
    "--m": ("m", "mass", ("kepler",), 'orbiter mass, e.g. "1 Mjup" or "0 kg"'),
    "--a-inner": ("a_inner", "length", ("triple",), "inner binary's semi-major axis"),
    "--a-outer": ("a_outer", "length", ("triple",), "companion's semi-major axis"),
    "--omega": ("omega", "frequency", ("oscillator",), 'angular frequency, e.g. "6.283 1/yr"'),
    "--amplitude": ("amplitude", "length", ("oscillator",), "semi-major axis of the oscillator's ellipse"),
}


def _number(name):
    def parse(text):
        try:
            return float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None
    parse.__name__ = name
    return parse


def _quantity(kind):
    def parse(text):
        from .units import parse as parse_quantity, to_scene

        try:
            value = parse_quantity(text, kind, "value")
            to_scene(value, kind, "value")  # the right dimension, finite
        except ValueError as error:
            raise argparse.ArgumentTypeError(str(error).replace("value: ", "").replace("value=", "")) from None
        return value
    parse.__name__ = kind
    return parse


def _positive_int(text):
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not an integer") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"{value} must be at least 1")
    return value


def _positive_float(text):
    value = _number("number")(text)
    if not value > 0:
        raise argparse.ArgumentTypeError(f"{text!r} must be positive")
    return value


def _families(text):
    from .compare import FAMILIES

    names = [n.strip().lower() for n in text.split(",") if n.strip()]
    bad = [n for n in names if n not in FAMILIES]
    if bad or not names:
        raise argparse.ArgumentTypeError(f"{', '.join(bad) or repr(text)} not an integrator family; "
                                         f"allowed: {', '.join(FAMILIES)} (comma-separated)")
    return names


def _case_names(text):
    from .stability import cases

    names = [n.strip() for n in text.split(",") if n.strip()]
    bad = [n for n in names if n not in cases()]
    if bad or not names:
        raise argparse.ArgumentTypeError(f"{', '.join(bad) or repr(text)} not a case; allowed: "
                                         f"{', '.join(cases())} (comma-separated)")
    return names


def _stability_families(text):
    names = [n.strip().lower() for n in text.split(",") if n.strip()]
    bad = [n for n in names if n not in ("pfvi", "ias15", "whfast")]
    if bad or not names:
        raise argparse.ArgumentTypeError(f"{', '.join(bad) or repr(text)} not an integrator; allowed: "
                                         "pfvi, ias15, whfast (comma-separated)")
    return names


def build_parser():
    parser = argparse.ArgumentParser(prog="rebound-pfvi",
                                     description="Phase-fitted discrete Lagrangian integrator for REBOUND.")
    commands = parser.add_subparsers(dest="command")
    demo = commands.add_parser("demo", help="circular and e = 0.95 orbits with pfvi, IAS15 and WHFast (default)")
    demo.add_argument("--orbits", type=_positive_int, default=100, help="orbits to integrate (default 100)")

    compare = commands.add_parser(
        "compare", help="error against run time: pfvi, IAS15, WHFast, LEAPFROG, BS on a scene",
        description="Sweeps every integrator's accuracy knob on a scene and writes <scene>.md (tables), "
                    ".json, .csv and .png (work-precision diagram) to --output.")
    compare.add_argument("--scene", default="kepler", choices=("kepler", "comet", "triple", "oscillator", "mercury-gr"),
                         help="default kepler (e = 0.95, 100 periods)")
    for option, (_, kind, scenes, text) in SCENE_OPTIONS.items():
        compare.add_argument(option, type=_number(kind) if kind == "number" else _quantity(kind), default=None,
                             help=f"{text} [{', '.join(scenes)}]")
    compare.add_argument("--integrators", type=_families, default=None,
                         help="comma-separated families to run (default: all that apply to the scene)")
    compare.add_argument("--full", action="store_true", help="the full sweep (more settings, s = 6 too)")
    compare.add_argument("--repeats", type=_positive_int, default=3, help="timed repeats, best kept (default 3)")
    compare.add_argument("--samples", type=_positive_int, default=100,
                         help="times at which the energy error is sampled (default 100)")
    compare.add_argument("--workers", type=_positive_int, default=None,
                         help="processes of the local pool (default: the number of cores; 1: no pool)")
    compare.add_argument("--scheduler", default=None, metavar="ADDRESS",
                         help="send the runs to this Dask distributed scheduler (needs the [dask] extra)")
    compare.add_argument("--output", default="rebound-pfvi-results", help="folder for the results")

    stability = commands.add_parser(
        "stability", help="stiff and extreme cases: pfvi (every fitting, s = 2 and 4) beside IAS15 and WHFast",
        description="Runs each extreme case (e up to 0.9999, flybys, radial infall, Burrau's problem, a "
                    "close encounter, mass ratios, fixed steps beyond u_max, 1e5 periods, a stiff triple) "
                    "with every integrator, each in its own process with a wall-time budget, and writes "
                    "stability.md and stability.json to --output.")
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
    stability.add_argument("--output", default="rebound-pfvi-stability", help="folder for the report")

    paper = commands.add_parser("paper", help="rerun a figure of the seed paper")
    paper.add_argument("figure", choices=("fig1", "fig2", "fig3"),
                       help="fig1: steps against energy error, phase vs none; fig2: energy and position error "
                            "over 1e5 periods at e = 0.95; fig3: the curvature frequency over 10 periods")
    paper.add_argument("--output", default="docs/paper", help="folder for the page, data and PNG (default docs/paper)")
    paper.add_argument("--stages", type=int, default=None, choices=range(2, 7), metavar="{2..6}",
                       help="Gauss-Lobatto nodes (default: 2 for fig1, as in the seed; 4 for fig2 and fig3)")
    paper.add_argument("--step-control", default=None, choices=("seed", "reversible"),
                       help="default: seed for fig1, reversible for fig2 and fig3")
    paper.add_argument("--epsilon", type=_positive_float, default=1e-6, help="fig2/fig3 tolerance (default 1e-6)")
    paper.add_argument("--periods", type=_positive_float, default=None,
                       help="fig2: default 1e5; fig3: default 10")
    paper.add_argument("--samples", type=_positive_int, default=2000, help="fig2: sampled times (default 2000)")
    return parser


class Progress:
    """A one-line progress bar on stderr (a line per run when not a terminal)."""

    def __init__(self, stream=None):
        self.stream = stream or sys.stderr
        self.tty = self.stream.isatty()
        self.start = time.perf_counter()

    def __call__(self, done, total, row=None):
        elapsed = time.perf_counter() - self.start
        what = ""
        if row is not None:
            what = f"{row['line']} {row['knob']}={row['value']:g}"
            if row["status"] != "ok":
                what += f" [{row['status'][:60]}]"
        if self.tty:
            width = 30
            bar = "#" * (width * done // total) + "." * (width - width * done // total)
            self.stream.write(f"\r[{bar}] {done}/{total} {elapsed:5.0f} s  {what[:50]:<50}")
            if done == total:
                self.stream.write("\n")
        else:
            self.stream.write(f"[{done}/{total}] {elapsed:.0f} s {what}\n")
        self.stream.flush()


def _scene_from_args(parser, args):
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
        return scenes.make(args.scene, **params)
    except ValueError as error:
        parser.error(f"scene {args.scene}: {error}")


def run_compare(parser, args, argv):
    from . import compare, report

    scene = _scene_from_args(parser, args)
    try:
        settings = compare.default_settings(scene, "full" if args.full else "quick", args.integrators)
    except ValueError as error:
        parser.error(f"argument --integrators: {error}")
    if not settings:
        parser.error(f"argument --integrators: none of {', '.join(args.integrators)} applies to scene "
                     f"{scene.name!r} (it takes: {', '.join(scene.families)})")
    print(f"{scene.describe()}: {len(settings)} runs, best of {args.repeats}", flush=True)
    results = compare.run(scene, settings, repeats=args.repeats, samples=args.samples, workers=args.workers,
                          scheduler=args.scheduler, progress=Progress())
    command = "rebound-pfvi " + " ".join(shlex.quote(a) for a in argv)
    paths = report.write(results, args.output, command=command)
    if results.interrupted:
        print(f"\nInterrupted: {results.finished} of {len(settings)} runs finished and kept.", file=sys.stderr)
    print(f"Wrote {', '.join(paths.values())} ({results.wall_s:.1f} s)")
    best = report.fastest(results.rows, 1e-6)
    if best:
        winner = min(best, key=lambda n: best[n]["wall_s"])
        print(f"Fastest to a position error of 1e-6 AU: {winner} ({best[winner]['wall_s']:.3g} s)")
    return 130 if results.interrupted else 0


def run_paper(args):
    from . import paper as seed_paper

    if args.figure == "fig1":
        seed_paper.figure1(args.output, stages=args.stages or 2, step_control=args.step_control or "seed",
                           progress=lambda row: print(
                               f"e = {row['e']}, epsilon = {row['epsilon']:.0e}: phase {row['phase_steps']} steps,"
                               f" none {row['none_steps']} steps", flush=True))
        return 0
    stages, control = args.stages or 4, args.step_control or "reversible"
    if args.figure == "fig2":
        progress = Progress()
        periods = args.periods or 1e5
        command = (f"python3 -P -m rebound_pfvi paper fig2 --output {args.output} --periods {periods:g} "
                   f"--samples {args.samples} --stages {stages} --epsilon {args.epsilon:g} --step-control {control}")
        try:
            rows, wall = seed_paper.figure2(args.output, periods=periods, samples=args.samples, stages=stages,
                                            epsilon=args.epsilon, step_control=control,
                                            progress=lambda k, n: progress(k, n) if k % max(1, n // 200) == 0
                                            or k == n else None, command=command)
        except KeyboardInterrupt:
            print("\nInterrupted: nothing written.", file=sys.stderr)
            return 130
        print(f"Figure 2: {rows[-1]['steps']} steps, run time {wall:.1f} s; wrote {args.output}/figure2.md, .png, .json")
        return 0
    periods = args.periods or 10
    command = (f"python3 -P -m rebound_pfvi paper fig3 --output {args.output} --periods {periods:g} "
               f"--stages {stages} --epsilon {args.epsilon:g} --step-control {control}")
    rows, wall = seed_paper.figure3(args.output, periods=periods, stages=stages, epsilon=args.epsilon,
                                    step_control=control, command=command)
    print(f"Figure 3: {len(rows)} steps, run time {wall:.1f} s; wrote {args.output}/figure3.md, .png, .json")
    return 0


def run_stability(args, argv):
    from . import stability

    if args.list:
        for name, case in stability.cases().items():
            print(f"{name:20s} {case.title}")
        return 0
    configs = stability.default_configs(args.integrators, epsilon=args.epsilon)
    names = args.cases or list(stability.cases())
    total = len(names) * len(configs)
    print(f"{len(names)} cases x {len(configs)} integrators = {total} runs, {args.workers} at once, "
          f"budget {args.budget:g} s each", flush=True)
    bar = Progress()
    done = [0]

    def progress(index, outcome):
        done[0] += 1
        row = outcome[1] if outcome[0] == "ok" else None
        what = f"{row['case']}: {row['integrator']} {row['status'][:40]}" if row else f"[{outcome[0]}]"
        bar.stream.write(f"[{done[0]}/{total}] {time.perf_counter() - bar.start:.0f} s {what}\n")
        bar.stream.flush()

    try:
        report = stability.run_all(names, configs, budget=args.budget, workers=args.workers, progress=progress)
    except KeyboardInterrupt:
        print("\nInterrupted: nothing written.", file=sys.stderr)
        return 130
    command = "rebound-pfvi " + " ".join(shlex.quote(a) for a in argv)
    paths = stability.write(report, args.output, command=command)
    bad = [r for r in report.rows if r["status"] != "finished"]
    print(f"Wrote {', '.join(map(str, paths))} ({report.wall_s:.0f} s); {len(report.rows) - len(bad)} runs "
          f"finished, {len(bad)} refused, stopped or failed (see what_happened)")
    return 0


def main(argv=None):
    argv = list(sys.argv[1:] if argv is None else argv)
    parser = build_parser()
    args = parser.parse_args(argv)
    if args.command == "compare":
        return run_compare(parser, args, argv)
    if args.command == "paper":
        return run_paper(args)
    if args.command == "stability":
        return run_stability(args, argv)
    from .demo import run_demo

    run_demo(getattr(args, "orbits", 100))
    return 0


if __name__ == "__main__":
    sys.exit(main())
