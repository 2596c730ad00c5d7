"""A fixed frequency far from the motion's (issue 27 item 3), measured:
docs/method.md's table "A fixed frequency far from the motion's".

    python -P benchmarks/fixed_frequency.py

Sun and planet (a = 1, e = 0.5, G = 1, as added: Sun at the origin),
frequency "fixed", epsilon 0, dt = 1e-3: the energy error at 6 and 60 time
units, or where the step was refused as unstable (t and the planet's
distance). B = omega tan(u/2) for s = 2; for s >= 3 the same from the
free particle's half trace (t - 1 = B^2 h^2/2 to leading order), which the
refusal message reports as the growth factor 1 + g (t - 1 ~ g^2/2).
"""
import math
import re

import rebound

import rebound_pfvi  # noqa: F401

CASES = [(2, "phase", 20.0), (2, "phase", 21.0), (2, "phase", 22.0), (2, "phase", 30.0), (2, "phase", 50.0),
         (4, "phase", 450.0), (4, "phase", 500.0), (4, "phase", 1000.0), (6, "phase", 1000.0)]


def build(stages, fitting, omega, dt=1e-3):
    sim = rebound.Simulation()
    sim.G = 1.0
    sim.add(m=1.0)
    sim.add(m=1e-3, a=1.0, e=0.5)
    sim.integrator = "pfvi"
    sim.dt = dt
    sim.integrator.stages = stages
    sim.integrator.fitting = fitting
    sim.integrator.frequency = "fixed"
    sim.integrator.omega = omega
    sim.integrator.epsilon = 0.0
    return sim


def free_particle_B(stages, omega, dt):
    """B from the refusal of a free particle's step (W = 0), or 0 if it runs."""
    sim = rebound.Simulation()
    sim.add(m=0.0, x=1.0, vy=1.0)
    sim.integrator = "pfvi"
    sim.dt = dt
    sim.integrator.stages = stages
    sim.integrator.fitting = "phase"
    sim.integrator.frequency = "fixed"
    sim.integrator.omega = omega
    sim.integrator.epsilon = 0.0
    sim.integrator.u_max = 3.0
    try:
        sim.steps(1)
        return 0.0
    except RuntimeError as error:
        g = float(re.search(r"factor 1 \+ ([0-9.e+-]+)", str(error)).group(1))
        return g / dt  # t - 1 = g^2/2 = B^2 h^2/2 to leading order


def main():
    print("| stages | omega | u | B | energy error (6, 60) |")
    print("|---|---|---|---|---|")
    for stages, fitting, omega in CASES:
        dt = 1e-3
        u = min(omega * dt, 1.0)
        B = omega * math.tan(u / 2) if stages == 2 else free_particle_B(stages, u / dt, dt)
        sim = build(stages, fitting, omega, dt)
        E0 = sim.energy()
        out = []
        for T in (6.0, 60.0):
            try:
                sim.integrate(T)
                out.append(f"{abs(sim.energy() / E0 - 1):.2g}")
            except RuntimeError:
                p = sim.particles
                r = math.dist(p[0].xyz, p[1].xyz)
                out.append(f"refused at t = {sim.t:.2g} (r = {r:.2g}, energy error {abs(sim.energy() / E0 - 1):.2g})")
                break
        print(f"| {stages} | {omega:g} | {u:g} | {B:.2g} | {', '.join(out)} |")


if __name__ == "__main__":
    main()
