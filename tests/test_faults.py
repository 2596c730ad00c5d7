"""Faults injected through additional_forces, in every step mode: the step is
not taken, t and every particle stay bit-identical, and the error says why."""
import math

import pytest
import rebound

from conftest import STEP_MODES, snapshot, two_body

MODES = STEP_MODES


def running(mode, fitting="phase"):
    stages, epsilon, step_control = MODES[mode]
    sim = two_body(1e-3, e=0.6, com=True)
    sim.add(m=0.0, a=2.0, e=0.1, primary=sim.particles[0])
    sim.integrator = "pfvi"
    sim.integrator.stages = stages
    sim.integrator.epsilon = epsilon
    sim.integrator.step_control = step_control
    sim.integrator.fitting = fitting
    sim.dt = 0.01
    sim.integrate(0.37)  # mid-run: kept forces, predictor and compensation in use
    return sim


def inject(sim, fault, after):
    """Install fault(particles) to run from the after-th force evaluation on."""
    calls = {"n": 0}

    def force(simp):
        calls["n"] += 1
        if calls["n"] >= after:
            fault(simp.contents.particles)

    sim.additional_forces = force
    return calls


def nan_force(ps):
    ps[1].ax = math.nan


def inf_force(ps):
    ps[2].az = -math.inf


@pytest.mark.parametrize("mode", MODES)
@pytest.mark.parametrize("fault, particle", [(nan_force, 1), (inf_force, 2)], ids=["nan", "inf"])
@pytest.mark.parametrize("after", [1, 2, 5])
def test_non_finite_force_leaves_everything_as_it_was(mode, fault, particle, after):
    sim = running(mode)
    calls = inject(sim, fault, after)
    steps = sim.integrator.n_steps
    # Steps before the fault are taken; the step that meets it is refused.
    with pytest.raises(RuntimeError, match=rf"force on particle {particle} is not finite.*state restored"):
        while True:
            before, steps = snapshot(sim), sim.integrator.n_steps
            sim.steps(1)
    assert snapshot(sim) == before
    assert sim.integrator.n_steps == steps
    assert calls["n"] >= after


@pytest.mark.parametrize("mode", MODES)
def test_stage_solve_that_cannot_converge_leaves_everything_as_it_was(mode):
    # A force flipping between +1e250 and -1e250 at every evaluation: the
    # s = 4 stage solve cannot converge at any step the adaptive control can
    # reach, so it is refused in every mode; the explicit s = 2 step takes the
    # force as given (it is the user's) and must still end finite or refuse.
    stages, epsilon, _ = MODES[mode]
    sim = running(mode)
    calls = {"n": 0}

    def flip(ps):
        calls["n"] += 1
        ps[1].ay += 1e250 if calls["n"] % 2 else -1e250

    inject(sim, flip, 1)
    before = snapshot(sim)
    if stages == 2:
        try:
            sim.steps(1)
        except RuntimeError as error:
            assert "state restored" in str(error)
            assert snapshot(sim) == before
        else:
            assert all(math.isfinite(getattr(p, f)) for p in sim.particles for f in ("x", "vx", "ax"))
        return
    # (or, under the adaptive control, the u bound drives dt so low that dt^2 underflows)
    with pytest.raises(RuntimeError, match=r"(did not converge|meets epsilon|not solved|dt\^2 underflows).*state restored"):
        sim.steps(1)
    assert snapshot(sim) == before


@pytest.mark.parametrize("mode", ["seed-s4", "reversible-s4"])
def test_adaptive_steps_shorten_a_step_whose_stage_solve_fails(mode):
    # A stiff spring (h^2 k = 25 at dt = 0.1): the fixed step is refused
    # (test_stages.py); the adaptive control retries shorter and goes on.
    from conftest import harmonic_oscillator
    stages, epsilon, step_control = MODES[mode]
    sim = harmonic_oscillator(50.0, stages=stages, fitting="none", epsilon=epsilon, step_control=step_control,
                              frequency="curvature")
    sim.dt = 0.1
    sim.integrate(1.0)
    assert sim.t == 1.0
    assert sim.integrator.n_rejected + sim.integrator.n_attempts > sim.integrator.n_steps
    assert sim.dt_last_done < 0.05


# A callback changing N mid-step: tests/test_force_model_changes.py (every particle's bytes).


@pytest.mark.parametrize("fitting", ["none", "phase"])
def test_a_value_that_overflows_in_the_step_is_named_and_the_step_undone(fitting):
    # Gravity off and a constant push of 1e308: the force at the step's end
    # stays finite, so only the check of the particles after the step sees
    # that particle 1's velocity and position overflowed (two-point step).
    sim = rebound.Simulation()
    sim.gravity = "none"
    sim.add(m=1.0, x=1.0)
    sim.add(m=1.0, y=1.0, vx=1.0)

    def push(simp):
        simp.contents.particles[1].ax = 1e308

    sim.additional_forces = push
    sim.integrator = "pfvi"
    sim.integrator.stages = 2
    sim.integrator.epsilon = 0.0
    sim.integrator.fitting = fitting
    sim.dt = 10.0
    before = snapshot(sim)
    with pytest.raises(RuntimeError, match=r"particle 1 became non-finite in the step from t = 0; "
                                           r"step not taken, state restored"):
        sim.steps(1)
    assert snapshot(sim) == before
    assert sim.integrator.n_steps == 0
