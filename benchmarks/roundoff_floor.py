"""The round-off floor on Kepler e = 0.95: pfvi's final error in the
relative position (body 1 about body 0, m = 1 and 1e-3, COM frame) after
100 orbits against the exact two-body motion, from six starting phases, at
each epsilon given; with the stage solve's rounds per step and the steps.

    python -P benchmarks/roundoff_floor.py [--eps 1e-10,1e-12,1e-13,1e-14]

docs/performance.md uses it to test the stop rule as the floor's cause: run
once as built and once with PFVI_SOLVE_RESOLUTION (rebound_pfvi/csrc/pfvi.h)
set to 0x1p-64 and the core rebuilt in place.
"""
import argparse
import math
import statistics

import rebound

import rebound_pfvi  # noqa: F401

PHASES = (0.0, 1.0, 2.5, 3.14159, 4.0, 5.5)


def run(epsilon, f):
    sim = rebound.Simulation()
    sim.add(m=1.0)
    sim.add(m=1e-3, a=1.0, e=0.95, f=f)
    sim.move_to_com()
    o = sim.particles[1].orbit(primary=sim.particles[0])
    sim.integrator = "pfvi"
    sim.integrator.epsilon = epsilon
    sim.integrate(100 * o.P, exact_finish_time=1)
    exact = rebound.Simulation()
    exact.add(m=1.0)
    exact.add(m=1e-3, a=o.a, e=o.e, omega=o.omega, M=(o.M + o.n * sim.t) % (2 * math.pi))
    d, de = sim.particles[1] - sim.particles[0], exact.particles[1] - exact.particles[0]
    return math.dist(d.xyz, de.xyz), float(sim.integrator.iterations_mean), sim.integrator.n_steps


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--eps", default="1e-10,1e-12,1e-13,1e-14")
    args = parser.parse_args()
    print("| epsilon | median error | largest | rounds per step | steps |")
    print("|---|---|---|---|---|")
    for epsilon in (float(x) for x in args.eps.split(",")):
        runs = [run(epsilon, f) for f in PHASES]
        errors = [r[0] for r in runs]
        print(f"| {epsilon:g} | {statistics.median(errors):.2e} | {max(errors):.2e} | "
              f"{statistics.mean(r[1] for r in runs):.2f} | {statistics.mean(r[2] for r in runs):.0f} |")


if __name__ == "__main__":
    main()
