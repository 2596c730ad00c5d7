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
sim.dt = sim.particles[1].P / 2000
sim.integrate(10 * sim.particles[1].P)

print(repr(sim.integrator))
print(f"relative energy error after 10 orbits: {abs(sim.energy() / E0 - 1):.2e}")
print(f"omega of the last step: {sim.integrator.omega_min:.3f} .. {sim.integrator.omega_max:.3f}")
