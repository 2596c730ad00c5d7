"""The simulation changed between integrate() calls: particles added, removed,
edited, collisions merging bodies, the integrator switched. Continuing must be
the same as starting afresh from the changed state."""
import pytest
import rebound

from conftest import STEP_MODES, seed_pfvi, two_body

FIELDS = ("x", "y", "z", "vx", "vy", "vz", "m")
MODES = STEP_MODES


def configure(sim, mode):
    stages, epsilon, step_control = MODES[mode]
    seed_pfvi(sim)
    sim.integrator.stages = stages
    sim.integrator.epsilon = epsilon
    sim.integrator.step_control = step_control
    sim.dt = 0.01
    return sim


def planets():
    sim = two_body(1e-3, e=0.3, com=False)
    sim.add(m=1e-4, a=2.0, e=0.2, primary=sim.particles[0])
    return sim


def fresh_copy(sim, mode):
    """A new simulation with sim's particles, t and proposed dt, nothing else."""
    copy = rebound.Simulation()
    for p in sim.particles:
        copy.add(p.copy())
    copy.t = sim.t
    configure(copy, mode)
    copy.dt = sim.dt
    return copy


def physical_state(sim):
    return sim.t, [[getattr(p, f) for f in FIELDS] for p in sim.particles]


def change_add(sim):
    sim.add(m=1e-5, a=3.0, e=0.1, primary=sim.particles[0])


def change_remove(sim):
    sim.remove(1)


def change_replace(sim):
    # Same N, different particle: nothing may be carried over from the old one.
    sim.remove(2)
    sim.add(m=1e-4, a=2.5, e=0.4, primary=sim.particles[0])


def change_edit(sim):
    sim.particles[1].vx *= 1.01
    sim.particles[2].m = 2e-4


def continue_and_fresh(change, mode):
    sim = configure(planets(), mode)
    sim.integrate(0.7)
    change(sim)
    fresh = fresh_copy(sim, mode)
    if MODES[mode][1] > 0.:
        # The reversible control also carries its last step forward.
        fresh.integrator.dt_reversible = sim.integrator.dt_reversible
    sim.integrate(1.5)
    fresh.integrate(1.5)
    return physical_state(sim), physical_state(fresh)


@pytest.mark.parametrize("mode", MODES)
@pytest.mark.parametrize("change", [change_add, change_remove], ids=["add", "remove"])
def test_continuing_after_n_changed_equals_a_fresh_start(change, mode):
    # N changed: nothing of the last step is kept, bit for bit.
    continued, fresh = continue_and_fresh(change, mode)
    assert continued == fresh


@pytest.mark.parametrize("mode", MODES)
@pytest.mark.parametrize("change", [change_replace, change_edit], ids=["replace", "edit"])
def test_continuing_after_particles_changed_in_place_matches_a_fresh_start(change, mode):
    # Same N: the edited particles start afresh, the untouched ones keep the
    # few ulps their compensated sums carry; so equal to round-off, not bits.
    (t, continued), (t_fresh, fresh) = continue_and_fresh(change, mode)
    assert t == t_fresh
    for a, b in zip(continued, fresh):
        assert a == pytest.approx(b, rel=1e-13, abs=1e-15)


def test_merging_collision_between_steps_is_handled():
    sim = rebound.Simulation()
    sim.add(m=1.0, r=0.01)
    sim.add(m=1e-3, r=0.02, x=1.0, vx=-1.0)
    sim.add(m=1e-3, r=0.02, x=3.0, vy=0.6)
    sim.move_to_com()
    sim.integrator = "pfvi"
    sim.collision = "direct"
    sim.collision_resolve = "merge"
    p0 = [sum(p.m * getattr(p, v) for p in sim.particles) for v in ("vx", "vy", "vz")]
    sim.integrate(2.0)
    assert sim.N == 2 and sim.t == 2.0
    assert sim.particles[0].m == pytest.approx(1.001, rel=1e-15)
    p1 = [sum(p.m * getattr(p, v) for p in sim.particles) for v in ("vx", "vy", "vz")]
    assert p1 == pytest.approx(p0, abs=1e-15)


def test_switching_to_ias15_and_back_restarts_pfvi_with_its_defaults():
    sim = configure(planets(), "fixed-s2")
    sim.integrate(1.0)
    sim.integrator = "ias15"
    sim.integrate(2.0)
    E0 = sim.energy()
    sim.integrator = "pfvi"
    # REBOUND frees the old state and creates a new one: defaults, no statistics.
    assert (sim.integrator.stages, sim.integrator.epsilon, sim.integrator.n_steps) == (8, 1e-6, 0)
    sim.integrate(3.0)
    assert sim.t == 3.0
    # The defaults: symmetric steps at epsilon 1e-6, a relative position error of at
    # most 1e-6 per orbit (measured 4.7e-10 here; 2.5e-13 under the old
    # osculating-circle default, which took many more steps).
    assert abs(sim.energy() / E0 - 1) < 1e-8


def test_switching_from_ias15_mid_run_equals_a_fresh_pfvi_start():
    sim = planets()
    sim.integrator = "ias15"
    sim.integrate(0.8)
    configure(sim, "fixed-s4")
    fresh = fresh_copy(sim, "fixed-s4")
    sim.integrate(1.6)
    fresh.integrate(1.6)
    assert physical_state(sim) == physical_state(fresh)


@pytest.mark.parametrize("name, value", [("stages", 3), ("stages", 6), ("fitting", "none"),
                                         ("fitting", "phase-literal"), ("frequency", "fixed"),
                                         ("u_max", 0.005), ("epsilon", 1e-8)])
def test_switching_pfvi_options_mid_run_takes_effect_at_the_next_step(name, value):
    sim = configure(planets(), "fixed-s2")
    sim.integrator.omega = 7.0  # used once frequency is "fixed"
    if name == "frequency":
        # About the origin the star feels no pull towards it, and a fixed
        # omega's two-point step is unstable for it (refused, docs/method.md):
        # about the pairs' barycentres each body feels its partner's.
        sim.integrator.centre = "partner"
    sim.integrate(0.5)
    kept = sim.copy()  # the same run, options unchanged
    setattr(sim.integrator, name, value)
    steps_before = sim.integrator.n_steps
    sim.integrate(0.7)
    kept.integrate(0.7)
    assert sim.t == kept.t == pytest.approx(0.7, abs=1e-15)
    # The option changed the steps that followed, and only those.
    assert physical_state(sim) != physical_state(kept)
    assert getattr(sim.integrator, name) == value
    if name == "epsilon":
        assert sim.integrator.n_steps - steps_before != 20  # adaptive, no longer 20 fixed steps of 0.01
    if name == "u_max":
        assert sim.integrator.n_u_limited > kept.integrator.n_u_limited
