"""Quick start: an eccentric orbit with pfvi, its options and statistics.

    python examples/quickstart.py
"""
import rebound

import rebound_pfvi  # noqa: F401  (registers "pfvi")

sim = rebound.Simulation()
sim.add(m=1.0)
sim.add(m=1e-3, a=1.0, e=0.5)
sim.move_to_com()
E0 = sim.energy()

sim.integrator = "pfvi"
sim.integrator.fitting = "phase"
# Steps are adaptive by default (epsilon = 1e-6, step_control "reversible",
# stages = 4); set sim.integrator.epsilon = 0 for fixed steps of sim.dt.
sim.integrate(10 * sim.particles[1].P)

print(repr(sim.integrator))
print(f"steps per orbit: {sim.integrator.n_steps / 10:.0f}, trial steps per step: "
      f"{sim.integrator.n_attempts / sim.integrator.n_steps:.2f}")
print(f"relative energy error after 10 orbits: {abs(sim.energy() / E0 - 1):.2e}")
print(f"omega of the last step: {sim.integrator.omega_min:.3f} .. {sim.integrator.omega_max:.3f}")
