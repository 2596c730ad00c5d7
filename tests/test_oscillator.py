"""The fitted scheme on its test Lagrangian, the harmonic oscillator (seed section 3)."""
import math

import pytest
import rebound_pfvi

from conftest import harmonic_oscillator, oscillator_exact

Q0, V0 = (1.0, 0.3), (0.2, 0.7)
N_STEPS = 10_000


def run(u, fitting, v0, **fields):
    # omega = 1 makes omega*h = h exactly, so the reference phase is exact.
    sim = harmonic_oscillator(1.0, Q0, v0, fitting=fitting, **fields)
    sim.dt = u
    sim.steps(N_STEPS)
    q, v = oscillator_exact(1.0, N_STEPS, u, Q0, V0)
    p = sim.particles[0]
    return sim, (p.x, p.y), (p.vx, p.vy), q, v


def rel(a, b):
    return math.hypot(a[0] - b[0], a[1] - b[1]) / math.hypot(*b)


@pytest.mark.parametrize("u", [0.1, 1.0, 2.5])
def test_phase_is_exact_in_positions_and_momenta(u):
    # u = 2.5 lies beyond the default u_max = 1 and beyond the pole at pi/2.
    sim, q, v, q_exact, v_exact = run(u, "phase", V0, u_max=3.0)
    assert sim.integrator.n_u_limited == 0
    assert rel(q, q_exact) < 1e-12
    assert rel(v, v_exact) < 1e-12


@pytest.mark.parametrize("u", [0.1, 1.0, 2.5])
def test_phase_literal_scales_momenta_by_gamma(u):
    g = rebound_pfvi.gamma(u)
    assert g == pytest.approx(u / math.tan(u), rel=1e-15)
    # Started on the literal scheme's own momentum, gamma times the true one,
    # its positions are exact and its momenta stay gamma times too large.
    sim, q, v, q_exact, v_exact = run(u, "phase-literal", (g * V0[0], g * V0[1]), u_max=3.0)
    assert rel(q, q_exact) < 1e-12
    for k in range(2):
        assert v[k] / v_exact[k] == pytest.approx(g, rel=1e-11)


@pytest.mark.parametrize("u, measured", [(0.1, 1.93e-3), (1.0, 1.10e-1), (2.5, 1.07)])
def test_phase_literal_from_exact_momenta_is_not_exact(u, measured):
    # Fed the true momentum, the printed Ld starts on the wrong trajectory.
    _, q, _, q_exact, _ = run(u, "phase-literal", V0, u_max=3.0)
    assert rel(q, q_exact) == pytest.approx(measured, rel=0.02)


def test_u_beyond_u_max_is_limited_and_counted():
    # u = 1.5 is limited to u_max = 1 (omega 1/1.5 against the motion's 1);
    # the step so fitted is still stable (half trace -0.28).
    sim = harmonic_oscillator(1.0, Q0, V0)
    sim.dt = 1.5
    sim.steps(100)
    assert sim.integrator.u_max == 1.0
    assert sim.integrator.n_u_limited == 100
    assert sim.integrator.omega_max == pytest.approx(1.0 / 1.5, rel=1e-15)
    assert math.hypot(sim.particles[0].x, sim.particles[0].y) < 2 * math.hypot(*Q0)


def test_a_limited_fit_that_cannot_follow_the_motion_is_refused():
    # At dt = 2.5 the limited omega = 0.4 leaves the pull (W h = 2.5, beyond
    # even Verlet's 2) to the residual: half trace -2.9, a growth of 5.7 per
    # step, which ran silently to 1e75 in 100 steps; now the first step is
    # refused.
    sim = harmonic_oscillator(1.0, Q0, V0)
    sim.dt = 2.5
    with pytest.raises(RuntimeError, match=r"particle 0: the 2-stage step fitted to the fixed omega = 0\.4 is "
                       r"unstable at dt = 2\.5 against the pull it feels \(frequency 1\): a deviation grows by a "
                       r"factor 1 \+ 4\.6"):
        sim.steps(100)
    assert sim.t == 0.0 and (sim.particles[0].x, sim.particles[0].y) == Q0
