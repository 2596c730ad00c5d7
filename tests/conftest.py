"""Shared helpers for the rebound_pfvi tests."""
import ctypes
import math
from fractions import Fraction

import pytest
import rebound

import rebound_pfvi  # noqa: F401  (registers "pfvi")


def _python_heartbeat_settable():
    try:
        rebound.Simulation().heartbeat = lambda simp: None
    except AttributeError:
        return False
    return True


#: True where REBOUND's Python Simulation takes a heartbeat: before 5.2.2 its
#: __slots__ have no room for the callback (``sim.heartbeat = f`` raises
#: AttributeError: '_hb'), REBOUND's own limit, not pfvi's.
PYTHON_HEARTBEAT = _python_heartbeat_settable()
needs_python_heartbeat = pytest.mark.skipif(
    not PYTHON_HEARTBEAT, reason=f"rebound {rebound.__version__} cannot set sim.heartbeat from Python (fixed in 5.2.2)")

#: rebound 5.0.0's Python binding declares reb_collision's indices as c_int
#: where the C struct has size_t, so a Python collision_resolve function reads
#: p2 as 0 with any integrator (IAS15's too): REBOUND's limit, not pfvi's.
needs_python_collision_resolve = pytest.mark.skipif(
    ctypes.sizeof(dict(rebound.simulation.CollisionS._fields_)["p1"]) != ctypes.sizeof(ctypes.c_size_t),
    reason=f"rebound {rebound.__version__}'s Python binding reads reb_collision.p2 wrongly")


def particle_bytes(sim):
    """Every byte of every particle: the 'nothing lost' check compares these."""
    size = ctypes.sizeof(rebound.Particle) * sim.N
    return ctypes.string_at(ctypes.addressof(sim._particles.contents), size) if sim.N else b""


def snapshot(sim):
    return sim.t, particle_bytes(sim)


def seed_pfvi(sim):
    """pfvi with the seed's scheme: fitting "phase" with the curvature frequency
    about the origin (the defaults until issue 14; most tests of the seed's
    method were written against it)."""
    sim.integrator = "pfvi"
    sim.integrator.fitting = "phase"
    sim.integrator.frequency = "curvature"
    sim.integrator.centre = "origin"


def fixed_step_pfvi(sim):
    """pfvi with the seed's scheme, fixed steps of sim.dt and the two-point
    scheme (s = 2), unless a test sets others."""
    seed_pfvi(sim)
    sim.integrator.epsilon = 0.
    sim.integrator.stages = 2


def harmonic_oscillator(omega, q0=(1.0, 0.3), v0=(0.2, 0.7), **fields):
    """2-D isotropic oscillator: gravity off, force -omega^2 x from additional_forces."""
    sim = rebound.Simulation()
    sim.gravity = "none"
    sim.add(m=1.0, x=q0[0], y=q0[1], vx=v0[0], vy=v0[1])

    def force(simp):
        p = simp.contents.particles[0]
        p.ax = -omega * omega * p.x
        p.ay = -omega * omega * p.y
        p.az = -omega * omega * p.z

    sim.additional_forces = force
    fixed_step_pfvi(sim)
    sim.integrator.frequency = "fixed"
    sim.integrator.omega = omega
    for name, value in fields.items():
        setattr(sim.integrator, name, value)
    return sim


def exact_phase_cos_sin(n_steps, u):
    """cos and sin of n_steps*u with the product taken exactly.

    Rounding n*u to a double would alone be an error of about n*u*1e-16 in
    the phase (3e-12 at n = 1e4, u = 2.5): as large as what is being tested.
    """
    x = Fraction(n_steps) * Fraction(u)
    hi = float(x)
    lo = float(x - Fraction(hi))
    c, s = math.cos(hi), math.sin(hi)
    return c - s * lo, s + c * lo


def oscillator_exact(omega, n_steps, h, q0, v0):
    """Exact oscillator state after n_steps of h, for omega*h exactly representable."""
    c, s = exact_phase_cos_sin(n_steps, omega * h)
    q = [c * q0[k] + s / omega * v0[k] for k in range(2)]
    v = [-omega * s * q0[k] + c * v0[k] for k in range(2)]
    return q, v


def two_body(m1, a=1.0, e=0.0, com=True, f=0.0):
    sim = rebound.Simulation()
    sim.add(m=1.0)
    sim.add(m=m1, a=a, e=e, f=f)
    if com:
        sim.move_to_com()
    return sim


def two_planets():
    """A star and two planets of 1e-3 (a = 1, e = 0.3; a = 1.7, e = 0.1) under
    pfvi at its defaults, centre of mass at rest: the hostile trials' system
    of the output, copy and archive tests."""
    sim = rebound.Simulation()
    sim.add(m=1.0)
    sim.add(m=1e-3, a=1.0, e=0.3)
    sim.add(m=1e-3, a=1.7, e=0.1)
    sim.move_to_com()
    sim.integrator = "pfvi"
    return sim


def relative_energy_error(sim, E0):
    return abs((sim.energy() - E0) / E0)


#: Step modes for tests that must hold in each: (stages, epsilon, step_control).
STEP_MODES = {
    "fixed-s2": (2, 0.0, "reversible"),
    "fixed-s4": (4, 0.0, "reversible"),
    "seed-s2": (2, 1e-7, "seed"),
    "seed-s4": (4, 1e-7, "seed"),
    "reversible-s2": (2, 1e-7, "reversible"),
    "reversible-s4": (4, 1e-7, "reversible"),
    "symmetric-s2": (2, 1e-7, "symmetric"),
    "symmetric-s4": (4, 1e-7, "symmetric"),
}


def three_bodies(stages, epsilon, step_control="reversible", e=0.3):
    """A star, a planet of 1e-3 (a = 1, eccentricity e) and one of 1e-4 (a = 1.7)
    under pfvi, dt = 0.01: the system of the force-model and refusal tests."""
    sim = rebound.Simulation()
    sim.add(m=1.0)
    sim.add(m=1e-3, a=1.0, e=e)
    sim.add(m=1e-4, a=1.7, e=0.1, primary=sim.particles[0])
    sim.testparticle_hidewarnings = 1
    sim.integrator = "pfvi"
    sim.integrator.stages = stages
    sim.integrator.epsilon = epsilon
    sim.integrator.step_control = step_control
    sim.dt = 0.01
    return sim
