"""Property tests (hypothesis): random orbits, masses and options.

Whatever the input, a step either finishes with every particle finite or is
refused with an error and changes nothing; no crash, no hang. With fixed
steps and a time-symmetric fit, forward then back returns to the start.
"""
import faulthandler
import math

import pytest
import rebound
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

from conftest import snapshot

# No example database in the working directory; the same examples on every run.
SETTINGS = dict(database=None, derandomize=True, deadline=None,
                suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much])
HANG_SECONDS = 120  # per test: a hang aborts with every thread's traceback


@pytest.fixture(autouse=True)
def no_hang():
    faulthandler.dump_traceback_later(HANG_SECONDS, exit=True)
    yield
    faulthandler.cancel_dump_traceback_later()


log_uniform = lambda lo, hi: st.floats(lo, hi).map(lambda x: 10.0 ** x)  # noqa: E731

orbit = st.fixed_dictionaries({
    "m": st.one_of(st.just(0.0), log_uniform(-12, 0)),
    "a": st.floats(0.2, 5.0),
    "e": st.one_of(st.floats(0.0, 0.999), st.sampled_from([0.0, 0.99, 0.999])),
    "inc": st.floats(0.0, math.pi),
    "Omega": st.floats(0.0, 2 * math.pi),
    "omega": st.floats(0.0, 2 * math.pi),
    "f": st.floats(-math.pi, math.pi),
})

options = st.fixed_dictionaries({
    "stages": st.integers(2, 6),
    "fitting": st.sampled_from(["phase", "phase-literal", "none"]),
    "frequency": st.sampled_from(["curvature", "fixed"]),
    "omega": st.one_of(st.just(0.0), log_uniform(-2, 2)),
    "u_max": st.floats(0.05, 3.1),
    "epsilon": st.one_of(st.just(0.0), log_uniform(-10, -3)),
    "step_control": st.sampled_from(["seed", "reversible"]),
})


def build(central, orbits, opts, dt_fraction, com):
    sim = rebound.Simulation()
    sim.add(m=central)
    for o in orbits:
        sim.add(primary=sim.particles[0], **o)
    if com:
        sim.move_to_com()
    sim.integrator = "pfvi"
    for name, value in opts.items():
        setattr(sim.integrator, name, value)
    period = 2 * math.pi * math.sqrt(min(o["a"] for o in orbits) ** 3 / central)
    sim.dt = dt_fraction * period
    return sim


def finite(sim):
    return all(math.isfinite(getattr(p, f)) for p in sim.particles
               for f in ("x", "y", "z", "vx", "vy", "vz", "ax", "ay", "az", "m"))


@settings(max_examples=1000, **SETTINGS)
@given(central=log_uniform(-3, 1), orbits=st.lists(orbit, min_size=1, max_size=3, unique_by=lambda o: (o["a"], o["f"])), opts=options,
       dt_fraction=log_uniform(-5, 0), com=st.booleans(), n_steps=st.integers(1, 12),
       backward=st.booleans())
def test_a_step_finishes_finite_or_is_refused_unchanged(central, orbits, opts, dt_fraction, com, n_steps, backward):
    sim = build(central, orbits, opts, dt_fraction, com)
    if backward:
        sim.dt = -sim.dt
    for _ in range(n_steps):
        before = snapshot(sim)
        try:
            sim.steps(1)
        except RuntimeError as error:
            assert str(error).startswith("pfvi: ")
            assert snapshot(sim) == before
            return
        assert finite(sim)
        assert sim.t != before[0]


@settings(max_examples=300, **SETTINGS)
@given(m=st.one_of(st.just(0.0), log_uniform(-12, 0)), e=st.floats(0.0, 0.9), f=st.floats(-math.pi, math.pi),
       stages=st.integers(2, 6), fitting=st.sampled_from(["phase", "phase-literal", "none"]),
       steps_per_orbit=st.integers(50, 2000), n_steps=st.integers(1, 50), omega=st.floats(0.0, 2.0))
def test_forward_then_back_returns_to_the_start(m, e, f, stages, fitting, steps_per_orbit, n_steps, omega):
    # Fixed steps with a fixed frequency: the map is symmetric, and only
    # round-off separates the return from the start. (The curvature
    # frequency is taken at the start of a step and is not symmetric: that
    # round trip is measured in test_verlet_and_reversibility.py.)
    sim = rebound.Simulation()
    sim.add(m=1.0)
    sim.add(m=m, a=1.0, e=e, f=f)
    sim.move_to_com()
    sim.integrator = "pfvi"
    sim.integrator.stages = stages
    sim.integrator.fitting = fitting
    sim.integrator.frequency = "fixed"
    sim.integrator.omega = omega
    sim.integrator.epsilon = 0.0
    sim.dt = 2 * math.pi / steps_per_orbit
    start = [(p.x, p.y, p.z, p.vx, p.vy, p.vz) for p in sim.particles]
    try:
        sim.steps(n_steps)
        sim.dt = -sim.dt
        sim.steps(n_steps)
    except RuntimeError:
        # Refused (a stage solve not converging near pericentre at coarse
        # steps): covered by the test above; not a round trip.
        assume(False)
    v_scale = math.sqrt((1 + e) / (1 - e))  # pericentre speed
    for p, q in zip(sim.particles, start):
        assert max(abs(p.x - q[0]), abs(p.y - q[1]), abs(p.z - q[2])) < 1e-11
        assert max(abs(p.vx - q[3]), abs(p.vy - q[4]), abs(p.vz - q[5])) < 1e-11 * v_scale
