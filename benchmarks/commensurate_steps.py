"""Kepler pairs whose orbit takes a whole number of the track's steps: the
error over 100 orbits against the exact two-body solution, beside its
neighbours in e (docs/step-control.md, "Where it falls short"). A hostile
trial found it (2026-11-27).

    python -P benchmarks/commensurate_steps.py
"""
import math

import rebound

import rebound_pfvi  # noqa: F401

ORBITS = 100.37
CASES = ((1e-6, (0.70, 0.71, 0.715, 0.717, 0.72, 0.73)), (1e-8, (0.80, 0.81, 0.82)),
         (1.19e-7, (0.60, 0.61, 0.62)), (1e-10, (0.72, 0.73, 0.74)))


def pair(e, M=4.0):
    sim = rebound.Simulation()
    sim.add(m=1.0)
    sim.add(m=1e-3, a=1.0, e=e, M=M)
    sim.move_to_com()
    return sim


def relative(sim):
    p = sim.particles
    return (p[1].x - p[0].x, p[1].y - p[0].y, p[1].z - p[0].z)


def exact(e, t):
    o = pair(e).particles[1].orbit(primary=pair(e).particles[0])
    sim = rebound.Simulation()
    sim.add(m=1.0)
    sim.add(m=1e-3, a=o.a, e=o.e, omega=o.omega, M=o.M + o.n * t)
    return relative(sim), o.P


def main():
    print("| epsilon | e | steps per orbit | error (epsilon_effective a n) | error (epsilon a n) | IAS15 (1e-11) |")
    print("|---|---|---|---|---|---|")
    for epsilon, es in CASES:
        for e in es:
            period = exact(e, 0.0)[1]
            t_end = ORBITS * period
            reference = exact(e, t_end)[0]
            sim = pair(e)
            sim.integrator = "pfvi"
            sim.integrator.epsilon = epsilon
            sim.integrate(t_end)
            error = math.dist(relative(sim), reference)
            ias15 = pair(e)
            ias15.integrator = "ias15"
            ias15.integrator.epsilon = 1e-11
            ias15.integrate(t_end)
            scale = sim.integrator.epsilon_effective * ORBITS
            print(f"| {epsilon:.3g} | {e:.3g} | {sim.integrator.n_steps / ORBITS:.3f} | {error / scale:.2g} | "
                  f"{error / (epsilon * ORBITS):.2g} | {math.dist(relative(ias15), reference):.1e} |")


if __name__ == "__main__":
    main()
