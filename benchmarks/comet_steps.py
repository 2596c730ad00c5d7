"""Where the Encke-like comet's error comes from at the defaults: its steps
into perihelion and the track's drift corrections (docs/step-control.md,
"Where it falls short").

    python -P benchmarks/comet_steps.py [--epsilons 1.2e-7,1e-7,5e-8]   # about 20 s

For each epsilon: the run's end error against IAS15 (epsilon 1e-13), in AU
and in epsilon a n (a = 2.2 AU, n = 20 orbits); its steps and asymmetric
steps; each asymmetric step (t, its length, the comet's distance from the
Sun at its start and end); and the longest step into perihelion, as h omega
at its end (omega = sqrt(G M/r^3), the comet's local rate there).
"""
import argparse
import math
import sys
from pathlib import Path

import rebound_pfvi  # noqa: F401

sys.path.insert(0, str(Path(__file__).resolve().parent))

import outputs  # noqa: E402  (the Encke-like comet)


def distance(sim):
    c, s = sim.particles[-1], sim.particles[0]
    return math.sqrt((c.x - s.x) ** 2 + (c.y - s.y) ** 2 + (c.z - s.z) ** 2)


def reference(scene, t):
    sim = scene.build()
    sim.integrator = "ias15"
    sim.integrator.epsilon = 1e-13
    sim.integrate(t)
    return [(p.x, p.y, p.z) for p in sim.particles]


def run(scene, epsilon):
    sim = scene.build()
    sim.integrator = "pfvi"
    sim.integrator.epsilon = epsilon
    it = sim.integrator
    GM = sim.G * sim.particles[0].m
    asymmetric, worst, n_asym = [], (0.0, None), 0
    while sim.t < scene.t_end:
        t0, r0 = sim.t, distance(sim)
        sim.steps(1)
        h, r1 = sim.t - t0, distance(sim)
        if it.n_asymmetric != n_asym:
            n_asym = it.n_asymmetric
            asymmetric.append((t0, h, r0, r1))
        if r1 < r0:   # inbound
            u = h * math.sqrt(GM / r1 ** 3)
            worst = max(worst, (u, (t0, h, r0, r1)))
    return sim, asymmetric, worst


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--epsilons", default="1.2e-7,1e-7,5e-8")
    args = parser.parse_args()
    scene = outputs.Encke()
    scale = 2.2 * scene.periods
    for epsilon in (float(e) for e in args.epsilons.split(",")):
        sim, asymmetric, (u, (t0, h, r0, r1)) = run(scene, epsilon)
        # (the run's own steps end past t_end: the reference is taken where they end)
        ref = reference(scene, sim.t)
        error = max(math.dist((p.x, p.y, p.z), q) for p, q in zip(sim.particles, ref))
        print(f"epsilon {epsilon:g}: end error {error:.2g} AU ({error / (epsilon * scale):.2g} epsilon a n), "
              f"{sim.integrator.n_steps} steps, {sim.integrator.n_asymmetric} asymmetric")
        for a in asymmetric:
            print(f"    asymmetric step at t = {a[0]:.3f}: h = {a[1]:.4f}, r {a[2]:.3f} -> {a[3]:.3f} AU")
        print(f"    longest step into perihelion: h omega = {u:.2f} at its end (t = {t0:.3f}, h = {h:.4f}, "
              f"r {r0:.3f} -> {r1:.3f} AU)")


if __name__ == "__main__":
    main()
