"""fitting 'none' is velocity Verlet; fixed steps are time-reversible."""
import math

import pytest

from conftest import fixed_step_pfvi, snapshot, two_body


def test_none_equals_velocity_verlet():
    sim = two_body(1e-3, e=0.5, com=True)
    fixed_step_pfvi(sim)
    sim.integrator.fitting = "none"
    h = 0.01
    sim.dt = h
    G = sim.G
    m = [p.m for p in sim.particles]
    x = [[p.x, p.y, p.z] for p in sim.particles]
    v = [[p.vx, p.vy, p.vz] for p in sim.particles]

    def acc(x):
        d = [x[1][k] - x[0][k] for k in range(3)]
        r3 = math.sqrt(sum(c * c for c in d)) ** 3
        return [[G * m[1] * d[k] / r3 for k in range(3)], [-G * m[0] * d[k] / r3 for k in range(3)]]

    a = acc(x)
    for _ in range(500):
        for i in range(2):
            for k in range(3):
                v[i][k] += 0.5 * h * a[i][k]
                x[i][k] += h * v[i][k]
        a = acc(x)
        for i in range(2):
            for k in range(3):
                v[i][k] += 0.5 * h * a[i][k]
    sim.steps(500)
    for i, p in enumerate(sim.particles):
        for k, name in enumerate("xyz"):
            assert getattr(p, name) == pytest.approx(x[i][k], rel=1e-14, abs=1e-14)
            assert getattr(p, "v" + name) == pytest.approx(v[i][k], rel=1e-14, abs=1e-14)


def round_trip(sim, n):
    start = [(p.x, p.y, p.z, p.vx, p.vy, p.vz) for p in sim.particles]
    sim.steps(n)
    sim.dt = -sim.dt
    sim.steps(n)
    return max(abs(a - b) for p, s in zip(sim.particles, start)
               for a, b in zip((p.x, p.y, p.z, p.vx, p.vy, p.vz), s))


def e05_round_trip(fitting, frequency, n):
    sim = two_body(1e-3, e=0.5, com=True)
    fixed_step_pfvi(sim)
    sim.integrator.fitting = fitting
    sim.integrator.frequency = frequency
    sim.integrator.omega = 1.0
    sim.dt = 2 * math.pi / 500
    return round_trip(sim, n)


@pytest.mark.parametrize("fitting, frequency", [("none", "curvature"), ("phase", "fixed")])
def test_fixed_step_round_trip_returns_to_start(fitting, frequency):
    # 10 orbits at e = 0.5 and back; measured 9.6e-14 (none) and 4.5e-14 (phase).
    assert e05_round_trip(fitting, frequency, 5000) < 1e-12


@pytest.mark.parametrize("stages", [3, 4, 5, 6, 7, 8])
@pytest.mark.parametrize("fitting, frequency", [("none", "curvature"), ("phase", "fixed"),
                                                ("phase-literal", "fixed")])
def test_stage_solve_round_trip_returns_to_start(stages, fitting, frequency):
    # Lobatto nodes are symmetric, so with a fixed omega the step is a
    # symmetric map; the solve is converged to round-off (stopped once the
    # change stops falling). 10 orbits at e = 0.5, 100 steps per orbit, and
    # back: measured 5.5e-14 to 1.1e-12 (before the classical form of
    # docs/roundoff.md).
    sim = two_body(1e-3, e=0.5, com=True)
    fixed_step_pfvi(sim)
    sim.integrator.stages = stages
    sim.integrator.fitting = fitting
    sim.integrator.frequency = frequency
    sim.integrator.omega = 1.0
    sim.dt = 2 * math.pi / 100
    assert round_trip(sim, 1000) < 2e-12


def test_phase_literal_round_trip_is_limited_by_its_momentum_rescaling():
    # v/gamma, then gamma*v every step, without compensated sums: measured 7.5e-12.
    assert e05_round_trip("phase-literal", "fixed", 5000) < 1.5e-11


@pytest.mark.parametrize("n, measured", [(500, 1.36e-4), (5000, 1.36e-2)])
def test_curvature_frequency_breaks_reversibility_by_a_measured_amount(n, measured):
    # omega is estimated at the start of each step, so a backward step does
    # not reuse the forward step's omega: the map is not symmetric. The
    # departure grows as t^2 (1 and 10 orbits at e = 0.5, 500 steps per orbit).
    assert e05_round_trip("phase", "curvature", n) == pytest.approx(measured, rel=0.1)


def test_backward_integration_mirrors_forward():
    fwd = two_body(1e-3, e=0.3, com=True)
    bwd = two_body(1e-3, e=0.3, com=True)
    for sim in (fwd, bwd):
        fixed_step_pfvi(sim)
        sim.dt = 0.01
    for p in bwd.particles:
        p.vx, p.vy, p.vz = -p.vx, -p.vy, -p.vz
    fwd.integrate(3.0)
    bwd.integrate(-3.0)
    assert bwd.t == -3.0 and fwd.t == 3.0
    for a, b in zip(fwd.particles, bwd.particles):
        assert (a.x, a.y, a.z) == pytest.approx((b.x, b.y, b.z), abs=1e-13)
        assert (a.vx, a.vy, a.vz) == pytest.approx((-b.vx, -b.vy, -b.vz), abs=1e-13)


def test_exact_finish_time_lands_on_t():
    sim = two_body(1e-3, e=0.3, com=True)
    fixed_step_pfvi(sim)
    sim.dt = 0.03
    sim.integrate(1.0)
    assert sim.t == 1.0
    assert sim.dt == 0.03  # REBOUND restores the full step after the shortened last one
    t, _ = snapshot(sim)
    sim.integrate(1.0)
    assert sim.t == t
