"""Where a near-circular orbit's steps could be longer, and why they are not
(issue 42; docs/performance.md, "Longer steps for near-circular orbits").

    python -P benchmarks/circular_steps.py [--parts pairs,comet,planets]

pairs: Kepler pairs (m = 1e-6 about 1, a = 1, from pericentre, 100 orbits)
at pfvi's defaults, epsilon 1e-6 and 1e-9: steps per orbit and the
position error per orbit relative to a, against IAS15 at 1e-14. Below
e = 0.2 the error is many decades under epsilon: the steps are set by the
orbit's frequency (kappa about 1), not by the error.

comet: the Encke-like comet among Venus, Earth, Mars and Jupiter (the
scene of benchmarks/equal_error.py, 20 comet periods): each body's final
relative position error against IAS15 at 1e-13, for pfvi at several
epsilon and IAS15 at its loosest settings, and where the first comet
orbit's steps lie (by the comet's distance from the Sun).

planets: the comet's planets without it, Venus with each of the others
(moved to their barycentre, 20 comet periods): Venus's final relative
position error against IAS15 at 1e-13, at the defaults. It tells which
pull sets the steps Venus needs.

With PFVI_EXP_M / PFVI_EXP_EC read by a build patched as docs/performance.md
describes (not in the tree), the same script measures the longer steps.
"""
import argparse
import math
import os
import sys

import numpy as np
import rebound

import rebound_pfvi  # noqa: F401  (registers "pfvi")
from rebound_pfvi import scenes
from rebound_pfvi.verdict import relative_position_error

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import outputs  # noqa: E402  (the Encke-like scene)


def pairs():
    print("| e | epsilon | steps/orbit | error per orbit / a |")
    print("|---|---|---|---|")
    for e in (0.0, 0.007, 0.05, 0.2, 0.5, 0.85, 0.95):
        for epsilon in (1e-6, 1e-9):
            sim = rebound.Simulation()
            sim.add(m=1.0)
            sim.add(m=1e-6, a=1.0, e=e)
            sim.move_to_com()
            period = sim.particles[1].P
            reference = sim.copy()
            sim.integrator = "pfvi"
            sim.integrator.epsilon = epsilon
            sim.integrate(100 * period, exact_finish_time=1)
            reference.integrator = "ias15"
            reference.integrator.epsilon = 1e-14
            reference.integrate(100 * period, exact_finish_time=1)
            p, q = sim.particles, reference.particles
            miss = math.dist([p[1].x - p[0].x, p[1].y - p[0].y, p[1].z - p[0].z],
                             [q[1].x - q[0].x, q[1].y - q[0].y, q[1].z - q[0].z])
            print(f"| {e:g} | {epsilon:.0e} | {sim.steps_done / 100:.1f} | {miss / 100:.1e} |")


def comet():
    scene = outputs.Encke()
    sim = scene.build()
    sim.integrator = "ias15"
    sim.integrator.epsilon = 1e-13
    sim.integrate(scene.t_end, exact_finish_time=1)
    reference = [[p.x, p.y, p.z] for p in sim.particles]
    names = ["Venus", "Earth", "Mars", "Jupiter", "comet"]
    print("| integrator | epsilon | steps | " + " | ".join(names) + " | largest |")
    print("|---|---|---|" + "---|" * (len(names) + 1))
    runs = [("pfvi", x) for x in (1e-6, 1e-8, 1e-10, 1e-12)] + [("ias15", x) for x in (1e-4, 1e-6)]
    for integrator, epsilon in runs:
        sim = scene.build()
        sim.integrator = integrator
        sim.integrator.epsilon = epsilon
        sim.integrate(scene.t_end, exact_finish_time=1)
        got = [[p.x, p.y, p.z] for p in sim.particles]
        each = [relative_position_error([got[0], got[i]], [reference[0], reference[i]]) for i in range(1, sim.N)]
        print(f"| {integrator} | {epsilon:.0e} | {sim.steps_done} | " + " | ".join(f"{x:.1e}" for x in each)
              + f" | {relative_position_error(got, reference):.1e} |")
    print("\nThe first comet orbit's steps by the comet's distance r from the Sun (AU):\n")
    bins = (0.3, 0.4, 0.6, 1.0, 2.0, 5.0)
    print("| integrator | epsilon | steps | " + " | ".join(f"r {a:g}-{b:g}" for a, b in zip(bins, bins[1:])) + " |")
    print("|---|---|---|" + "---|" * (len(bins) - 1))
    for integrator, epsilon in (("pfvi", 1e-6), ("pfvi", 1e-10), ("ias15", 1e-4), ("ias15", 1e-6)):
        sim = scene.build()
        period = sim.particles[5].orbit(primary=sim.particles[0]).P
        sim.integrator = integrator
        sim.integrator.epsilon = epsilon
        distances = []
        while sim.t < period:
            sim.steps(1)
            p = sim.particles
            distances.append(math.dist(p[5].xyz, p[0].xyz))
        counts = np.histogram(distances, bins=bins)[0]
        print(f"| {integrator} | {epsilon:.0e} | {len(distances)} | " + " | ".join(str(c) for c in counts) + " |")


def planets():
    scene = outputs.Encke()
    print("| bodies | steps | Venus's error |")
    print("|---|---|---|")
    for label, keep in (("Sun, Venus", (0, 1)), ("Sun, Venus, Earth", (0, 1, 2)),
                        ("Sun, Venus, Jupiter", (0, 1, 4)), ("Sun and the four planets", (0, 1, 2, 3, 4))):
        runs = []
        for integrator, epsilon in (("ias15", 1e-13), ("pfvi", 1e-6)):
            whole = scene.build()
            sim = scenes.new_simulation()   # (the scene's units)
            for i in keep:
                sim.add(whole.particles[i].copy())
            sim.move_to_com()
            sim.integrator = integrator
            sim.integrator.epsilon = epsilon
            sim.integrate(scene.t_end)
            runs.append(sim)
        reference, sim = runs
        error = relative_position_error([[p.x, p.y, p.z] for p in sim.particles][:2],
                                        [[p.x, p.y, p.z] for p in reference.particles][:2])
        print(f"| {label} | {sim.steps_done} | {error:.1e} |")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--parts", default="pairs,comet,planets")
    args = parser.parse_args()
    for part in args.parts.split(","):
        {"pairs": pairs, "comet": comet, "planets": planets}[part]()
        print()


if __name__ == "__main__":
    main()
