"""Inclined and retrograde bodies inside Jupiter's orbit against IAS15 (issue 40,
item 6): a reduced grid of benchmarks/retrograde_sweep.py (the dense sweep and its
table: docs/step-control.md)."""
import math

import pytest
import rebound

import rebound_pfvi  # noqa: F401  (registers "pfvi")

T = 300.0


def _build(inc, m, a, e, f):
    sim = rebound.Simulation()
    sim.units = ("AU", "yr", "Msun")
    sim.add(m=1.0)
    sim.add(m=9.55e-4, a=5.203, e=0.048, f=1.0, inc=0.02)
    sim.add(m=m, a=a, e=e, f=f, inc=inc, Omega=0.5, omega=0.5)
    sim.move_to_com()
    return sim


def _goal(system, s, eps):
    """The largest position error at T in units of epsilon_effective a n."""
    inc, m, a, e, f = system
    ref = _build(*system)
    ref.integrator = "ias15"
    ref.integrator.epsilon = 1e-11
    ref.integrate(T)
    sim = _build(*system)
    sim.integrator = "pfvi"
    sim.integrator.stages = s
    sim.integrator.epsilon = eps
    sim.integrate(T)
    error = max(math.dist(p.xyz, q.xyz) for p, q in zip(sim.particles[1:], ref.particles[1:]))
    return error / (sim.integrator.epsilon_effective * a * T / math.sqrt(a**3))


# (system (inclination, mass, a, e, f), s, epsilon). The build before the fix
# (547cb7b) failed five of them: 2.3e4, 617, 31, 1.1e4 and 4.5e3 epsilon a n;
# the prograde body and s = 4 are controls.
@pytest.mark.parametrize("system, s, eps", [
    ((math.pi, 1e-5, 3.0, 0.3, 2.0), 8, 1e-10),
    ((math.pi, 0.0, 3.0, 0.0, 2.0), 6, 1e-6),
    ((math.pi / 2, 0.0, 3.0, 0.3, 0.0), 8, 1e-6),
    ((math.pi, 1e-5, 2.0, 0.0, 2.0), 8, 1e-9),
    ((0.0, 0.0, 3.0, 0.3, 0.0), 8, 1e-10),
    ((math.pi, 0.0, 3.0, 0.3, 2.0), 4, 1e-6),
    ((math.pi, 0.0, 3.0, 0.3, 0.0), 8, 1e-6),
    ((2.5, 0.0, 3.0, 0.0, 0.0), 8, 1e-10),
    ((math.pi / 2, 1e-5, 3.0, 0.0, 2.0), 8, 1e-6),
])
def test_inclined_and_retrograde_bodies_within_the_goal(system, s, eps):
    assert _goal(system, s, eps) <= 10.0
