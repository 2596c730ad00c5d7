"""Adaptive steps from osculating circles (seed section 4): both step controls."""
import math

import pytest
import rebound

from conftest import seed_pfvi, snapshot

CONTROLS = ["seed", "reversible"]
FIELDS = ("x", "y", "z", "vx", "vy", "vz", "ax", "ay", "az", "m")


def state(sim):
    """t and every numeric field of every particle, exactly (for comparing two simulations)."""
    return (sim.t.hex(),) + tuple(getattr(p, f).hex() for p in sim.particles for f in FIELDS)


def eccentric(e=0.9, stages=2, fitting="phase", step_control="seed", epsilon=1e-6):
    sim = rebound.Simulation()
    sim.add(m=1.0)
    sim.add(m=1e-3, a=1.0, e=e)
    sim.move_to_com()
    seed_pfvi(sim)
    sim.integrator.stages = stages
    sim.integrator.fitting = fitting
    sim.integrator.step_control = step_control
    sim.integrator.epsilon = epsilon
    return sim


def test_defaults_are_adaptive_and_documented():
    sim = rebound.Simulation()
    sim.integrator = "pfvi"
    assert sim.integrator.epsilon == 1e-6
    assert sim.integrator.step_control == "symmetric"
    assert "osculating" in sim.integrator.__doc__


@pytest.mark.parametrize("step_control", CONTROLS)
@pytest.mark.parametrize("stages", [2, 4])
def test_energy_error_decreases_with_epsilon_over_four_decades(step_control, stages):
    # e = 0.9, one orbit, epsilon = 1e-5 .. 1e-9. Measured (s = 2, phase):
    # seed 8.2e-3, 7.5e-4, 4.7e-5, 4.1e-6, 4.2e-7; reversible 5.3e-3, 7.1e-4,
    # 2.1e-5, 5.8e-7, 7.6e-9. Each decade must gain at least a factor 2.
    errors, steps = [], []
    for k in range(5, 10):
        sim = eccentric(stages=stages, step_control=step_control, epsilon=10.0**-k)
        E0 = sim.energy()
        sim.integrate(sim.particles[1].P)
        errors.append(abs(sim.energy() / E0 - 1))
        steps.append(sim.integrator.n_steps)
    for coarse, fine in zip(errors, errors[1:]):
        assert fine < coarse / 2, errors
    assert steps == sorted(steps), steps


def test_rejected_step_leaves_no_trace():
    # A: the first step is tried too long, rejected, and retried shorter.
    # B: starts with the step A took. Every byte of the particles, t, and the
    # stage predictor (s = 4: the second step starts from it) must agree.
    a = eccentric(stages=4, step_control="seed", epsilon=1e-8)
    b = eccentric(stages=4, step_control="seed", epsilon=1e-8)
    a.dt = 0.5
    a.steps(1)
    assert a.integrator.n_rejected >= 1
    assert a.integrator.n_attempts == a.integrator.n_rejected + 1
    b.dt = a.dt_last_done
    b.steps(1)
    assert b.integrator.n_rejected == 0
    assert state(a) == state(b)
    # Second step: A is again made to try too far first.
    a.dt = 0.5
    a.steps(1)
    assert a.integrator.n_rejected >= 2
    b.dt = a.dt_last_done
    b.steps(1)
    assert b.integrator.n_rejected == 0
    assert state(a) == state(b)
    assert a.integrator.n_iterations == b.integrator.n_iterations


@pytest.mark.parametrize("step_control", CONTROLS)
def test_a_step_no_trial_can_satisfy_is_refused_with_state_untouched(step_control):
    # A force that flips between +1e250 and -1e250 at every evaluation: the
    # s = 4 stage solve cannot converge at any step length the control can
    # reach (60 shrinks of at most 10x), so every trial is refused. (Random
    # force noise does not do it: the seed's estimate moves R and the centre
    # together along the normal and cancels such noise to first order, and a
    # kick flipping the curvature's side makes it abstain, pfvi_osculating.c.)
    sim = eccentric(step_control=step_control, epsilon=1e-9, stages=4)
    sim.integrate(0.3)
    calls = {"n": 0}

    def flip(simp):
        calls["n"] += 1
        simp.contents.particles[1].ay += 1e250 if calls["n"] % 2 else -1e250

    sim.additional_forces = flip
    before = snapshot(sim)
    with pytest.raises(RuntimeError, match=r"(no step from t = .* meets epsilon = 1e-09|reversible step "
                                           r"equation from t = .* was not solved|did not converge|"
                                           r"dt\^2 underflows).*state restored"):
        sim.steps(1)
    assert snapshot(sim) == before


@pytest.mark.parametrize("step_control", CONTROLS)
@pytest.mark.parametrize("stages", [2, 3])
def test_exact_finish_time_lands_on_t_forward_and_backward(step_control, stages):
    sim = eccentric(stages=stages, step_control=step_control)
    for t in (0.1234, 1.0, 2.5, math.pi, -0.7, 0.0):
        sim.integrate(t)
        assert sim.t == t
    # The proposal left in sim.dt is a full step, not the shortened last one.
    assert abs(sim.dt) > 1e-4


@pytest.mark.parametrize("step_control", CONTROLS)
def test_next_step_respects_u_max(step_control):
    sim = eccentric(e=0.0, step_control=step_control)
    sim.integrator.u_max = 0.5
    sim.integrate(20.0, exact_finish_time=0)
    # A circular orbit has no curvature change: only u <= u_max limits the step.
    omega = 2 * math.pi / sim.particles[1].P
    assert sim.dt_last_done * omega <= 0.5 * (1 + 1e-9)
    assert sim.dt_last_done * omega > 0.45
    assert sim.integrator.n_u_limited == 0


def test_reversible_round_trip_returns_to_start():
    # 10 orbits at e = 0.9 (s = 2, epsilon = 1e-8), forward, then back to 0.
    # Measured: reversible 5.4e-5 (phase) and 7.5e-5 (none); seed 1.7e-2 for
    # both (python -P benchmarks/adaptive.py roundtrip). Asserted: below 2e-4
    # and at least 50x better than the seed controller.
    errors = {}
    for step_control in CONTROLS:
        sim = eccentric(step_control=step_control, epsilon=1e-8)
        start = [(p.x, p.y, p.z) for p in sim.particles]
        sim.integrate(10 * sim.particles[1].P)
        sim.integrate(0.0)
        assert sim.t == 0.0
        errors[step_control] = max(math.dist(a, (p.x, p.y, p.z)) for a, p in zip(start, sim.particles))
    assert errors["reversible"] < 2e-4
    assert errors["reversible"] * 50 < errors["seed"]


@pytest.mark.parametrize("step_control", CONTROLS)
@pytest.mark.parametrize("stages", [2, 4])
def test_archive_continuation_is_bit_identical(tmp_path, step_control, stages):
    # The controller's state (the proposed sim.dt, the last reversible step,
    # the predictor) travels in the Simulationarchive.
    sim = eccentric(stages=stages, step_control=step_control, epsilon=1e-7)
    sim.integrate(2.0, exact_finish_time=0)
    path = str(tmp_path / "adaptive.bin")
    sim.save_to_file(path)
    loaded = rebound.Simulation(path)
    assert loaded.integrator.step_control == step_control
    assert loaded.integrator.epsilon == 1e-7
    assert loaded.integrator.dt_reversible == sim.integrator.dt_reversible
    sim.integrate(5.0, exact_finish_time=0)
    loaded.integrate(5.0, exact_finish_time=0)
    assert state(loaded) == state(sim)
    assert loaded.dt == sim.dt
    assert loaded.integrator.n_attempts == sim.integrator.n_attempts


def test_straight_line_motion_takes_its_steps_from_the_force():
    # No particle has a curvature (1-D oscillator, frequency 'curvature') and
    # there are no pairs (gravity off): the steps come from the stages'
    # resolution of the spring (tests/test_unpaired.py), not from sim.dt,
    # which the build before kept whatever epsilon asked.
    sim = rebound.Simulation()
    sim.gravity = "none"
    sim.add(m=1.0, x=1.0)

    def spring(simp):
        p = simp.contents.particles[0]
        p.ax = -p.x

    sim.additional_forces = spring
    sim.integrator = "pfvi"
    sim.dt = 0.01
    sim.integrate(5.0, exact_finish_time=0)
    assert 0.5 < abs(sim.dt) < 2.0   # about a radian of the oscillation (u aimed at 1.4 kappa, 0.9 of it)
    assert sim.integrator.n_steps < 20
    assert abs(sim.particles[0].x - math.cos(sim.t)) < 1e-8


@pytest.mark.parametrize("stages", [4, 6])
@pytest.mark.parametrize("e", [0.5, 0.95])
def test_reversible_trials_start_from_the_last_trials_stages(stages, e):
    # The reversible controller solves its step equation with several trial
    # steps from one start; each starts its stage solve from the last trial's
    # converged stages. Before, each started from the last step's: over these
    # 2 orbits a taken step needed 3.4-4.1 rounds of stage forces and a step
    # 52.7-53.0 (s = 4) or 78.1-78.8 (s = 6) force evaluations; now 1.9-2.2
    # rounds and 42.1-42.2 or 55.6-56.7 evaluations (same steps, same trials).
    sim = eccentric(e=e, stages=stages, step_control="reversible")  # the defaults but s
    sim.integrate(2 * sim.particles[1].P)
    assert sim.integrator.iterations_mean <= 2.4
    assert sim.integrator.n_force_evaluations / sim.integrator.n_steps < {4: 47, 6: 62}[stages]
