"""Quick start: an eccentric orbit with pfvi at its defaults, and what it counted.

    python examples/quickstart.py
"""
import rebound

import rebound_pfvi  # registers "pfvi"

sim = rebound.Simulation()
sim.add(m=1.0)
sim.add(m=1e-3, a=1.0, e=0.5)
sim.move_to_com()
E0 = sim.energy()

sim.integrator = "pfvi"
# The defaults (rebound_pfvi.DEFAULTS, from the C core): s = 8 Gauss-Lobatto
# nodes (order 14), no fitting, adaptive time-symmetric steps with epsilon =
# 1e-6, the position error per orbit relative to the orbit's size. No sim.dt
# is needed; epsilon = 0 would take fixed steps of sim.dt instead.
print("defaults:", rebound_pfvi.DEFAULTS)
sim.integrate(10 * sim.particles[1].P)

print(repr(sim.integrator))
print(f"steps per orbit: {sim.integrator.n_steps / 10:.0f}, force evaluations per step: "
      f"{sim.integrator.n_force_evaluations / sim.integrator.n_steps:.1f}, steps retaken: "
      f"{sim.integrator.n_rejected}")
print(f"relative energy error after 10 orbits: {abs(sim.energy() / E0 - 1):.2e}")
