"""Options, the force model and the integrator changed from inside a step,
a fixed frequency far from the motion's, damaged stored state, integers that
do not fit (issue 27). A change made during a step acts from the next step,
exactly as the same change made between steps; where that cannot be (a
particle added or removed, a callback replaced) the step is refused with t
and every particle restored."""
import json
import math
import os
import subprocess
import sys
import textwrap

import pytest
import rebound

import rebound_pfvi
from conftest import PYTHON_HEARTBEAT

FIELDS = ("x", "y", "z", "vx", "vy", "vz", "m")


def state(sim):
    return sim.t, [tuple(getattr(p, f) for f in FIELDS) for p in sim.particles]


def sun_and_planet(stages=2, dt=0.01, epsilon=0.0):
    sim = rebound.Simulation()
    sim.add(m=1.0)
    sim.add(m=1e-3, a=1.0, e=0.5)
    sim.move_to_com()
    sim.integrator = "pfvi"
    sim.integrator.stages = stages
    sim.integrator.epsilon = epsilon
    sim.dt = dt
    return sim


def on_call(sim, k, action):
    """Runs action(simulation) in the force callback's k-th call; returns a
    list that records the number of steps taken before that call."""
    calls, seen = [0], []

    def force(simp):
        calls[0] += 1
        if calls[0] == k:
            seen.append(simp.contents.integrator.n_steps)
            action(simp.contents)

    sim.additional_forces = force
    return seen


def between_steps(build, steps, action, t_end, force=None):
    """The reference: the same steps, the change made after them, the rest;
    with force as its additional_forces, if given."""
    sim = build()
    if force is not None:
        sim.additional_forces = force
    sim.steps(steps)
    action(sim)
    sim.integrate(t_end)
    return sim


def changed_in_a_step(build, call, action, t_end):
    """The run with action made in the force callback's given call, and the
    reference with it made after the step that call was in."""
    sim = build()
    seen = on_call(sim, call, action)
    sim.integrate(t_end)
    # The reference has a force callback too, one that adds nothing, as the
    # run's does after its call: a simulation without one takes other paths
    # (pfvi's own gravity pass, the two-body predictor without a rest) whose
    # converged stages can differ in the last place.
    return sim, between_steps(build, seen[0] + 1, action, t_end, force=lambda simp: None)


@pytest.mark.parametrize("epsilon", [0.0, 1e-6])
def test_stages_changed_in_a_callback_act_from_the_next_step(epsilon):
    # The scheme was chosen again when the step committed: a two-point trial
    # committed as an 8-stage one, x = -1.2048872194 where IAS15 has
    # -1.2050436281 (and valgrind saw unwritten unknowns).
    def change(s):
        s.integrator.stages = 8

    def build():
        return sun_and_planet(epsilon=epsilon)

    sim, reference = changed_in_a_step(build, 2, change, 2.0)
    assert state(sim) == state(reference)
    # Against IAS15: the first step's two-point (Verlet) error, 8.6e-6 with
    # fixed steps (the wrong commit was 1.6e-4 off).
    ias15 = sun_and_planet()
    ias15.integrator = "ias15"
    ias15.integrate(2.0)
    assert abs(sim.particles[1].x - ias15.particles[1].x) < 2e-5


@pytest.mark.parametrize("to", ["ias15", "leapfrog", "pfvi"])
def test_the_integrator_switched_in_a_callback_takes_over_after_the_step(to):
    # REBOUND freed pfvi's state while its step still used it: "malloc():
    # unaligned tcache chunk detected", or a segfault.
    def switch(s):
        s.integrator = to

    def build():
        return sun_and_planet(stages=4, epsilon=1e-8)

    sim, reference = changed_in_a_step(build, 5, switch, 1.0)
    assert str(sim.integrator) == to
    assert state(sim) == state(reference)


def test_the_force_model_changed_in_a_callback_acts_from_the_next_step():
    def change(s):
        s.G = 1.01
        s.softening = 1e-3

    def build():
        return sun_and_planet(stages=6, epsilon=1e-8)

    sim, reference = changed_in_a_step(build, 7, change, 1.0)
    assert (sim.G, sim.softening) == (1.01, 1e-3)
    assert state(sim) == state(reference)


def test_a_callback_replaced_during_a_step_is_refused_with_the_state_restored():
    # The step's force evaluations must all come from one force model; a
    # replaced callback cannot be deferred (REBOUND calls whatever is set),
    # so the step is refused, leaving the state of the steps taken before.
    def nothing(simp):
        pass

    sim = sun_and_planet(stages=4, epsilon=1e-8)
    calls = [0]

    def force(simp):
        calls[0] += 1
        if calls[0] == 30:  # in the third step (13 calls in the first, 10 to 13 after)
            sim.additional_forces = nothing

    sim.additional_forces = force
    with pytest.raises(RuntimeError, match="replaced additional_forces"):
        sim.integrate(1.0)
    taken = sim.integrator.n_steps
    assert taken > 0
    reference = sun_and_planet(stages=4, epsilon=1e-8)
    reference.additional_forces = nothing
    reference.steps(taken)
    assert state(sim) == state(reference)
    sim.integrate(1.0)  # then it goes on with the new callback
    assert sim.t == 1.0


def test_steps_called_from_a_callback_is_refused_and_the_step_goes_on():
    sim = sun_and_planet(stages=4, epsilon=1e-8)
    inner = []

    def force(simp):
        if not inner:
            try:
                simp.contents.steps(1)
                inner.append("ran")
            except RuntimeError as error:
                inner.append(str(error))

    sim.additional_forces = force
    sim.integrate(0.5)
    assert sim.t == 0.5
    assert "while one is running" in inner[0]


def fixed_frequency(stages, fitting, omega, dt=1e-3):
    sim = sun_and_planet(stages=stages, dt=dt)
    sim.integrator.fitting = fitting
    sim.integrator.frequency = "fixed"
    sim.integrator.omega = omega
    return sim


@pytest.mark.parametrize("stages, fitting, omega", [(2, "phase", 50.0), (2, "phase", 1e300),
                                                    (2, "phase-literal", 30.0), (4, "exact", 1e300),
                                                    (4, "phase", 500.0)])
def test_a_fixed_frequency_the_step_cannot_follow_is_refused(stages, fitting, omega):
    # A fitted step far from the motion's frequency adds a repulsive
    # harmonic force: omega = 50 at s = 2 unbound the planet (e = 843),
    # omega = 1e300 reached 8e266 in one time unit, s = 4 at u = 1 reached
    # an energy error of 4e28 in 6 time units, all reported as success. The
    # step is refused where its linear map grows, with t and every particle
    # as after the last step taken (the same steps taken alone).
    sim = fixed_frequency(stages, fitting, omega)
    with pytest.raises(RuntimeError, match=rf"particle \d: the {stages}-stage step fitted to the fixed omega "
                       r"= .* is unstable"):
        sim.integrate(6.0)
    taken = sim.integrator.n_steps
    reference = fixed_frequency(stages, fitting, omega)
    if taken:
        reference.steps(taken)
    assert state(sim) == state(reference)


@pytest.mark.parametrize("stages, fitting, omega", [(2, "phase", 20.0), (4, "phase", 450.0)])
def test_a_fixed_frequency_within_the_bound_runs_with_its_accuracy(stages, fitting, omega):
    # omega = 20 at s = 2 (20 tan 0.01 = 0.2 against the pull's 0.54 at
    # aphelion) and u = 0.45 at s = 4 stay bound: the energy error, set by
    # the wrong frequency, is 0.10 to 0.12 and does not grow from 6 to 60
    # time units (docs/method.md).
    sim = fixed_frequency(stages, fitting, omega)
    E0 = sim.energy()
    sim.integrate(6.0)
    early = abs(sim.energy() / E0 - 1)
    sim.integrate(60.0)
    late = abs(sim.energy() / E0 - 1)
    assert 0.05 < early < 0.15 and late < 1.5 * early


def oscillator_map(stages, omega, W2, h=1.0):
    """Half the trace of one step's map of (x, v) for x'' = -W2 x, omega fixed."""
    columns = []
    for x, v in ((1.0, 0.0), (0.0, 1.0)):
        sim = rebound.Simulation()
        sim.add(m=0.0, x=x, vx=v)

        def force(simp):
            p = simp.contents.particles[0]
            p.ax -= W2 * p.x
        sim.additional_forces = force
        sim.integrator = "pfvi"
        sim.integrator.stages = stages
        sim.integrator.fitting = "exact" if stages > 2 else "phase"
        sim.integrator.frequency = "fixed"
        sim.integrator.omega = omega
        sim.integrator.epsilon = 0.0
        sim.dt = h
        sim.steps(1)
        columns.append((sim.particles[0].x, sim.particles[0].vx))
    return 0.5 * (columns[0][0] + columns[1][1])


def refused_growth(stages, omega, W2, h=1.0):
    with pytest.raises(RuntimeError, match="unstable") as refusal:
        oscillator_map(stages, omega, W2, h)
    return float(refusal.value.args[0].split("factor 1 + ")[1].split()[0])


def test_the_two_point_bound_is_omega_tan_half_u_against_the_pull():
    # The two-point step's half trace is cos u - (W^2/omega^2 - 1) sin u tan u/2:
    # stable while omega tan(u/2) <= W. On the oscillator both sides of it.
    omega, u = 1.0, 0.8
    bound = omega * math.tan(u / 2)
    assert oscillator_map(2, omega, (1.01 * bound)**2, h=u) <= 1.0
    refused_growth(2, omega, (0.99 * bound)**2, h=u)


def test_the_stage_schemes_growth_is_their_step_maps():
    # At s = 4 a free particle fitted to omega grows (half trace 1 + 4.8e-8 at
    # u = 0.5): the refusal reports the factor 1 + g per step from the
    # scheme's linear map; the map measured from two steps under weak pulls
    # (which run), extrapolated to no pull, must agree.
    u = 0.5
    g = refused_growth(4, u, 0.0)
    pulls = [6e-7, 1.2e-6]
    traces = [oscillator_map(4, u, W2) for W2 in pulls]
    t0 = traces[0] - (traces[1] - traces[0]) / (pulls[1] - pulls[0]) * pulls[0]
    measured = (t0 - 1.0) + math.sqrt((t0 - 1.0) * (t0 + 1.0))
    assert 4e-8 < t0 - 1.0 < 6e-8
    assert measured == pytest.approx(g, rel=1e-2)


@pytest.mark.parametrize("field, value", [("predictor_h", float("nan")), ("predictor_h", 1e-300),
                                          ("density_scale", -1.0), ("density_scale", float("inf")),
                                          ("density_scale", 1e300), ("rho", float("nan")), ("rho", 1e5),
                                          ("rho", 1e8), ("rho", 1e300), ("rho", 1e-300),
                                          ("track_done", float("nan")), ("t_compensation", 1e300)])
def test_damaged_stored_state_is_discarded(tmp_path, field, value):
    # predictor_h = NaN or 1e-300 made every later step refuse ("particle 0's
    # position overflowed"), and lowering dt 100x did not help; rho = 1e8
    # (the track keeps any multiple of the density) took 1e6 steps per 0.01
    # time units, forever; rho = 1e300 or 1e-300 and density_scale = 1e300
    # refused every step with messages about dt, overflow or convergence.
    sim = sun_and_planet(stages=4, epsilon=1e-8)
    sim.integrate(0.3)
    setattr(sim.integrator, field, value)
    path = str(tmp_path / "damaged.bin")
    sim.save_to_file(path)
    loaded = rebound.Simulation(path)
    assert getattr(loaded.integrator, field) == value or value != value
    reference = sun_and_planet()
    reference.integrator = "ias15"
    reference.integrate(2.0)
    for run in (sim, loaded):
        steps = run.integrator.n_steps
        run.integrate(2.0)
        assert math.dist((run.particles[1].x, run.particles[1].y), (reference.particles[1].x, reference.particles[1].y)) < 1e-7
        assert run.integrator.n_steps - steps < 2000  # an undamaged run takes 720 from 0.3 to 2


@pytest.mark.parametrize("stages", [2, 4, 8])
@pytest.mark.parametrize("edit", ["m", "x", "vx", "t"])
def test_a_particle_edited_in_a_callback_during_a_step_is_refused(stages, edit):
    # A mass changed at the third force evaluation was wiped by the retaken
    # step (s = 8), blended into a fixed step, or refused as "the 2-stage
    # solve did not converge"; positions, velocities and t set in a callback
    # were silently overwritten. An edit inside a step has no between-steps
    # equivalent (between which stage points?): refused, every particle and
    # t as the step found them, the edit undone too.
    def change(s):
        if edit == "t":
            s.t += 0.5
        else:
            p = s.particles[1]
            setattr(p, edit, getattr(p, edit) * 1.5 + 1e-3)

    sim = sun_and_planet(stages=stages, epsilon=1e-6)
    on_call(sim, 7, change)
    with pytest.raises(RuntimeError, match=(r"changed sim\.t during the step" if edit == "t" else
                                            rf"changed particle 1's {edit} during the step")):
        sim.integrate(1.0)
    reference = sun_and_planet(stages=stages, epsilon=1e-6)
    reference.additional_forces = lambda simp: None
    if sim.integrator.n_steps:
        reference.steps(sim.integrator.n_steps)
    assert state(sim) == state(reference)


@pytest.mark.parametrize("stages", [4, 8])
@pytest.mark.parametrize("edit", ["m", "x", "vy"])
def test_a_variational_particle_edited_in_a_callback_during_a_step_is_refused(stages, edit):
    # A variational particle's mass enters REBOUND's variational gravity,
    # which pfvi's own pass computes for all stages before the first call:
    # edited in the callback, it acted from the next stage through REBOUND's
    # routine but not through the pass (a hostile trial). Refused as a real
    # particle's edit is, every particle, real and variational, and t
    # restored.
    def change(s):
        p = s._particles_var[1]
        setattr(p, edit, getattr(p, edit) * 1.5 + 1e-3)

    def build():
        sim = sun_and_planet(stages=stages, epsilon=1e-6)
        sim.add(m=1e-3, a=2.0, e=0.1, f=1.0)
        sim.init_megno(seed=1)
        return sim

    sim = build()
    on_call(sim, 9, change)
    sim.force_is_velocity_dependent = 0
    with pytest.raises(RuntimeError, match=rf"changed variational particle 1's {edit} during the step"):
        sim.integrate(1.0)
    reference = build()
    reference.additional_forces = lambda simp: None
    reference.force_is_velocity_dependent = 0
    if sim.integrator.n_steps:
        reference.steps(sim.integrator.n_steps)
    assert state(sim) == state(reference)
    variational = [[getattr(run._particles_var[v], f) for f in FIELDS for v in range(run.N_var)]
                   for run in (sim, reference)]
    assert variational[0] == variational[1]


@pytest.mark.parametrize("before", [0, 1])
def test_a_variation_added_in_a_callback_during_a_step_is_refused(before):
    # REBOUND's add_variation() moves the variational particles' array: the
    # step wrote into the freed one ("realloc(): invalid next size", a
    # hostile trial). Refused, t and the real particles restored.
    sim = sun_and_planet(stages=8, epsilon=1e-6)
    for _ in range(before):
        sim.add_variation().particles[1].x = 1e-3
    on_call(sim, 5, lambda s: s.add_variation())
    sim.force_is_velocity_dependent = 0
    with pytest.raises(RuntimeError, match=r"a callback changed the variational particles \(N_var from "
                                           rf"{2 * before} to {2 * before + 2}\)"):
        sim.integrate(1.0)
    reference = sun_and_planet(stages=8, epsilon=1e-6)
    reference.additional_forces = lambda simp: None
    reference.force_is_velocity_dependent = 0
    if sim.integrator.n_steps:
        reference.steps(sim.integrator.n_steps)
    assert state(sim) == state(reference)


@pytest.mark.parametrize("kind", ["int", "numpy", "0-d array"])
@pytest.mark.parametrize("field, value", [("stages", 2**32 + 4), ("fitting", 2**32 + 3), ("stages", 2**31),
                                          ("stages", -2**31 - 1)])
def test_integers_that_do_not_fit_are_refused_on_assignment(field, value, kind):
    # (numpy's integers passed the check and wrapped: np.int64(2**32 + 4) ran at s = 4, a hostile trial)
    np = pytest.importorskip("numpy")
    given = {"int": value, "numpy": np.int64(value), "0-d array": np.array(value, dtype=np.int64)}[kind]
    sim = sun_and_planet()
    before = getattr(sim.integrator, field)
    with pytest.raises(ValueError, match=f"integrator.{field} = {value} does not fit"):
        setattr(sim.integrator, field, given)
    assert getattr(sim.integrator, field) == before


@pytest.mark.parametrize("field", sorted(rebound_pfvi._STATISTICS))
def test_statistics_are_read_only(field):
    # The docs call them read-only; REBOUND wrote them (n_steps = 5 counted on from 5).
    sim = sun_and_planet(epsilon=1e-6)
    sim.integrate(1.0)
    before = getattr(sim.integrator, field)
    with pytest.raises(AttributeError, match=f"integrator.{field} is a statistic"):
        setattr(sim.integrator, field, 5)
    assert getattr(sim.integrator, field) == before


# The property: hostile actions inside a force callback or a heartbeat, at a
# random call.
# Each example runs in its own process (a crash is a failed example, not a
# dead test run); every outcome must be the between-steps result, or a
# refusal that restored t and every particle.
SCRIPT = textwrap.dedent('''
    import json, sys
    import rebound, rebound_pfvi
    p = json.loads(sys.argv[1])

    def build():
        sim = rebound.Simulation()
        sim.add(m=1.0)
        sim.add(m=1e-3, a=1.0, e=0.6)
        sim.add(m=1e-4, a=2.2, e=0.2, inc=0.1)
        sim.move_to_com()
        sim.integrator = "pfvi"
        sim.integrator.stages = p["stages"]
        sim.integrator.epsilon = p["epsilon"]
        sim.dt = 0.02
        return sim

    def act(s):
        kind, value = p["action"], p["value"]
        if kind == "option":
            setattr(s.integrator, value[0], value[1])
        elif kind == "model":
            setattr(s, value[0], value[1])
        elif kind == "integrator":
            s.integrator = value
        elif kind == "add":
            s.add(m=1e-6, a=3.0)
        elif kind == "remove":
            s.remove(2)
        elif kind == "raise":
            raise ValueError("hostile")
        elif kind == "steps":
            try:
                s.steps(1)
            except RuntimeError:
                pass
        elif kind == "edit":
            setattr(s.particles[1], value, getattr(s.particles[1], value) * 1.01)

    def snapshot(sim):
        return [sim.t] + [[getattr(q, f) for f in ("x", "y", "z", "vx", "vy", "vz", "m")] for q in sim.particles]

    sim = build()
    calls, seen = [0], []
    def hostile(simp):
        calls[0] += 1
        if calls[0] == p["call"]:
            s = simp.contents
            seen.append(s.integrator.n_steps if str(s.integrator) == "pfvi" else -1)
            act(s)
    if p["where"] == "force":
        sim.additional_forces = hostile
    else:
        sim.heartbeat = hostile
    outcome = "finished"
    try:
        sim.integrate(p["t_end"])
    except RuntimeError as error:
        outcome = "refused: " + str(error)
    taken = sim.steps_done  # (counted whichever integrator took them)
    result = {"outcome": outcome, "state": snapshot(sim), "seen": seen}
    if seen and seen[0] >= 0:
        # The between-steps reference: the same steps, then the change (a
        # raise or a refused inner step change nothing), then the rest; and
        # the state the step it happened in started from. A force callback
        # acts inside step seen[0] + 1, so its change is made after that
        # step; a heartbeat runs between steps, so after step seen[0]. A
        # change after the run's last step (cut to end on t_end) is made
        # after the whole run.
        def fresh():
            r = build()
            r.additional_forces = lambda simp: None
            return r
        start = fresh()
        start.steps(seen[0])
        result["start"] = snapshot(start)
        inside = p["where"] == "force"
        after = seen[0] + 1 if inside else seen[0]
        last = outcome == "finished" and after == taken
        reference = fresh()
        if last:
            reference.integrate(p["t_end"])
        else:
            reference.steps(after)
        try:
            if p["action"] != "raise" and not (inside and p["action"] == "steps"):
                act(reference)
            if not last:
                reference.integrate(p["t_end"])
            result["reference_outcome"] = "finished"
        except RuntimeError as error:
            result["reference_outcome"] = "refused: " + str(error)
        result["reference"] = snapshot(reference)
    print(json.dumps(result))
''')


def hostile_example(params):
    done = subprocess.run([sys.executable, "-P", "-c", SCRIPT, json.dumps(params)], capture_output=True, text=True,
                          timeout=120, env={**os.environ, "PYTHONFAULTHANDLER": "1"})
    assert done.returncode == 0, (params, done.stderr[-2000:])
    return json.loads(done.stdout.splitlines()[-1])


@pytest.mark.slow
def test_hostile_callbacks_property():
    hypothesis = pytest.importorskip("hypothesis")
    from hypothesis import strategies as st

    actions = st.one_of(
        st.tuples(st.just("option"), st.sampled_from([("stages", 6), ("stages", 9), ("epsilon", 1e-9),
                                                      ("epsilon", -1.0), ("fitting", "exact"), ("u_max", 5.0)])),
        st.tuples(st.just("model"), st.sampled_from([("G", 1.02), ("softening", 1e-3), ("N_active", 2),
                                                     ("gravity", "compensated"), ("gravity", "none")])),
        st.tuples(st.just("integrator"), st.sampled_from(["ias15", "leapfrog", "pfvi"])),
        st.tuples(st.sampled_from(["add", "remove", "raise", "steps"]), st.none()),
        st.tuples(st.just("edit"), st.sampled_from(["m", "x", "vy"])))

    @hypothesis.settings(max_examples=40, deadline=None, derandomize=True, database=None)
    @hypothesis.given(action=actions, call=st.integers(1, 40), stages=st.sampled_from([2, 4, 8]),
                      epsilon=st.sampled_from([0.0, 1e-6]),
                      where=st.sampled_from(["force", "heartbeat"] if PYTHON_HEARTBEAT else ["force"]))
    def check(action, call, stages, epsilon, where):
        params = {"action": action[0], "value": action[1], "call": call, "stages": stages, "epsilon": epsilon,
                  "t_end": 0.5, "where": where}
        result = hostile_example(params)
        if not result["seen"]:
            return  # the run ended before that call
        if where == "heartbeat" and action[0] == "steps":
            # REBOUND's own nesting, between steps: the inner steps() takes
            # its step and leaves status "success", which ends the outer
            # integrate() (IAS15 alike, t = 0.02 of 0.5). Not pfvi's to change.
            assert result["outcome"] == "finished"
            return
        if where == "force" and action[0] == "edit":
            # Refused in the step it happened in, the edit undone: the state
            # that step started from.
            assert "during the step" in result["outcome"], result["outcome"]
            assert result["state"] == result["start"]
            return
        if where == "force" and action[0] in ("add", "remove"):
            # Refused in the step it happened in: t and every particle still
            # there back at that step's start (the removed one stays removed,
            # the added one stays added).
            assert "changed the number of particles" in result["outcome"], result["outcome"]
            start = result["start"]
            kept = start[1:3] + start[4:] if action[0] == "remove" else start[1:]
            assert result["state"][0] == start[0]
            assert result["state"][1:1 + len(kept)] == kept
            return
        # Every other change acts from the next step: the outcome is the
        # between-steps run's, bit for bit (an invalid option refuses the
        # next step in both).
        assert result["outcome"].split(":")[0] == result["reference_outcome"].split(":")[0], (params, result)
        assert result["state"] == result["reference"], (params, result["outcome"])
    check()
