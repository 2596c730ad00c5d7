"""Where a fresh step track starts (pfvi_control.c, pericentre_start;
docs/step-control.md, "Where a track starts"): at the state, on the curve
the track begun at the leading orbit's last pericentre follows.

The start lambda sigma + kappa g/2 the build before took put a track begun
away from pericentre on a curve about 8% below the density, and near a whole
number of steps per orbit the orbits' errors added up (benchmarks/
commensurate_steps.py --sweep). Each case below is among the sweep's worst
for the build before.
"""
import math

import pytest
import rebound

import rebound_pfvi  # noqa: F401

ORBITS = 100.37


def pair(e, M):
    sim = rebound.Simulation()
    sim.add(m=1.0)
    sim.add(m=1e-3, a=1.0, e=e, M=M)
    sim.move_to_com()
    return sim


def relative(sim):
    p = sim.particles
    return (p[1].x - p[0].x, p[1].y - p[0].y, p[1].z - p[0].z)


def error_per_orbit(e, M, epsilon):
    """The final relative position error against the exact two-body orbit
    over ORBITS orbits, per orbit, in units of epsilon a (a = 1)."""
    sim = pair(e, M)
    orbit = sim.particles[1].orbit(primary=sim.particles[0])
    t_end = ORBITS * orbit.P
    reference = rebound.Simulation()
    reference.add(m=1.0)
    reference.add(m=1e-3, a=orbit.a, e=orbit.e, omega=orbit.omega, M=orbit.M + orbit.n * t_end)
    sim.integrator = "pfvi"
    sim.integrator.epsilon = epsilon
    sim.integrate(t_end)
    return math.dist(relative(sim), relative(reference)) / (epsilon * ORBITS)


# (e, starting mean anomaly, epsilon, the largest error per orbit allowed):
# the build before ended 66, 23, 13 and 31 epsilon a per orbit off (measured
# 2026-11-27; this build 0.066, 0.29, 0.32 and 1.02, the last ending just
# past pericentre, where a phase error shows most).
@pytest.mark.parametrize("e, M, epsilon, bound", [
    (0.71, 5 * math.pi / 4, 3e-8, 1.0),
    (0.84, 5 * math.pi / 4, 1e-8, 1.0),
    (0.81, 5 * math.pi / 4, 1e-8, 1.0),
    (0.705, 5 * math.pi / 4, 1e-7, 2.0),
])
def test_a_pair_near_a_whole_number_of_steps_per_orbit_stays_within_epsilon(e, M, epsilon, bound):
    assert error_per_orbit(e, M, epsilon) < bound


def test_the_starting_phase_no_longer_sets_the_steps_per_orbit():
    # e = 0.77 at 1e-7 over 20 orbits from 8 phases: 9.95 ... 11.0 steps per
    # orbit before (11.0 from pericentre), 10.85 ... 11.0 now.
    counts = []
    for k in range(8):
        sim = pair(0.77, 2 * math.pi * k / 8)
        period = sim.particles[1].orbit(primary=sim.particles[0]).P
        sim.integrator = "pfvi"
        sim.integrator.epsilon = 1e-7
        sim.integrate(20 * period)
        counts.append(sim.integrator.n_steps / 20)
    assert max(counts) / min(counts) < 1.03


def positions(sim):
    return [(p.x, p.y, p.z) for p in sim.particles]


@pytest.mark.parametrize("steps", [1, 2, 40])
def test_a_flip_after_a_start_on_the_pericentre_curve_comes_back_to_it(steps):
    # The fresh track's first interval begins at the state (a grid point),
    # so a reversal ends there as it did before.
    sim = pair(0.6, 3.0)
    sim.integrator = "pfvi"
    start = positions(sim)
    sim.steps(steps)
    assert sim.integrator.n_asymmetric == 0
    sim.dt = -sim.dt
    sim.steps(steps)
    assert abs(sim.t) < 1e-13
    assert max(math.dist(a, b) for a, b in zip(start, positions(sim))) < 1e-13


def test_a_long_round_trip_from_a_start_on_the_pericentre_curve():
    # 20940 steps out at s = 4 and back (a first version placed the start
    # inside an interval and logged its first step; the log's ring dropped
    # it and the way back ended 8.3e-8 off).
    sim = rebound.Simulation()
    sim.add(m=1.0)
    sim.add(m=1e-3, a=1.0, e=0.99, f=math.pi / 4)
    sim.move_to_com()
    sim.integrator = "pfvi"
    sim.integrator.stages = 4
    start = positions(sim)
    sim.integrate(400.0)
    assert sim.integrator.n_steps > 16 * 1024
    sim.integrate(0.0)
    scale = max(math.hypot(*x) for x in start)
    assert max(math.dist(a, b) for a, b in zip(start, positions(sim))) / scale < 1e-10


def test_an_edit_every_few_steps_does_not_let_the_error_grow():
    # A hostile trial of the first version (which placed each fresh track
    # inside an interval of the pericentre track's grid): a mass changed by
    # 1e-15 every 4th step restarted the track there each time, and e = 0.7
    # at 1e-8 ended 9.4 and 87 epsilon a per orbit off after 300 and 3000
    # time units (the build before: 1.26, 1.17; this build 0.13, 0.12).
    def run(t_end):
        sim = pair(0.7, math.pi / 2 + 0.05)
        sim.particles[1].inc = 0.2
        orbit = sim.particles[1].orbit(primary=sim.particles[0])
        sim.integrator = "pfvi"
        sim.integrator.epsilon = 1e-8
        count = [0]

        def edit(simp):
            count[0] += 1
            if count[0] % 4 == 0:
                simp.contents.particles[1].m *= (1 + 1e-15) if count[0] % 8 else (1 - 1e-15)
        sim.post_timestep_modifications = edit
        sim.integrate(t_end)
        reference = rebound.Simulation()
        reference.add(m=1.0)
        reference.add(m=1e-3, a=orbit.a, e=orbit.e, inc=orbit.inc, Omega=orbit.Omega, omega=orbit.omega,
                      M=orbit.M + orbit.n * t_end)
        return math.dist(relative(sim), relative(reference)) / (1e-8 * t_end / orbit.P)
    assert run(1000.0) < 1.0
