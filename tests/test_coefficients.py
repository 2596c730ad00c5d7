"""The closed-form step equals the seed's position-momentum equations."""
import math

import pytest
import rebound

import rebound_pfvi
from conftest import fixed_step_pfvi


def seed_step(q0, v0, h, omega, force, fitting):
    """One step of p_k = -D1 Ld, p_k+1 = D2 Ld for the seed's two-node Ld, 1-D, unit mass.

    Ld = h/2 [qdot^1^2/2 - V(q0) + qdot^2^2/2 - V(q1)], h qdot^j = B^j q0 + Bbar^j q1,
    with the seed's coefficients at c = 0 and c = 1, divided by gamma for "phase".
    """
    u = omega * h
    b1, bb1, B1, Bb1 = rebound_pfvi.seed_coefficients(u, 0.0)
    b2, bb2, B2, Bb2 = rebound_pfvi.seed_coefficients(u, 1.0)
    assert (b1, bb1, b2, bb2) == pytest.approx((1.0, 0.0, 0.0, 1.0), abs=1e-15)
    g = rebound_pfvi.gamma(u) if fitting == "phase" else 1.0
    # -D1 Ld = -(1/(2h)) sum_j B^j (B^j q0 + Bbar^j q1) - (h/2) F(q0) = g p0, linear in q1.
    sum_BB = B1 * B1 + B2 * B2
    sum_BBb = B1 * Bb1 + B2 * Bb2
    q1 = (-(2 * h) * (g * v0 + 0.5 * h * force(q0)) - sum_BB * q0) / sum_BBb
    # D2 Ld = (1/(2h)) sum_j Bbar^j (B^j q0 + Bbar^j q1) + (h/2) F(q1) = g p1.
    sum_BbBb = Bb1 * Bb1 + Bb2 * Bb2
    v1 = ((sum_BBb * q0 + sum_BbBb * q1) / (2 * h) + 0.5 * h * force(q1)) / g
    return q1, v1


def pfvi_step(q0, v0, h, omega, force, fitting):
    sim = rebound.Simulation()
    sim.gravity = "none"
    sim.add(m=1.0, x=q0, vx=v0)

    def add_force(simp):
        p = simp.contents.particles[0]
        p.ax = force(p.x)

    sim.additional_forces = add_force
    fixed_step_pfvi(sim)
    sim.integrator.fitting = fitting
    sim.integrator.frequency = "fixed"
    sim.integrator.omega = omega
    sim.dt = h
    sim.steps(1)
    return sim.particles[0].x, sim.particles[0].vx


@pytest.mark.parametrize("fitting", ["phase", "phase-literal"])
@pytest.mark.parametrize("u", [0.05, 0.4, 0.9])
@pytest.mark.parametrize("h", [0.1, -0.07])
def test_closed_form_matches_seed_equations(fitting, u, h):
    # An anharmonic force, so that the residual kicks matter; its pull (W^2
    # = 50 near q = 0.8) keeps every (u, h) here within the fixed frequency's
    # stability bound omega tan(u/2) <= W (docs/method.md), which a weaker one
    # (W = 1.35 against omega = 9 at u = 0.9) fails: that step is refused.
    def force(q):
        return -50.0 * q - 0.6 * q ** 3 + 0.2

    omega = abs(u / h)
    expected = seed_step(0.8, -0.35, h, omega, force, fitting)
    got = pfvi_step(0.8, -0.35, h, omega, force, fitting)
    assert got == pytest.approx(expected, rel=1e-12, abs=1e-14)


def test_coefficients_never_nan_near_zero():
    for u in (0.0, 1e-300, 1e-12, 1e-5, 1e-3):
        c = rebound_pfvi.two_point_coefficients(u, 1.0)
        assert all(math.isfinite(x) for k, x in c.items() if k != "limited")
        assert c["half_kick"] == pytest.approx(0.5 * (1 + u * u / 3), rel=1e-15)
        assert c["h_sinc_u"] == pytest.approx(1 - u * u / 6, rel=1e-15)
        assert rebound_pfvi.gamma(u) == pytest.approx(1 - u * u / 3, rel=1e-15)


def test_pole_at_half_pi_is_refused_and_u_max_limits():
    with pytest.raises(ValueError, match="pole"):
        rebound_pfvi.two_point_coefficients(math.pi / 2, 1.0, u_max=3.0)
    c = rebound_pfvi.two_point_coefficients(5.0, 1.0)
    assert c["limited"] and c["omega"] == 1.0
    with pytest.raises(ValueError, match="fitting"):
        rebound_pfvi.two_point_coefficients(1.0, 1.0, fitting="bogus")
