"""The round-off floor on near-radial Kepler pairs, pfvi (s = 8) beside
IAS15 at the same epsilon: the worst final position error over 6 phases,
in units of epsilon a n (a = 1, n = 20 orbits), against the exact orbit
(the pair's elements at M + n T). docs/step-control.md, "Epsilon".

    python -P benchmarks/radial_floor.py [--orbits 20]
"""
import argparse
import math

import numpy as np
import rebound

import rebound_pfvi  # noqa: F401  (registers "pfvi")


def pair(e, f):
    sim = rebound.Simulation()
    sim.add(m=1.0)
    sim.add(m=1e-3, a=1.0, e=e, f=f, inc=0.3, Omega=0.3, omega=0.7)
    sim.move_to_com()
    return sim


def relative(sim):
    p, q = sim.particles[1], sim.particles[0]
    return np.array([p.x - q.x, p.y - q.y, p.z - q.z])


def worst_ratio(integrator, e, epsilon, orbits):
    ratios = []
    for k in range(6):
        sim = pair(e, k * 2 * math.pi / 6 + 0.1)
        orbit = sim.particles[1].orbit(primary=sim.particles[0])
        t_end = orbit.P * orbits
        exact = rebound.Simulation()
        exact.add(m=1.0)
        exact.add(m=1e-3, a=1.0, e=e, inc=0.3, Omega=0.3, omega=0.7, M=orbit.M + orbit.n * t_end)
        sim.integrator = integrator
        sim.integrator.epsilon = epsilon
        sim.integrate(t_end)
        ratios.append(np.abs(relative(sim) - relative(exact)).max() / (epsilon * orbits))
    return max(ratios)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--orbits", type=int, default=20)
    args = parser.parse_args(argv)
    epsilons = (1e-10, 1e-12, 1e-13)
    print("| e | " + " | ".join(f"ε = {eps:g}" for eps in epsilons) + " |")
    print("|---|" + "---|" * len(epsilons))
    for e in (0.95, 0.99, 0.999):
        cells = []
        for eps in epsilons:
            cells.append("%.2g, %.2g" % (worst_ratio("pfvi", e, eps, args.orbits),
                                         worst_ratio("ias15", e, eps, args.orbits)))
        print(f"| {e} | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    main()
