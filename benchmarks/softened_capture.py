"""A test particle captured for a while by a planet, its pericentres inside
the softening length: pfvi's error against IAS15 (epsilon 1e-14) with and
without softening (docs/step-control.md, "Where it falls short").

    python -P benchmarks/softened_capture.py     # about 10 s

Sun, two planets of 1e-3 (a = 1, e = 0.3; a = 2.2, e = 0.2), and a massless
particle (a = 1.5, e = 0.5) that orbits the first planet about 50 times at
0.005 to 0.05 before it leaves; 3 orbits of the first planet. The error is
the test particle's distance from IAS15's at the end; the goal of the step
control is about 10 epsilon a n (a n: 1.5 x 3), for errors that add up along
the orbit. "Amplification": how much IAS15 (1e-14) moves the particle's end
for a shift of 1e-12 in its starting x, the factor by which the dynamics
multiply any error made early on.
"""
import math

import rebound

import rebound_pfvi  # noqa: F401

T = 3 * 2 * math.pi


def build(softening):
    sim = rebound.Simulation()
    sim.add(m=1.0)
    sim.add(m=1e-3, a=1.0, e=0.3)
    sim.add(m=1e-3, a=2.2, e=0.2, inc=0.1)
    sim.add(m=0.0, a=1.5, e=0.5)
    sim.move_to_com()
    sim.softening = softening
    return sim


def main():
    print("| softening | amplification | epsilon | steps | retaken | error | error / (epsilon a n) |")
    print("|---|---|---|---|---|---|---|")
    for softening in (0.0, 0.003, 0.01, 0.03):
        ref = build(softening)
        ref.integrator = "ias15"
        ref.integrator.epsilon = 1e-14
        ref.integrate(T)
        shifted = build(softening)
        shifted.particles[3].x += 1e-12
        shifted.integrator = "ias15"
        shifted.integrator.epsilon = 1e-14
        shifted.integrate(T)
        amplification = math.dist(shifted.particles[3].xyz, ref.particles[3].xyz) / 1e-12
        for epsilon in (1e-8, 1e-10, 1e-12):
            sim = build(softening)
            sim.integrator = "pfvi"
            sim.integrator.epsilon = epsilon
            sim.integrate(T)
            error = math.dist(sim.particles[3].xyz, ref.particles[3].xyz)
            it = sim.integrator
            print(f"| {softening:g} | {amplification:.2g} | {epsilon:g} | {it.n_steps} | {it.n_rejected} | {error:.2g} | "
                  f"{error / (epsilon * 4.5):.2g} |")


if __name__ == "__main__":
    main()
