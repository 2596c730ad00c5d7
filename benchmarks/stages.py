"""The s-stage pfvi beside LEAPFROG and IAS15: cost per step, and error
against steps and against wall time, with fixed steps.

    python -P benchmarks/stages.py cost        [--repeats 5]
    python -P benchmarks/stages.py precision   [--e 0.5] [--orbits 100] [--repeats 3]
    python -P benchmarks/stages.py oscillator
    python -P benchmarks/stages.py predictor
    python -P benchmarks/stages.py order
    python -P benchmarks/stages.py reversibility

cost: ns/step, force evaluations and iterations per step for s = 2..6
(fitting "phase" and "none"), N = 2 (m = 1 and 1e-3, a = 1, e = 0.5, COM
frame, 100 steps per orbit, 100 orbits), beside LEAPFROG on the same steps.
Runs are interleaved and the best of --repeats is kept: the machine is shared
and noisy, so compare ratios within one run.

precision: the same two bodies at eccentricity --e for --orbits orbits. For
each setting, the largest relative energy error over the run (sampled 200
times), the final position error against the exact Kepler position (REBOUND's
orbital elements, mean anomaly advanced by n t), steps, and wall time (best
of --repeats, sampling included for every integrator alike). pfvi and
LEAPFROG sweep steps per orbit; IAS15 sweeps its epsilon.

oscillator: relative position error after 1000 steps of u = 0.5 on the 2-D
oscillator (omega = 1, frequency "fixed"), every s and fitting: the values
asserted in tests/test_stages.py.

order: e = 0.5, one orbit of a test particle around m = 1, every s, "none"
and "phase": largest energy error and final position error at the step
counts of tests/test_stages.py, and the slope of the position error between
them (the order the test asserts).

reversibility: 10 orbits at e = 0.5 (m = 1 and 1e-3, COM frame, 100 steps
per orbit) and back, with the curvature frequency: the largest difference
from the start in any coordinate.

predictor: mean iterations per step with the last step's stage accelerations
extrapolated (default) and without (the predictor cleared before every step).
Output: markdown tables on stdout.
"""
import argparse
import math
import time

import rebound

import rebound_pfvi  # noqa: F401
from rebound_pfvi.integrators import configure as configure_integrator

STAGES = (2, 3, 4, 5, 6)


def two_body(e):
    sim = rebound.Simulation()
    sim.add(m=1.0)
    sim.add(m=1e-3, a=1.0, e=e)
    sim.move_to_com()
    return sim


def configure(sim, integrator, fields):
    configure_integrator(sim, integrator, **fields)


def pfvi(s, fitting):
    return "pfvi", {"stages": s, "fitting": fitting, "epsilon": 0.}  # fixed steps


def cost(repeats):
    settings = [("leapfrog", "leapfrog", {})]
    for s in STAGES:
        for fitting in ("phase", "none"):
            settings.append((f"pfvi s={s} {fitting}",) + pfvi(s, fitting))
    steps = 10000
    best = {}
    stats = {}
    for _ in range(repeats):
        for label, integrator, fields in settings:
            sim = two_body(0.5)
            configure(sim, integrator, fields)
            sim.dt = 2 * math.pi / 100
            tick = time.perf_counter()
            sim.steps(steps)
            wall = time.perf_counter() - tick
            best[label] = min(best.get(label, math.inf), wall / steps * 1e9)
            if integrator == "pfvi":
                stats[label] = (sim.integrator.n_force_evaluations / steps, sim.integrator.iterations_mean,
                                sim.integrator.iterations_max)
            else:
                stats[label] = (1.0, None, None)
    print("| integrator | ns/step | ratio to leapfrog | force evaluations/step | iterations/step (mean, max) |")
    print("|---|---|---|---|---|")
    for label, _, _ in settings:
        fe, mean, most = stats[label]
        iterations = "" if mean is None else f"{mean:.2f}, {most}"
        print(f"| {label} | {best[label]:.0f} | {best[label] / best['leapfrog']:.2f} | {fe:.2f} | {iterations} |")


def run_precision(e, orbits, integrator, fields, dt=None, epsilon=None, samples=200):
    sim = two_body(e)
    configure(sim, integrator, fields)
    if dt is not None:
        sim.dt = dt
    if epsilon is not None:
        sim.integrator.epsilon = epsilon
    orbit = sim.particles[1].orbit(primary=sim.particles[0])
    E0 = sim.energy()
    energy_error = 0.0
    tick = time.perf_counter()
    if dt is not None:
        total = int(round(orbits * orbit.P / dt))
        done = 0
        for k in range(1, samples + 1):
            target = total * k // samples
            sim.steps(target - done)
            done = target
            energy_error = max(energy_error, abs(sim.energy() / E0 - 1))
        t_end = total * dt
        steps = total
    else:
        for k in range(1, samples + 1):
            sim.integrate(orbits * orbit.P * k / samples, exact_finish_time=0)
            energy_error = max(energy_error, abs(sim.energy() / E0 - 1))
        t_end = sim.t
        steps = sim.steps_done
    wall = time.perf_counter() - tick
    exact = two_body(e)
    p, star = exact.particles[1], exact.particles[0]
    ref = rebound.Simulation()
    ref.add(m=star.m)
    ref.add(m=p.m, a=orbit.a, e=e, M=orbit.M + orbit.n * t_end)
    rel = (sim.particles[1].x - sim.particles[0].x, sim.particles[1].y - sim.particles[0].y)
    position_error = math.hypot(rel[0] - ref.particles[1].x, rel[1] - ref.particles[1].y)
    evaluations = sim.integrator.n_force_evaluations if integrator == "pfvi" else None
    return energy_error, position_error, steps, wall, evaluations


def precision(e, orbits, repeats):
    period = two_body(e).particles[1].P
    rows = []
    sweeps = [("leapfrog", "leapfrog", {}, [300, 1000, 3000, 10000, 30000, 100000])]
    per_orbit = {2: [300, 1000, 3000, 10000], 3: [100, 200, 400, 800, 1600],
                 4: [50, 100, 200, 400, 800], 5: [50, 100, 200, 400], 6: [40, 80, 160, 320]}
    if e > 0.8:
        per_orbit = {s: [n * 10 for n in ns] for s, ns in per_orbit.items()}
        sweeps[0] = ("leapfrog", "leapfrog", {}, [3000, 10000, 30000, 100000, 300000])
    for s in STAGES:
        for fitting in ("phase", "none"):
            sweeps.append((f"pfvi s={s} {fitting}",) + pfvi(s, fitting) + (per_orbit[s],))
    for label, integrator, fields, ns in sweeps:
        for n in ns:
            best = None
            for _ in range(repeats):
                try:
                    result = run_precision(e, orbits, integrator, fields, dt=period / n)
                except RuntimeError as error:
                    result = None
                    print(f"<!-- {label} n={n}: {error} -->")
                    break
                if best is None or result[3] < best[3]:
                    best = result
            if best is not None:
                rows.append((label, f"{n}/orbit", *best))
    for epsilon in (1e-5, 1e-7, 1e-9):
        best = None
        for _ in range(repeats):
            result = run_precision(e, orbits, "ias15", {}, epsilon=epsilon)
            if best is None or result[3] < best[3]:
                best = result
        rows.append(("ias15", f"epsilon={epsilon:g}", *best))
    print(f"e = {e}, {orbits} orbits, m = 1 and 1e-3, COM frame\n")
    print("| integrator | step | max rel. energy error | position error | steps | force evaluations | wall time [s] |")
    print("|---|---|---|---|---|---|---|")
    for label, step, energy, position, steps, wall, evaluations in rows:
        fe = "" if evaluations is None else str(evaluations)
        print(f"| {label} | {step} | {energy:.2e} | {position:.2e} | {steps} | {fe} | {wall:.4f} |")


def tests_path():
    import os
    import sys
    sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tests"))


def order():
    tests_path()
    from test_stages import ORDER_STEPS, kepler_errors

    print("| s | steps/orbit | none: energy, position | phase: energy, position | slope none / phase |")
    print("|---|---|---|---|---|")
    for s in STAGES:
        n1, n2 = ORDER_STEPS[s]
        cells, slopes = [], []
        for fitting in ("none", "phase"):
            coarse, fine = kepler_errors(s, fitting, n1), kepler_errors(s, fitting, n2)
            cells.append(f"{coarse[0]:.3g}, {coarse[1]:.3g}")
            slopes.append(math.log(coarse[1] / fine[1]) / math.log(n2 / n1))
        print(f"| {s} | {n1} | {cells[0]} | {cells[1]} | {slopes[0]:.2f} / {slopes[1]:.2f} |")


def reversibility():
    tests_path()
    from test_verlet_and_reversibility import round_trip

    print("| s | round trip, curvature frequency |")
    print("|---|---|")
    for s in STAGES:
        sim = two_body(0.5)
        configure(sim, *pfvi(s, "phase"))
        sim.dt = 2 * math.pi / 100
        print(f"| {s} | {round_trip(sim, 1000):.2g} |")


def oscillator():
    tests_path()
    from conftest import harmonic_oscillator, oscillator_exact

    print("| s | phase | phase-literal | none |")
    print("|---|---|---|---|")
    for s in STAGES:
        errors = []
        for fitting in ("phase", "phase-literal", "none"):
            sim = harmonic_oscillator(1.0, stages=s, fitting=fitting)
            sim.dt = 0.5
            sim.steps(1000)
            q, _ = oscillator_exact(1.0, 1000, 0.5, (1.0, 0.3), (0.2, 0.7))
            p = sim.particles[0]
            errors.append(math.hypot(p.x - q[0], p.y - q[1]) / math.hypot(*q))
        print(f"| {s} | " + " | ".join(f"{x:.3g}" for x in errors) + " |")


def predictor():
    print("| s | e | steps/orbit | iterations/step, extrapolated | iterations/step, start force only |")
    print("|---|---|---|---|---|")
    for s in (3, 4, 6):
        for e, n in ((0.5, 100), (0.95, 1000)):
            means = []
            for clear in (False, True):
                sim = two_body(e)
                configure(sim, *pfvi(s, "phase"))
                sim.dt = sim.particles[1].P / n
                if clear:
                    for _ in range(2 * n):
                        sim.integrator.predictor_stages = 0
                        sim.steps(1)
                else:
                    sim.steps(2 * n)
                means.append(sim.integrator.iterations_mean)
            print(f"| {s} | {e} | {n} | {means[0]:.2f} | {means[1]:.2f} |")


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("what", choices=("cost", "precision", "oscillator", "predictor", "order",
                                         "reversibility"))
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--e", type=float, default=0.5)
    parser.add_argument("--orbits", type=int, default=100)
    args = parser.parse_args()
    if args.what == "cost":
        cost(args.repeats)
    elif args.what == "precision":
        precision(args.e, args.orbits, args.repeats)
    elif args.what == "oscillator":
        oscillator()
    elif args.what == "order":
        order()
    elif args.what == "reversibility":
        reversibility()
    else:
        predictor()


if __name__ == "__main__":
    main()
