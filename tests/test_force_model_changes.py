"""Issue 17: the force model changed without a new integrate() call, a
callback that adds or removes particles mid-step, and magnitudes at the edge
of the doubles.

A steps() or heartbeat boundary must give the trajectory a fresh integrate()
from the same state gives, to the bit; a refused step puts back t and every
particle still there; no quantity over- or underflows into a silently wrong
result.
"""
import ctypes
import math

import pytest
import rebound

from conftest import STEP_MODES, needs_python_heartbeat, particle_bytes, snapshot, three_bodies

#: Every step mode of the fault tests, and the other stage counts with fixed steps.
MODES = dict(STEP_MODES, **{f"fixed-s{s}": (s, 0.0, "reversible") for s in (3, 5, 6)})


def pair(mode, e=0.3, setup=None):
    sim = three_bodies(*MODES[mode], e=e)
    if setup:
        setup(sim)
    return sim


def soften(sim):
    sim.softening = 0.3


def push(sim):
    def force(simp):
        simp.contents.particles[1].ax += 0.05

    sim.additional_forces = force


def activate_fewer(sim):
    sim.N_active = 2


def make_test_particles_pull(sim):
    sim.testparticle_type = 1


def gravity_off(sim):
    sim.gravity = "none"


def stronger_G(sim):
    sim.G = 1.5


# (set up at the start, changed mid-run)
CHANGES = {
    "softening": (None, soften),
    "additional_forces": (None, push),
    "N_active": (None, activate_fewer),
    "testparticle_type": (activate_fewer, make_test_particles_pull),
    "gravity": (None, gravity_off),
    "G": (None, stronger_G),
}


def numbers(sim):
    """The bytes of every particle's doubles (x ... r): equal across two
    simulations only if their trajectories agree to the bit (the pointers
    that follow differ between simulations)."""
    size, doubles = ctypes.sizeof(rebound.Particle), 11 * 8
    data = particle_bytes(sim)
    return [data[k * size:k * size + doubles] for k in range(sim.N)]


def continue_fresh(sim, t_end):
    """What a fresh integrate() from sim's state gives, stopping where t_end was reached."""
    sim.integrate(t_end, exact_finish_time=0)


@pytest.mark.parametrize("mode", MODES)
@pytest.mark.parametrize("change", CHANGES)
def test_a_force_model_change_between_steps_calls_equals_a_fresh_integrate(mode, change):
    # The repro: steps(37); softening = 0.3; steps(20) reused the
    # start force of the old model (4.9e-5 in x after one step at s = 2).
    setup, apply = CHANGES[change]
    a, b = pair(mode, setup=setup), pair(mode, setup=setup)
    for sim in (a, b):
        sim.steps(37)
        apply(sim)
    a.steps(20)
    continue_fresh(b, a.t)
    assert b.t == a.t
    assert numbers(b) == numbers(a)
    # The change matters: without it the trajectory is another one.
    unchanged = pair(mode, setup=setup)
    unchanged.steps(57)
    assert numbers(unchanged) != numbers(a)


@needs_python_heartbeat
@pytest.mark.parametrize("mode", MODES)
@pytest.mark.parametrize("change", ["softening", "additional_forces", "G"])
def test_a_force_model_change_in_a_heartbeat_equals_a_fresh_integrate(mode, change):
    apply = CHANGES[change][1]
    a = pair(mode)

    def heartbeat(simp):
        done = simp.contents.steps_done
        if done == 37:
            apply(a)
        elif done == 57:
            a.stop()

    a.heartbeat = heartbeat
    a.integrate(1e9, exact_finish_time=0)
    b = pair(mode)
    b.steps(37)
    apply(b)
    continue_fresh(b, a.t)
    assert (a.steps_done, b.steps_done) == (57, 57)
    assert b.t == a.t
    assert numbers(b) == numbers(a)
    reference = pair(mode)
    reference.steps(57)
    assert numbers(reference) != numbers(a)


@needs_python_heartbeat
@pytest.mark.parametrize("mode", ["fixed-s2", "fixed-s4"])
def test_the_start_force_is_reused_only_within_one_call_without_a_heartbeat(mode):
    # What the check costs: one force evaluation per steps() call, and one per
    # step under a heartbeat; none per step otherwise.
    one = pair(mode)
    one.steps(30)
    three = pair(mode)
    for _ in range(3):
        three.steps(10)
    beating = pair(mode)
    beating.heartbeat = lambda simp: None
    beating.steps(30)
    evaluations = one.integrator.n_force_evaluations
    assert three.integrator.n_force_evaluations == evaluations + 2
    assert beating.integrator.n_force_evaluations == evaluations + 29
    assert numbers(three) == numbers(one) == numbers(beating)
    if MODES[mode][0] == 2:
        assert evaluations == 30 + 1


def adds_during(sim, after):
    calls = {"n": 0}

    def force(simp):
        calls["n"] += 1
        if calls["n"] == after:
            sim.add(m=1e-6, a=3.0)

    sim.additional_forces = force


def removes_during(sim, after, index=1):
    calls = {"n": 0}

    def force(simp):
        calls["n"] += 1
        if calls["n"] == after:
            sim.remove(index)

    sim.additional_forces = force


def particle_records(sim):
    size = ctypes.sizeof(rebound.Particle)
    data = particle_bytes(sim)
    return [data[k * size:(k + 1) * size] for k in range(sim.N)]


def step_until_refused(sim, match):
    """Steps one at a time until a step is refused; returns t and the
    particles' bytes at the start of the refused step."""
    with pytest.raises(RuntimeError, match=match):
        for _ in range(100):
            t0, before = sim.t, particle_records(sim)
            sim.steps(1)
    return t0, before


@pytest.mark.parametrize("mode", MODES)
@pytest.mark.parametrize("after", [1, 2, 5])
@pytest.mark.parametrize("index", [0, 1, 2])
def test_a_callback_removing_a_particle_restores_t_and_every_survivor(mode, after, index):
    # The repro: t was restored but the survivors stayed at their
    # trial positions (particle 1's x 0.93233 -> 0.93133).
    sim = pair(mode)
    sim.integrate(0.37)
    removes_during(sim, after, index)
    t0, before = step_until_refused(sim, r"number of particles from 3 to 2 .* t and the 2 particles still "
                                         r"present are restored to the step's start, 1 removed are gone")
    assert sim.t == t0
    assert particle_records(sim) == before[:index] + before[index + 1:]


@pytest.mark.parametrize("mode", MODES)
@pytest.mark.parametrize("after", [1, 2, 5])
def test_a_callback_adding_a_particle_restores_t_and_every_particle_it_had(mode, after):
    sim = pair(mode)
    sim.integrate(0.37)
    adds_during(sim, after)
    t0, before = step_until_refused(sim, r"from 3 to 4 .* the 3 particles still present are restored .* "
                                         r"0 removed are gone, 1 added are kept")
    assert sim.t == t0
    assert particle_records(sim)[:3] == before
    assert sim.particles[3].m == 1e-6


def flyer(stages, dt, vy=1e160):
    sim = rebound.Simulation()
    sim.add(m=1.0)
    sim.add(m=1e-3, x=1.0, vy=vy)
    sim.integrator = "pfvi"
    sim.integrator.stages = stages
    sim.integrator.epsilon = 0.0
    sim.dt = dt
    return sim


def straight_flyby(t, vy):
    """Planet passing a unit mass (G = 1) at closest distance 1 with speed
    vy, so fast that its path is straight: its x and vx at t."""
    u = vy * t
    root = math.sqrt(1.0 + u * u)
    vx = -(1.0 / vy) * u / root
    x = 1.0 - (1.0 / vy) * (1.0 / vy) * (u * u / (root + 1.0))
    return x, vx


def test_a_speed_beyond_the_squares_range_keeps_the_two_point_step_exact():
    # The repro: |v|^2 overflowed, omega was NaN and "limited":
    # s = 4 finished with x 1 -> 1.149 and vx 3e167, s = 2 blamed a
    # coincident particle. The curvature frequency is now scaled.
    sim = flyer(2, 1e-170)
    sim.integrate(1e-168)
    x, vx = straight_flyby(sim.t, 1e160)
    assert sim.particles[1].x == pytest.approx(x, rel=1e-15)
    assert sim.particles[1].vx == pytest.approx(vx, rel=1e-6)
    assert sim.particles[1].y == pytest.approx(1e160 * sim.t, rel=1e-12)


@pytest.mark.parametrize("stages", [3, 4, 5, 6])
def test_a_step_whose_square_underflows_is_refused_by_the_stage_schemes(stages):
    sim = flyer(stages, 1e-170)
    before = snapshot(sim)
    with pytest.raises(RuntimeError, match=r"dt = 1e-170: dt\^2 underflows .* state restored"):
        sim.integrate(1e-168)
    assert snapshot(sim) == before


@pytest.mark.parametrize("stages", [2, 3, 4, 5, 6])
@pytest.mark.parametrize("fitting", ["phase", "none"])
def test_huge_speeds_with_representable_squares_of_dt_integrate_correctly(stages, fitting):
    sim = flyer(stages, 1e-150, vy=1e155)
    sim.integrator.fitting = fitting
    sim.integrate(1e-148)
    x, vx = straight_flyby(sim.t, 1e155)
    assert sim.particles[1].vx == pytest.approx(vx, rel=1e-6)
    assert sim.particles[1].x == pytest.approx(x, abs=1e-14)
    # The star, nearly at rest and turning sharply, has omega ~ 1e136.
    assert sim.integrator.omega_max < 1e150 or fitting == "none"
