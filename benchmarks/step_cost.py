"""ns per step of pfvi beside LEAPFROG, WHFast and IAS15, as ratios from one run;
and the stage solve of every s beside IAS15 on eccentric orbits.

(The heartbeat rows: a Python heartbeat that does nothing, on pfvi and LEAPFROG.)

    python benchmarks/step_cost.py [--repeats 7] [--steps 200000] [--periods 100]

Two systems: N = 2 (m = 1 and 1e-3, a = 1, e = 0.5) and a star with 50
planets (masses 1e-5, a from 1 to 6, small e and inc). Every integrator runs
the same simulation for the same number of steps (IAS15: its own adaptive
steps over the same time span, counted with steps_done). Runs are
interleaved, integrator by integrator, `--repeats` times, and the best time
is kept: the machines are shared and noisy, so only the ratios in one run
mean something.

The second table: the default pfvi (symmetric steps, fitting "none",
epsilon 1e-6) at every s, and IAS15 at its default epsilon 1e-9, on Kepler
e = 0.5 and e = 0.95 (m = 1e-3, COM frame) for --periods periods: ns/step,
force evaluations per step (counted untimed by an empty additional_forces
callback) and, for pfvi, iterations (rounds of s - 1 evaluations) per stage
solve, and the run time over IAS15's for the same orbits (the runs of one
e interleaved). Output: markdown tables on stdout.
"""
import argparse
import random
import time

import rebound

import rebound_pfvi  # noqa: F401
from rebound_pfvi.integrators import configure as configure_integrator


def two_body():
    sim = rebound.Simulation()
    sim.add(m=1.0)
    sim.add(m=1e-3, a=1.0, e=0.5)
    sim.move_to_com()
    return sim, 2e-3


def star_and_50_planets():
    rng = random.Random(1)
    sim = rebound.Simulation()
    sim.add(m=1.0)
    for k in range(50):
        sim.add(m=1e-5, a=1.0 + 0.1 * k, e=0.05 * rng.random(), inc=0.02 * rng.random(),
                f=6.283 * rng.random())
    sim.move_to_com()
    return sim, 2e-3


SETTINGS = {
    # The two-point scheme with fixed steps (the integrator's default is adaptive, s = 8).
    "pfvi s=2 phase": ("pfvi", {"fitting": "phase", "epsilon": 0., "stages": 2}),
    "pfvi s=2 none": ("pfvi", {"fitting": "none", "epsilon": 0., "stages": 2}),
    # Under a heartbeat pfvi cannot reuse the last step's end force (the
    # heartbeat may change anything the force reads): one more evaluation per step.
    "pfvi s=2 phase + heartbeat": ("pfvi", {"fitting": "phase", "epsilon": 0., "stages": 2}),
    "leapfrog + heartbeat": ("leapfrog", {}),
    "leapfrog": ("leapfrog", {}),
    "whfast": ("whfast", {}),
    "ias15": ("ias15", {}),
}


def _no_op(simp):
    pass


def time_once(make, setting, steps):
    sim, dt = make()
    integrator, fields = SETTINGS[setting]
    configure_integrator(sim, integrator, dt=dt, **fields)
    if setting.endswith("+ heartbeat"):
        sim.heartbeat = _no_op
    tick = time.perf_counter()
    sim.integrate(steps * dt, exact_finish_time=0)
    wall = time.perf_counter() - tick
    return wall / sim.steps_done * 1e9, sim.steps_done


def measure(make, steps, repeats):
    best = {name: float("inf") for name in SETTINGS}
    counts = {}
    for _ in range(repeats):
        for name in SETTINGS:
            ns, n = time_once(make, name, steps)
            best[name] = min(best[name], ns)
            counts[name] = n
    return best, counts


def _solve_build(e, setting, periods):
    from rebound_pfvi.scenes import Kepler
    integrator, stages = setting
    scene = Kepler(e=e, periods=periods)
    sim = scene.build()
    if integrator == "pfvi":
        configure_integrator(sim, "pfvi", stages=stages)
    else:
        configure_integrator(sim, "ias15")
    return sim, scene.t_end


def solve_rows(e, settings, periods, repeats):
    """setting -> (ns/step, steps, force evaluations/step, iterations/solve or None),
    the settings' runs interleaved as in the first table."""
    best = {setting: float("inf") for setting in settings}
    done = {}
    for _ in range(repeats):
        for setting in settings:
            sim, t_end = _solve_build(e, setting, periods)
            tick = time.perf_counter()
            sim.integrate(t_end, exact_finish_time=0)
            best[setting] = min(best[setting], time.perf_counter() - tick)
            done[setting] = sim
    rows = {}
    for setting in settings:
        sim = done[setting]
        counted, t_end = _solve_build(e, setting, periods)
        calls = [0]

        def count(simp):
            calls[0] += 1

        counted.additional_forces = count
        counted.integrate(t_end, exact_finish_time=0)
        iterations = sim.integrator.iterations_mean if setting[0] == "pfvi" else None
        rows[setting] = (best[setting] / sim.steps_done * 1e9, sim.steps_done,
                         calls[0] / counted.steps_done, iterations, best[setting])
    return rows


def stage_solve_table(periods, repeats):
    settings = [("pfvi", s) for s in rebound_pfvi.STAGES if s >= 3] + [("ias15", None)]
    print()
    print(f"Stage solve, adaptive defaults, Kepler (m = 1e-3, COM frame), {periods:g} periods, "
          f"best of {repeats} interleaved runs:")
    print()
    print("| e | integrator | steps | ns/step | force evaluations/step | iterations/solve | run time / IAS15's |")
    print("|---|---|---|---|---|---|---|")
    for e in (0.5, 0.95):
        rows = solve_rows(e, settings, periods, repeats)
        ias15 = rows[("ias15", None)][4]
        for setting in settings:
            ns, steps, evaluations, iterations, wall = rows[setting]
            name = f"pfvi s={setting[1]}" if setting[0] == "pfvi" else "ias15"
            its = f"{iterations:.2f}" if iterations is not None else "-"
            print(f"| {e:g} | {name} | {steps} | {ns:.0f} | {evaluations:.1f} | {its} | {wall / ias15:.2f} |")


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeats", type=int, default=7)
    parser.add_argument("--steps", type=int, default=200_000, help="steps at N = 2 (N = 51: steps/50)")
    parser.add_argument("--periods", type=float, default=100.0, help="orbits of the stage-solve table")
    args = parser.parse_args()
    print(f"rebound {rebound.__version__}, rebound_pfvi {rebound_pfvi.__version__}, "
          f"best of {args.repeats} interleaved runs")
    print()
    print("| system | integrator | steps | ns/step | ratio to leapfrog |")
    print("|---|---|---|---|---|")
    for label, make, steps in (("N = 2", two_body, args.steps),
                               ("N = 51", star_and_50_planets, max(args.steps // 50, 100))):
        best, counts = measure(make, steps, args.repeats)
        for name in SETTINGS:
            print(f"| {label} | {name} | {counts[name]} | {best[name]:.0f} | "
                  f"{best[name] / best['leapfrog']:.2f} |")
    stage_solve_table(args.periods, args.repeats)


if __name__ == "__main__":
    main()
