"""The stage solve at the defaults (docs/solve.md): rounds, force evaluations,
halvings and recoveries over a dense grid of Kepler orbits, equal-mass
binaries, the pages' scenes and planetary systems; rounds against kappa with
fixed steps; and CPU time per step against another build of rebound_pfvi.

    python -P benchmarks/solve.py [--orbits 300] [--baseline "ENV=... python3"] [--output docs/solve-tables.md]

--baseline runs the timing and round-off floor tables also with another build (a shell
command prefix that starts its interpreter, e.g. PYTHONPATH and
LD_LIBRARY_PATH pointing at a checkout of an older commit built in place),
interleaved with this one's, each in a fresh process, best of --repeats.
Everything else runs in this process and in --workers processes.
"""
import argparse
import math
import shlex
import subprocess
import sys
import time
from concurrent.futures import ProcessPoolExecutor

import rebound

import rebound_pfvi  # noqa: F401
from rebound_pfvi import scenes

PHASES = [0.0, math.pi, math.pi / 3, 2 * math.pi / 3, 4 * math.pi / 3, 5 * math.pi / 3]


def statistics(sim):
    ri = sim.integrator
    steps = max(int(ri.n_steps), 1)
    return {"steps": steps, "rounds": float(ri.iterations_mean), "rounds_max": int(ri.iterations_max),
            "evaluations": int(ri.n_force_evaluations) / steps, "halved": int(ri.n_solve_halved),
            "recovered": int(ri.n_solve_recovered), "rejected": int(ri.n_rejected)}


def kepler_run(task):
    e, f, orbits, mass = task
    sim = rebound.Simulation()
    sim.add(m=1.0)
    sim.add(m=mass, a=1.0, e=e, f=f)
    sim.move_to_com()
    sim.integrator = "pfvi"
    sim.integrate(orbits * sim.particles[1].P)
    return (e, f, statistics(sim))


def summary(rows):
    return {"runs": len(rows), "halved": sum(r["halved"] for r in rows),
            "recovered": sum(r["recovered"] for r in rows), "rejected": sum(r["rejected"] for r in rows),
            "rounds_min": min(r["rounds"] for r in rows), "rounds_max": max(r["rounds"] for r in rows),
            "rounds_most": max(r["rounds_max"] for r in rows),
            "evaluations_max": max(r["evaluations"] for r in rows)}


def grid_table(results, bands, title):
    lines = [f"### {title}", "",
             "| e | runs | solve halvings | recovered solves | steps retaken | rounds per step (min - max) "
             "| most rounds in a step | force evaluations per step (max) |",
             "|---|---|---|---|---|---|---|---|"]
    for lo, hi in bands:
        rows = [r for e, f, r in results if lo <= e <= hi + 1e-9]
        if not rows:
            continue
        s = summary(rows)
        lines.append(f"| {lo:.2f} - {hi:.2f} | {s['runs']} | {s['halved']} | {s['recovered']} | {s['rejected']} "
                     f"| {s['rounds_min']:.2f} - {s['rounds_max']:.2f} | {s['rounds_most']} | {s['evaluations_max']:.1f} |")
    return lines


def planetary(kind):
    sim = rebound.Simulation()
    sim.add(m=1.0)
    if kind == "compact-5":
        for k in range(5):
            sim.add(m=3e-6, a=0.1 * 1.3**k, e=0.05, inc=0.01 * k, f=1.3 * k)
    elif kind == "star-10-planets":
        for k in range(10):
            sim.add(m=1e-5, a=1.0 + 0.5 * k, e=0.1, inc=0.01 * k, f=2.1 * k)
    sim.move_to_com()
    return sim


def scene_rows(orbits):
    rows = []
    for name in [n for n in scenes.SCENES if n != "mercury-gr"]:
        scene = scenes.make(name)
        sim = scene.build()
        sim.integrator = "pfvi"
        sim.integrate(scene.t_end, exact_finish_time=1)
        rows.append((f"page: {name}", sim.N, statistics(sim)))
    for kind, span in (("compact-5", 100 * 2 * math.pi * 0.1**1.5), ("star-10-planets", 20 * 2 * math.pi)):
        sim = planetary(kind)
        sim.integrator = "pfvi"
        sim.integrate(span)
        rows.append((kind, sim.N, statistics(sim)))
    return rows


def kappa_rows():
    rows = []
    for e in (0.0, 0.5, 0.9):
        for kappa in (0.5, 1.0, 1.5, 2.0, 3.0, 4.0, 5.0):
            cells = []
            for s in (4, 6, 8):
                sim = rebound.Simulation()
                sim.add(m=1.0)
                sim.add(m=1e-3, a=1.0, e=e, f=math.pi)
                sim.move_to_com()
                sim.integrator = "pfvi"
                sim.integrator.epsilon = 0.0
                sim.integrator.stages = s
                n_peri = math.sqrt((1 + e) / (1 - e)**3)
                sim.dt = kappa / n_peri
                import warnings
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    try:
                        sim.steps(int(20 * 2 * math.pi * n_peri / kappa) + 1)
                        cells.append(f"{sim.integrator.iterations_mean:.2f} ({sim.integrator.iterations_max})")
                    except RuntimeError as error:
                        cells.append("refused: " + ("not converged" if "did not converge" in str(error)
                                                    else str(error).split(";")[0][6:60]))
            rows.append((e, kappa, cells))
    return rows


TIMING = r"""
import math, sys, time, rebound, rebound_pfvi
kind = sys.argv[1]
sim = rebound.Simulation()
sim.add(m=1.0)
if kind == "N=2":
    sim.add(m=1e-3, a=1.0, e=0.5)
    span = 300 * 2 * math.pi
elif kind == "test particle":
    sim.add(m=0.0, a=1.0, e=0.95)
    sim.integrator = "pfvi"
    sim.integrator.epsilon = 1e-12
    span = 100 * 2 * math.pi
elif kind == "N=3":
    sim.add(m=1e-3, a=1.0, e=0.3)
    sim.add(m=3e-4, a=1.9, e=0.2, f=2.0)
    span = 200 * 2 * math.pi
else:
    planets = int(kind[2:]) - 1
    for k in range(planets):
        sim.add(m=1e-6, a=1.0 + 0.05 * k, e=0.05, inc=0.01 * (k % 7), f=2.1 * k)
    span = 2000 * 2 * math.pi / planets
sim.move_to_com()
if kind != "test particle":
    sim.integrator = "pfvi"
t = time.process_time()
sim.integrate(span)
t = time.process_time() - t
print(t / sim.integrator.n_steps * 1e9, sim.integrator.n_steps, float(sim.integrator.iterations_mean))
"""

# The round-off floor: a test particle on Kepler e about a unit mass at
# epsilon eps from `phases` starting phases, its position after `orbits`
# orbits against the exact two-body motion (the mean anomaly advanced by n t).
FLOOR = r"""
import math, statistics, sys, rebound, rebound_pfvi
e, eps, phases, orbits = float(sys.argv[1]), float(sys.argv[2]), int(sys.argv[3]), float(sys.argv[4])
errors, rounds = [], []
for k in range(phases):
    sim = rebound.Simulation()
    sim.add(m=1.0)
    sim.add(m=0.0, a=1.0, e=e, f=2 * math.pi * k / phases)
    sim.integrator = "pfvi"
    sim.integrator.epsilon = eps
    o = sim.particles[1].orbit(primary=sim.particles[0])
    sim.integrate(orbits * o.P)
    exact = rebound.Simulation()
    exact.add(m=1.0)
    exact.add(m=0.0, a=1.0, e=e, M=(o.M + o.n * sim.t) % (2 * math.pi))
    errors.append(math.dist(sim.particles[1].xyz, exact.particles[1].xyz))
    rounds.append(float(sim.integrator.iterations_mean))
print(statistics.median(errors), max(errors), min(errors), statistics.mean(rounds))
"""


def floor_rows(baseline, phases=8, orbits=100):
    rows = []
    for e in (0.5, 0.95):
        for eps in (1e-12, 1e-14):
            cells = {}
            for label, prefix in (("this build", [sys.executable]), ("baseline", shlex.split(baseline))):
                out = subprocess.run(["env"] + prefix + ["-P", "-c", FLOOR, str(e), str(eps), str(phases), str(orbits)],
                                     capture_output=True, text=True, check=True).stdout.split()
                cells[label] = [float(x) for x in out]
            rows.append((e, eps, cells))
    return rows


def last_bit_scatter(runs=10):
    """The retrograde crosser at the defaults from initial conditions `runs`
    ulps apart (particle 2's x times 1 + k 2^-48): its close encounters make
    the step sequence and the error depend on the last bits. Errors: the
    largest position difference from IAS15 at epsilon 1e-11."""
    scene = scenes.make("retrograde")
    ref = scene.build()
    ref.integrator = "ias15"
    ref.integrator.epsilon = 1e-11
    ref.integrate(scene.t_end, exact_finish_time=1)
    rows = []
    for k in range(runs):
        sim = scene.build()
        sim.integrator = "pfvi"
        sim.particles[2].x *= 1 + k * 2.0**-48
        sim.integrate(scene.t_end, exact_finish_time=1)
        error = max(math.dist(a.xyz, b.xyz) for a, b in zip(sim.particles, ref.particles))
        rows.append((k, int(sim.integrator.n_steps), float(sim.integrator.iterations_mean), error))
    return rows


def timing_rows(baseline, repeats):
    rows = []
    for kind in ("N=2", "test particle", "N=3", "N=11", "N=101"):
        best = {"this build": math.inf, "baseline": math.inf}
        info = {}
        for _ in range(repeats):
            for label, prefix in (("this build", [sys.executable]), ("baseline", shlex.split(baseline))):
                out = subprocess.run(["env"] + prefix + ["-P", "-c", TIMING, kind], capture_output=True, text=True,
                                     check=True).stdout.split()
                ns = float(out[0])
                best[label] = min(best[label], ns)
                info[label] = (int(out[1]), float(out[2]))
        rows.append((kind, best, info))
    return rows


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--orbits", type=float, default=300.0)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--baseline", default=None)
    parser.add_argument("--repeats", type=int, default=15)
    parser.add_argument("--output", default=None)
    args = parser.parse_args()
    started = time.time()
    lines = ["# The stage solve at the defaults", "",
             f"Written by `python -P benchmarks/solve.py --orbits {args.orbits:g}"
             + (" --baseline ..." if args.baseline else "") + "` (rebound_pfvi's defaults: s = 8, epsilon 1e-6, "
             "symmetric steps).", ""]
    tasks = [(round(0.01 * k, 2), f, args.orbits, 1e-3) for k in range(100) for f in PHASES]
    binaries = [(round(0.1 * k, 1), f, args.orbits / 3, 1.0) for k in range(10) for f in PHASES]
    with ProcessPoolExecutor(args.workers) as pool:
        kepler = list(pool.map(kepler_run, tasks, chunksize=8))
        binary = list(pool.map(kepler_run, binaries, chunksize=4))
    bands = [(0.0, 0.49), (0.5, 0.69), (0.7, 0.89), (0.9, 0.99)]
    lines += grid_table(kepler, bands,
                        f"1. Kepler pairs (m = 1e-3), e = 0 ... 0.99 every 0.01, six starting phases "
                        f"(pericentre, apocentre, 60, 120, 240, 300 degrees), {args.orbits:g} orbits each")
    lines += [""] + grid_table(binary, [(0.0, 0.45), (0.5, 0.9)],
                               f"2. Equal-mass binaries, e = 0 ... 0.9 every 0.1, six phases, "
                               f"{args.orbits / 3:g} orbits each")
    lines += ["", "### 3. The pages' scenes (their full runs) and planetary systems", "",
              "| run | N | steps | rounds per step | most in a step | force evaluations per step "
              "| solve halvings | recovered solves | steps retaken |", "|---|---|---|---|---|---|---|---|---|"]
    for name, n, r in scene_rows(args.orbits):
        lines.append(f"| {name} | {n} | {r['steps']} | {r['rounds']:.2f} | {r['rounds_max']} | {r['evaluations']:.1f} "
                     f"| {r['halved']} | {r['recovered']} | {r['rejected']} |")
    lines += ["", "### 4. Fixed steps: rounds per step (most in a step) against kappa = h n_pericentre, "
              "20 orbits from apocentre", "",
              "| e | kappa | s = 4 | s = 6 | s = 8 |", "|---|---|---|---|---|"]
    for e, kappa, cells in kappa_rows():
        lines.append(f"| {e} | {kappa} | " + " | ".join(cells) + " |")
    lines += ["", "### 5. Last-bit sensitivity: the retrograde crosser at the defaults, particle 2's x times "
              "1 + k 2^-48; error: largest position difference from IAS15 at epsilon 1e-11", "",
              "| k | steps | rounds per step | error (AU) |", "|---|---|---|---|"]
    for k, steps, rounds, error in last_bit_scatter():
        lines.append(f"| {k} | {steps} | {rounds:.2f} | {error:.2g} |")
    if args.baseline:
        lines += ["", f"### 6. CPU time per step (best of {args.repeats}, interleaved, each run a fresh process)", "",
                  "| system (N = 11, 101: a star and 10, 100 planets of 1e-6; the test particle: e = 0.95 at epsilon 1e-12) | this build: ns/step | rounds | baseline: ns/step | rounds | ratio |", "|---|---|---|---|---|---|"]
        for kind, best, info in timing_rows(args.baseline, args.repeats):
            lines.append(f"| {kind} | {best['this build']:.0f} | {info['this build'][1]:.2f} | {best['baseline']:.0f} "
                         f"| {info['baseline'][1]:.2f} | {best['this build'] / best['baseline']:.2f} |")
    if args.baseline:
        lines += ["", "### 7. The round-off floor: a test particle about a unit mass, 100 orbits, eight starting "
                  "phases; position error against the exact two-body motion (median, max, min over the phases)", "",
                  "| e | epsilon | this build | rounds | baseline | rounds |", "|---|---|---|---|---|---|"]
        for e, eps, cells in floor_rows(args.baseline):
            a, b = cells["this build"], cells["baseline"]
            lines.append(f"| {e} | {eps:g} | {a[0]:.2g}, {a[1]:.2g}, {a[2]:.2g} | {a[3]:.2f} "
                         f"| {b[0]:.2g}, {b[1]:.2g}, {b[2]:.2g} | {b[3]:.2f} |")
    lines += ["", f"(`python -P benchmarks/solve.py --orbits {args.orbits:g}` took {time.time() - started:.0f} s "
              f"on {args.workers} workers.)", ""]
    text = "\n".join(lines)
    if args.output:
        with open(args.output, "w") as f:
            f.write(text)
    print(text)


if __name__ == "__main__":
    main()
