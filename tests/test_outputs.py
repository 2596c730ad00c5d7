"""Outputs that do not change the answer (issue 36, item 1).

`for t in times: sim.integrate(t)` (exact_finish_time = 1) shows each time
from an output step and takes the run's steps unbroken: the run is the same,
bit for bit, whatever its output times. Full measurements on every page's
scene: benchmarks/outputs.py (docs/step-control.md, "Outputs and reversal").
"""
import math
import random
import sys
from pathlib import Path

import numpy as np
import pytest
import rebound

import rebound_pfvi  # noqa: F401  (registers "pfvi")
from conftest import needs_python_heartbeat, two_planets

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))
import outputs as outputs_bench  # noqa: E402


def kepler(e=0.6, f=0.0, **options):
    sim = rebound.Simulation()
    sim.add(m=1.0)
    sim.add(m=1e-3, a=1.0, e=e, f=f)
    sim.move_to_com()
    sim.integrator = "pfvi"
    for name, value in options.items():
        setattr(sim.integrator, name, value)
    return sim


def encke(**options):
    """An Encke-like comet (a = 2.2 AU, e = 0.85) among Venus, Earth, Mars and
    Jupiter, in AU, yr and Msun: benchmarks/outputs.py's scene."""
    sim = outputs_bench.Encke().build()
    sim.integrator = "pfvi"
    for name, value in options.items():
        setattr(sim.integrator, name, value)
    return sim


def cadence(T, period, per_orbit=None, rand=None, seed=1):
    if per_orbit:
        n = int(round(T/period*per_orbit))
        return [T*(k + 1)/n for k in range(n - 1)] + [T]
    if rand:
        rng = random.Random(seed)
        return sorted(rng.uniform(0.0, T) for _ in range(rand)) + [T]
    return [T]


def state(sim):
    return np.array([[p.x, p.y, p.z, p.vx, p.vy, p.vz] for p in sim.particles])


def run(build, times):
    sim = build()
    for t in times:
        sim.integrate(t)
        # REBOUND's own t + (t_out - t): exact from a step's start, within the
        # rounding of the step's end when the time lies inside the last step.
        assert sim.t == pytest.approx(t, rel=1e-14, abs=1e-300)
    return sim


@pytest.mark.parametrize("scene", ["kepler", "encke"])
@pytest.mark.parametrize("outputs", [(10, None), (100, None), (1000, None), (None, 50)],
                         ids=["10/orbit", "100/orbit", "1000/orbit", "random"])
def test_outputs_leave_the_run_bit_identical(scene, outputs):
    build, period, T = (kepler, 2*math.pi, 3*2*math.pi) if scene == "kepler" else (encke, 2.2**1.5, 2*2.2**1.5)
    if scene == "encke" and outputs[0] == 1000:
        T = 2.2**1.5  # one comet period: 3300 outputs
    one = run(build, [T])
    many = run(build, cadence(T, period, *outputs))
    assert state(many).tobytes() == state(one).tobytes()
    assert many.t == one.t
    a, b = one.integrator, many.integrator
    assert (b.n_steps, b.n_rejected, b.n_asymmetric, b.n_attempts) == (a.n_steps, a.n_rejected, a.n_asymmetric, a.n_attempts)
    assert b.n_outputs >= len(cadence(T, period, *outputs)) - 1
    assert b.n_rejected == 0


def step_ends(build, T):
    """The run's own step ends below T (sim.steps, no output)."""
    sim, ends = build(), []
    while sim.t < T:
        sim.steps(1)
        ends.append(sim.t)
    return ends[:-1]


def retrograde_planets(**options):
    """Two planets and an e = 0.9 retrograde test particle crossing them."""
    sim = rebound.Simulation()
    sim.add(m=1.0)
    sim.add(m=9.5e-4, a=5.2, e=0.05, f=0.6)
    sim.add(m=2.9e-4, a=9.55, e=0.056, inc=0.04, f=2.4)
    sim.add(m=0.0, a=3.0, e=0.9, inc=2.8, f=1.0)
    sim.move_to_com()
    sim.integrator = "pfvi"
    for name, value in options.items():
        setattr(sim.integrator, name, value)
    return sim


@pytest.mark.parametrize("build, T", [(lambda: kepler(e=0.5, epsilon=1e-7), 12.0),
                                      (lambda: retrograde_planets(epsilon=1e-9), 60.0)],
                         ids=["kepler", "retrograde-planets"])
def test_an_output_on_a_step_end_leaves_the_run_bit_identical(build, T):
    # A requested time exactly on one of the run's step ends (a time read from
    # sim.t after sim.steps): REBOUND cuts nothing there and restores, after
    # integrate(), its last full step or the sim.dt the call began with
    # (0.001 for a new simulation); pfvi goes on with its own proposal, as
    # after any other output. Before: 23 of 40 step ends on Kepler e = 0.5
    # changed the run (2.1e-9 in x at t = 60); a steps() after such an output
    # went 0.001 instead of the run's step.
    ends = step_ends(build, T)
    one = run(build, [T])
    every = run(build, ends + [T])
    assert state(every).tobytes() == state(one).tobytes()
    for k in range(0, len(ends), max(1, len(ends)//8)):
        single = run(build, [ends[k], T])
        assert state(single).tobytes() == state(one).tobytes(), f"output at the step end t = {ends[k]!r}"
    # Two step ends in a row, then a time inside the next step (a hostile
    # trial: 14 of 25 such runs changed before, REBOUND restoring the dt the
    # call began with where the run's step landed on the time uncut).
    for k in range(0, len(ends) - 2, max(1, len(ends)//6)):
        inside = ends[k + 1] + 0.1*(ends[k + 2] - ends[k + 1])
        mixed = run(build, [ends[k], ends[k + 1], inside, T])
        assert state(mixed).tobytes() == state(one).tobytes(), f"step ends {ends[k]!r}, {ends[k + 1]!r}"


def first_step(sim, call):
    """The length of the first step `call` takes (a heartbeat's times)."""
    times = []
    sim.heartbeat = lambda p: times.append(p.contents.t)
    t0 = sim.t
    call()
    sim.heartbeat = 0
    return abs(times[1] - t0)


@needs_python_heartbeat
@pytest.mark.parametrize("sequence", ["same dt before each integrate", "after a copy", "integrate twice, then steps",
                                      "default dt after an output inside a step"])
def test_a_users_dt_caps_whatever_came_before(sequence, tmp_path):
    # A second hostile trial of the step-end mend: sequences where a user's
    # sim.dt was taken for one REBOUND restored (the same value set again
    # before each call, 0.376 instead of 0.01; a copy's first call one
    # finishing step, 0.849 instead of 0.05; integrate() to the current time
    # leaving dt_last_done zero before a steps(), 0.376 instead of 0.05).
    sim = kepler(e=0.5, epsilon=1e-7)
    ends = step_ends(lambda: kepler(e=0.5, epsilon=1e-7), 5.0)
    u = 0.01
    if sequence == "same dt before each integrate":
        sim.dt = u
        sim.integrate(0.37)
        sim.dt = u
        h = first_step(sim, lambda: sim.integrate(0.74))
    elif sequence == "after a copy":
        sim.integrate(ends[0] + 0.8*(ends[1] - ends[0]))
        sim = sim.copy()
        sim.integrate(ends[1])
        u = 0.05
        sim.dt = u
        h = first_step(sim, lambda: sim.integrate(sim.t + 3.0))
    elif sequence == "integrate twice, then steps":
        u = 0.05
        sim.dt = u
        sim.integrate(0.37)
        sim.integrate(0.37)
        sim.dt = u
        h = first_step(sim, lambda: sim.steps(1))
    else:
        u = 0.001
        sim.integrate(0.37)
        sim.steps(5)
        sim.dt = u
        h = first_step(sim, lambda: sim.integrate(sim.t + 3.0))
    assert h <= u*(1 + 1e-12) + 8*np.spacing(sim.t)


@needs_python_heartbeat
@pytest.mark.parametrize("build", [lambda: kepler(e=0.5, epsilon=1e-7), lambda: retrograde_planets(epsilon=1e-9),
                                   lambda: two_planets()], ids=["kepler", "retrograde-planets", "two-planets"])
@pytest.mark.parametrize("u", [0.01, 1e-4])
def test_a_users_dt_caps_one_step_then_outputs_leave_the_run_alone(build, u):
    # A sim.dt set once mid-run caps the step from there; once a step took it
    # in full, REBOUND restoring that step after integrate() (its last full
    # one) is REBOUND's, not the user's again. Before, the cap came back after
    # every call: 200 steps at 100 outputs for one call's 5 on two planets,
    # the run 1e-11 off.
    runs = []
    for outputs in (1, 7, 60):
        sim = build()
        sim.integrate(1.0)
        sim.dt = u
        h = first_step(sim, lambda: sim.integrate(1.5))
        assert h <= u*(1 + 1e-12)
        n = sim.integrator.n_steps
        for k in range(1, outputs + 1):
            sim.integrate(1.5 + 4.0*k/outputs)
        runs.append((state(sim), sim.integrator.n_steps - n))
    for outputs, (x, n) in zip((7, 60), runs[1:]):
        assert x.tobytes() == runs[0][0].tobytes(), f"{outputs} outputs"
        assert n == runs[0][1], f"{outputs} outputs"


@pytest.mark.parametrize("build", [lambda: kepler(e=0.6), two_planets], ids=["kepler", "two-planets"])
@pytest.mark.parametrize("u", [0.1, 0.15, 0.3, 1.0])
def test_a_users_dt_at_least_the_time_to_the_next_output_caps_as_in_one_call(build, u):
    # REBOUND cuts such a sim.dt to finish on the next output, so pfvi saw
    # only the cut and showed the output from the run's own step past it: the
    # user's value capped a single call's first step but not the outputs' (a
    # hostile trial: 7 steps against 5, 9.0e-10 apart on Kepler at u = 0.3).
    # It now caps the step from the output, shown from there.
    runs = []
    for times in ([4.0], [1.0 + 0.1*k for k in range(1, 31)]):
        sim = build()
        sim.integrate(1.0)
        sim.dt = u
        n = sim.integrator.n_steps
        for t in times:
            sim.integrate(t)
        runs.append((state(sim), sim.integrator.n_steps - n))
    assert runs[1][0].tobytes() == runs[0][0].tobytes()
    assert runs[1][1] == runs[0][1]


def add_planet(sim):
    sim.add(m=1e-6, a=2.3, e=0.1, f=1.0)


def add_test_particle(sim):
    sim.add(m=0.0, a=1.4, e=0.2, f=2.0)


def remove_last(sim):
    sim.remove(sim.N - 1)


@pytest.mark.parametrize("edit", [("epsilon", 1e-5), ("epsilon", 1e-8), ("stages", 5), ("stages", 3),
                                  ("particles", add_planet), ("particles", add_test_particle),
                                  ("particles", remove_last)],
                         ids=["epsilon-1e-5", "epsilon-1e-8", "stages-5", "stages-3", "add-planet",
                              "add-test-particle", "remove"])
@pytest.mark.parametrize("build", [lambda: kepler(e=0.6), two_planets], ids=["kepler", "two-planets"])
def test_an_edit_at_an_output_leaves_the_run_independent_of_the_outputs_after_it(build, edit):
    # The step from an edited output was capped by the sim.dt REBOUND
    # restored after the last call (its last full step, set by the output
    # times), and not capped where REBOUND cut it to finish on the next
    # output (a hostile trial: epsilon 1e-5 set at t = 2.09, 7 steps to t =
    # 4.6 in one call, 6 with one more output; 124 of 200 fuzzed runs off;
    # a particle added or removed there, 18 of 28 and 5 of 40).
    name, value = edit
    runs = []
    for before, after in (([2.0884907111347983], [4.597597792967187]),
                          ([0.3, 0.7, 1.4, 2.0884907111347983], [2.7520986472187796, 3.1, 4.597597792967187]),
                          ([2.0884907111347983], [2.1 + 0.1*k for k in range(25)] + [4.597597792967187])):
        sim = build()
        for t in before:
            sim.integrate(t)
        if name == "particles":
            value(sim)
        else:
            setattr(sim.integrator, name, value)
        for t in after:
            sim.integrate(t)
        runs.append((state(sim).tobytes(), sim.integrator.n_steps))
    assert runs[1] == runs[0] and runs[2] == runs[0]


def test_a_dt_equal_to_the_time_to_the_next_output_twice_in_a_row_caps_two_steps_once_each():
    # The second such sim.dt, set where the simulation held the run's own
    # step end (the first cap ended exactly on its output), waited for the
    # next call, whose sim.dt REBOUND restored to it (a hostile trial: 14
    # steps against 12 with the output, 2.8e-10 apart).
    t = [1.5133332506383181, 1.553739909954983, 1.5834587606160988, 4.247171028310783]
    runs = []
    for with_output in (False, True):
        sim = retrograde_planets()
        sim.integrate(t[0])
        sim.dt = t[1] - t[0]
        sim.integrate(t[1])
        sim.dt = t[2] - t[1]
        if with_output:
            sim.integrate(t[2])
        sim.integrate(t[3])
        runs.append((state(sim).tobytes(), sim.integrator.n_steps))
    assert runs[0] == runs[1]


def test_a_snapshot_at_a_calls_start_or_end_restarted_with_a_call_to_its_own_time_goes_on_as_the_run(tmp_path):
    # REBOUND writes the call's first snapshot after cutting sim.dt to finish
    # on the output, and its last after restoring sim.dt, before pfvi's end
    # of the call replaces that; restarted, integrate() to the snapshot's own
    # time takes no step, and the next call took the cut or the restore for
    # a sim.dt of the user's (a hostile trial: 3.4e-2 off; 0.2 where the
    # runs ended at different times).
    path = str(tmp_path / "run.bin")
    times = [0.4, 0.5, 0.6, 0.7]
    sim = two_planets()
    sim.save_to_file(path, interval=0.1, delete_file=True)
    for t in times:
        sim.integrate(t)
    sim.steps(1)
    archive = rebound.Simulationarchive(path)
    cut = 0
    for k in range(len(archive)):
        again = archive[k]
        if again.t > times[-1]:
            continue   # (written by the steps(1) after the outputs)
        ahead = [t for t in times if t > again.t]
        cut += bool(ahead and abs(again.t + again.dt - ahead[0]) < 1e-12)
        for t in times:
            if t >= again.t:
                again.integrate(t)
        again.steps(1)
        assert (again.t, state(again).tobytes()) == (sim.t, state(sim).tobytes()), f"snapshot {k} at t = {archive[k].t}"
    assert cut >= 3   # (the call-start snapshots holding REBOUND's cut are among them)


@pytest.mark.parametrize("call", ["steps", "integrate"])
@pytest.mark.parametrize("u", [0.01, -0.1])
def test_a_copy_made_after_steps_or_edited_before_steps_judges_dt_as_the_original(call, u, tmp_path):
    # sim.steps() runs no integrate(): a copy made after it, or a copy or load
    # at an output stepped with steps() after an edit, took the user's sim.dt
    # for the snapshot's (first step 0.69 where the original's was 0.01; a
    # copy ending at t = 0 where its original went to 0.18; a hostile trial).
    for before in ("steps", "output"):
        sim = kepler(e=0.6)
        if before == "steps":
            sim.steps(2)
        else:
            sim.integrate(0.28493343604320753)
        copies = [sim.copy()]
        path = str(tmp_path / f"{before}.bin")
        sim.save_to_file(path, delete_file=True)
        copies.append(rebound.Simulation(path))
        for s in [sim] + copies:
            s.dt = u
            if call == "steps":
                s.steps(2)
            else:
                s.integrate(s.t + 5*u)
        for s in copies:
            assert s.t == sim.t and state(s).tobytes() == state(sim).tobytes(), before


@pytest.mark.parametrize("u", [0.01, 0.29])
def test_a_users_dt_set_on_a_copy_or_before_an_archive_caps_as_on_the_run(u, tmp_path):
    # A copy made at an output, or a snapshot sim.save_to_file writes between
    # calls or REBOUND's archive at a call's start, holds sim.dt as the user
    # left it. Before, a loaded simulation's first call took it for REBOUND's
    # own: a sim.dt set on a copy did not cap (1.0e-11 from the original under
    # the same edit), and an archive's first snapshot, written just after an
    # edit, restarted 2.7e-11 off. (A u equal to the time to the next output
    # is REBOUND's cut there as well: docs/outputs.md.)
    sim = two_planets()
    sim.integrate(1.0)
    sim.integrate(2.0)
    other = sim.copy()
    times = [2.0 + 0.3*k for k in range(1, 12)]
    for s in (sim, other):
        s.dt = u
        for t in times:
            s.integrate(t)
    assert state(other).tobytes() == state(sim).tobytes()
    path = str(tmp_path / "edited.bin")
    sim = two_planets()
    sim.integrate(1.0)
    sim.integrate(1.5)
    sim.dt = u
    sim.save_to_file(path, interval=0.37, delete_file=True)
    times = [1.5 + 0.3*k for k in range(1, 12)]
    for t in times:
        sim.integrate(t)
    archive = rebound.Simulationarchive(path)
    assert len(archive) > 5
    for k in range(len(archive)):
        restarted = archive[k]
        for t in times:
            if t > restarted.t:
                restarted.integrate(t)
        assert state(restarted).tobytes() == state(sim).tobytes(), f"snapshot {k} at t = {archive[k].t}"


def test_a_snapshot_before_an_output_on_a_step_end_restarts_bit_identically(tmp_path):
    # An archive of every step holds, just before an output on the next step
    # end, the sim.dt REBOUND cut to finish there; restarted, the first call's
    # one step is its last, and REBOUND restores that cut after it (a hostile
    # trial: 45 of 68 such restarts ended off the run before, up to 1.4e-7).
    build, T = (lambda: kepler(e=0.9, epsilon=1e-6)), 30.0
    ends = step_ends(build, T)
    checked = 0
    for k in range(1, len(ends) - 1, 5):
        path = str(tmp_path / f"run{k}.bin")
        sim = build()
        sim.save_to_file(path, step=1)
        sim.integrate(ends[k])
        sim.integrate(T)
        archive = rebound.Simulationarchive(path)
        for i in range(len(archive)):
            snap = archive[i]
            if snap.t != ends[k - 1]:
                continue
            snap.integrate(ends[k])
            snap.integrate(T)
            assert state(snap).tobytes() == state(sim).tobytes(), (k, ends[k])
            checked += 1
    assert checked >= 8


def test_steps_after_an_output_on_a_step_end_take_the_runs_steps():
    # REBOUND restores, after integrate(), the value the call began with where
    # the run's step landed on the time uncut: pfvi's own proposal (after any
    # call before), which a steps() right after goes on from (the build before:
    # 7 to 10 of 15 such runs off).
    build = lambda: kepler(e=0.9, epsilon=1e-9)
    ends = step_ends(build, 25.0)
    for k in range(5, min(len(ends) - 4, 50), 3):
        shown = build()
        shown.steps(1)
        shown.integrate(ends[k])
        shown.steps(3)
        plain = build()
        plain.steps(k + 4)
        assert state(shown).tobytes() == state(plain).tobytes(), ends[k]


def test_a_dt_set_after_an_output_on_a_step_end_caps_the_step():
    sim = kepler(e=0.5, epsilon=1e-7)
    ends = step_ends(lambda: kepler(e=0.5, epsilon=1e-7), 5.0)
    sim.integrate(ends[2])
    t = sim.t
    sim.dt = 0.01
    sim.steps(1)
    assert sim.t - t == pytest.approx(0.01, rel=1e-12)


@pytest.mark.parametrize("exact_finish_time", [1, 0])
@pytest.mark.parametrize("dt", [0.05, 0.001, -0.001])
def test_a_dt_set_between_steps_calls_caps_every_step(exact_finish_time, dt):
    # sim.steps() leaves dt_last_done as it was, and a new simulation's first
    # steps() finds it zero as integrate() does: a user's sim.dt equal to the
    # one the simulation began with is still the user's (a hostile trial: the
    # second step went 0.2434 instead of 0.05, and 1.443 instead of 0.001).
    sim = kepler(e=0.5, epsilon=1e-7)
    sim.exact_finish_time = exact_finish_time
    if dt == 0.05:
        sim.dt = dt
    else:
        sim.steps(4)
    for _ in range(4):
        t = sim.t
        sim.dt = dt
        sim.steps(1)
        assert abs(sim.t - t) <= abs(dt)*(1 + 1e-12)
        assert abs(sim.t - t) >= 0.5*abs(dt)


def test_an_output_is_as_accurate_as_the_run():
    # The output step's error against the run's own: each output of a
    # 100-per-orbit cadence against IAS15 at 1e-12, and the run's own states
    # at its step ends (exact_finish_time = 0) against the same.
    T, times = 3*2*math.pi, cadence(3*2*math.pi, 2*math.pi, 100)

    def errors(sim, exact):
        ref = kepler()
        ref.integrator = "ias15"
        ref.integrator.epsilon = 1e-12
        out = []
        for t in times:
            sim.integrate(t, exact_finish_time=exact)
            ref.integrate(sim.t, exact_finish_time=1)
            out.append(np.abs(state(sim)[:, :3] - state(ref)[:, :3]).max())
        return np.array(out)

    shown = errors(kepler(), 1)
    own = errors(kepler(), 0)
    # Measured: 1.03 times the steps' largest error (1.1e-7 AU after 3 orbits; e = 0.9: 1.17).
    assert shown.max() <= 3*own.max()
    assert own.max() < 1e-6


def test_archive_written_at_an_output_restarts_bit_identically(tmp_path):
    path = str(tmp_path / "outputs.bin")
    sim = encke()
    times = cadence(2*2.2**1.5, 2.2**1.5, 10)
    for t in times[:7]:
        sim.integrate(t)
    sim.save_to_file(path)
    loaded = rebound.Simulation(path)
    assert loaded.integrator.n_outputs == sim.integrator.n_outputs
    for s in (sim, loaded):
        for t in times[7:]:
            s.integrate(t)
    assert state(loaded).tobytes() == state(sim).tobytes()
    assert loaded.integrator.n_steps == sim.integrator.n_steps


def test_an_edit_at_an_output_starts_from_the_users_state():
    def edited(edit):
        sim = kepler()
        sim.integrate(1.0)
        assert sim.integrator.output_t_real > 1.0  # the run's state lies past the output
        if edit:
            sim.particles[1].vx += 1e-6
        sim.integrate(1.5)
        return sim
    sim, unedited = edited(True), edited(False)
    # A fresh simulation from the edited state at t = 1.
    fresh = kepler()
    fresh.integrate(1.0)
    fresh.particles[1].vx += 1e-6
    start = state(fresh)
    again = rebound.Simulation()
    again.add(m=1.0)
    again.add(m=1e-3)
    for p, row in zip(again.particles, start):
        p.x, p.y, p.z, p.vx, p.vy, p.vz = row
    again.t = 1.0
    again.integrator = "pfvi"
    again.integrate(1.5)
    # Measured: 1.4e-9 from the fresh run (its first step differs), 4.6e-7
    # from the run that ignored the edit.
    assert np.abs(state(again) - state(sim)).max() < 1e-8
    assert np.abs(state(unedited) - state(sim)).max() > 1e-7


def test_an_option_changed_at_an_output_starts_from_the_shown_state():
    sim = kepler()
    sim.integrate(1.0)
    sim.integrator.epsilon = 1e-8
    sim.integrate(1.3)
    assert sim.integrator.output_last_t0 == 1.0  # the first step started at the shown time


def test_exact_finish_time_0_shows_no_output():
    sim = kepler()
    for t in (1.0, 2.0, 3.0):
        sim.integrate(t, exact_finish_time=0)
        assert sim.t >= t
    assert sim.integrator.n_outputs == 0


def test_backward_outputs_leave_the_run_bit_identical():
    one = run(kepler, [-10.0])
    many = run(kepler, [-k*0.1 for k in range(1, 101)])
    assert state(many).tobytes() == state(one).tobytes()
    assert many.integrator.n_steps == one.integrator.n_steps


@needs_python_heartbeat
def test_heartbeat_sees_the_requested_times():
    sim = kepler()
    seen = []
    sim.heartbeat = lambda s: seen.append(sim.t)
    times = [0.37*k for k in range(1, 20)]
    for t in times:
        sim.integrate(t)
    assert set(times) <= set(seen)
    # Steps and outputs alike go forward: no heartbeat ever sees t run back.
    assert all(b >= a for a, b in zip(seen, seen[1:]))


def planet_and_retrograde_particle():
    sim = rebound.Simulation()
    sim.add(m=1.0)
    sim.add(m=1e-3, a=1.0, e=0.9)
    sim.add(m=1e-4, a=2.5, e=0.3, f=2.0)
    sim.add(a=1.8, e=0.6, inc=3.0, f=1.0)
    sim.move_to_com()
    sim.integrator = "pfvi"
    return sim


@needs_python_heartbeat
@pytest.mark.parametrize("build", [kepler, planet_and_retrograde_particle])
@pytest.mark.parametrize("seed", [0, 1])
def test_no_state_past_the_requested_time_is_shown(build, seed):
    # REBOUND decides whether a step finishes on the requested time by
    # comparing t + sim.dt with it; pfvi's step may be longer than sim.dt (a
    # new simulation's first, a symmetric step longer than it proposed), and
    # such a step was shown, to the heartbeat and REBOUND's collision search,
    # at its end past the time before the call came back to it (a hostile
    # trial: 20-30 calls of 4000 at random times, and every new
    # simulation's first call to a time inside its first step).
    times = np.sort(np.random.default_rng(seed).uniform(0.0, 10.0, 200))
    sim = build()
    seen = []
    sim.heartbeat = lambda s: seen.append((s.contents.t, s.contents.dt_last_done))
    for t in times:
        first = len(seen)
        sim.integrate(t)
        assert sim.t == t
        assert all(shown <= t and lived >= 0. for shown, lived in seen[first:])
    one = build()
    one.integrate(times[-1])
    assert state(sim).tobytes() == state(one).tobytes()
    assert sim.integrator.n_steps == one.integrator.n_steps


@pytest.mark.parametrize("t_first", [0.1, -0.01])
def test_steps_after_a_first_output_inside_the_first_step_go_on_with_the_run(t_first):
    # A new simulation's first integrate() to a time inside its first step
    # shows that time without REBOUND's finishing step; sim.dt after it is
    # what that finish would leave (the run's step), not REBOUND's 0.001,
    # which sim.steps() would take for a cap (a second hostile trial: after
    # integrate(0.1), steps(3) ended at 0.101, 0.430, 0.999 instead of the
    # run's 0.297, 0.760, 1.635).
    def build():
        sim = kepler(e=0.5)
        sim.dt = math.copysign(sim.dt, t_first)
        return sim
    own = build()
    ends = []
    for _ in range(3):
        own.steps(1)
        ends.append(own.t)
    sim = build()
    sim.integrate(t_first)
    assert sim.t == t_first
    seen = []
    for _ in range(3):
        sim.steps(1)
        seen.append(sim.t)
    assert seen == ends
    assert state(sim).tobytes() == state(own).tobytes()


def approaching_body():
    # A star, a planet at e = 0.5 and a small body closing on it at relative
    # speed 1: 0.12 apart at t = 0.077, inside pfvi's first step (0.297).
    sim = rebound.Simulation()
    sim.add(m=1.0)
    sim.add(m=1e-3, a=1.0, e=0.5)
    p = sim.particles[1]
    sim.add(m=1e-6, x=p.x, y=p.y + 0.2, vx=p.vx, vy=p.vy - 1.0)
    sim.move_to_com()
    sim.integrator = "pfvi"
    sim.exit_min_distance = 0.12
    return sim


@pytest.mark.parametrize("spacing", [0.002, 0.01, 0.03])
def test_an_encounter_is_raised_by_the_call_that_reaches_it(spacing):
    sim = approaching_body()
    calls = [spacing*k for k in range(1, int(0.2/spacing) + 1)]
    raised_in = None
    for t in calls:
        try:
            sim.integrate(t)
        except rebound.Encounter:
            raised_in = t
            break
        assert sim.t == t
    # (REBOUND raised it from a call to 0.002, 0.01 or 0.03 at t = 0.077.)
    assert raised_in is not None and raised_in >= 0.077 > raised_in - spacing
    assert 0.0765 < sim.t <= raised_in


@needs_python_heartbeat
@pytest.mark.parametrize("outputs", [5, 50, 500])
@pytest.mark.parametrize("sign", [1, -1])
def test_heartbeats_dt_last_done_at_an_output_is_the_time_it_lived(outputs, sign):
    # REBOUND's heartbeat runs after each step. At a requested time shown
    # from the run, dt_last_done is now the time since the state REBOUND
    # held before, as after a step cut to that time (the build before
    # reported the run's proposal there: up to 0.48 more than the time
    # passed at 50 outputs over 20 time units). The step that takes the run
    # up again reports the proposal still: REBOUND restores sim.dt from it.
    def build():
        sim = kepler_planets()
        sim.add(m=0.0, a=1.7, e=0.6, inc=2.8)   # a retrograde crosser
        sim.integrator = "pfvi"
        return sim

    T = sign*20.0
    times = [T*(k + 1)/outputs for k in range(outputs)]
    sim = build()
    seen = []
    sim.heartbeat = lambda simp: seen.append((simp.contents.t, simp.contents.dt_last_done))
    for t in times:
        sim.integrate(t)
    at_outputs = [(b[1], b[0] - a[0]) for a, b in zip(seen, seen[1:]) if b[0] in times and b[1] != 0.]
    assert len(at_outputs) >= outputs//2
    assert max(abs(done - lived) for done, lived in at_outputs) <= 1e-14*abs(T)
    # Steps and outputs alike go forward, and the run is one call's.
    assert all((b[0] - a[0])*sign >= 0. for a, b in zip(seen, seen[1:]))
    one = run(build, [T])
    assert state(sim).tobytes() == state(one).tobytes()
    assert sim.integrator.n_steps == one.integrator.n_steps


def test_variational_particles_and_megno_with_outputs():
    def build():
        sim = kepler_planets()
        sim.init_megno(seed=1)
        return sim
    one = run(build, [20.0])
    many = run(build, [0.25*k for k in range(1, 81)])
    plain = run(lambda: kepler_planets(), [20.0])
    assert state(many).tobytes() == state(one).tobytes()
    assert state(plain).tobytes() == state(one).tobytes()  # the real run, with or without them
    # Y at the output, from the output step's share: as the single call's.
    assert many._megno_Ys == pytest.approx(one._megno_Ys, rel=1e-12)
    assert np.abs(np.array([[p.x, p.vx] for p in many.particles_var])
                  - np.array([[p.x, p.vx] for p in one.particles_var])).max() == 0.0


def kepler_planets():
    sim = rebound.Simulation()
    sim.add(m=1)
    sim.add(m=1e-3, a=1.0, e=0.4)
    sim.add(m=1e-3, a=2.3, e=0.2, inc=0.1)
    sim.move_to_com()
    sim.integrator = "pfvi"
    return sim


def test_a_refused_step_after_an_output_leaves_the_output_shown():
    # The force turns non-finite (a callback pfvi cannot see change) while
    # an output is shown: an output inside the step is refused with the
    # simulation as the call found it, bit for bit; so is a call past the
    # step (the forces at the run's state, evaluated to see whether they
    # changed since the output, are not finite: pfvi_output_forces_hold).
    broken = {"on": False}

    def force(sim_pointer):
        if broken["on"]:
            sim_pointer.contents.particles[1].ax = float("nan")

    sim = kepler()
    sim.additional_forces = force
    sim.integrate(1.0)
    t_real = sim.integrator.output_t_real
    before = (sim.t, state(sim).tobytes())
    broken["on"] = True
    with pytest.raises(RuntimeError):
        sim.integrate(0.5*(1.0 + t_real))
    assert (sim.t, state(sim).tobytes()) == before
    with pytest.raises(RuntimeError):
        sim.integrate(2.0)
    assert (sim.t, state(sim).tobytes()) == before
    broken["on"] = False
    sim.integrate(2.0)  # and goes on from there
    assert sim.t == 2.0


def _sun_jupiter_saturn_comet():
    sim = rebound.Simulation()
    sim.add(m=1.0)
    sim.add(m=9.547919e-4, a=5.2, e=0.048, inc=0.0228)
    sim.add(m=2.858860e-4, a=9.58, e=0.056, inc=0.0434, Omega=1.98, omega=5.9, M=3.1)
    sim.add(m=0.0, a=2.2, e=0.85, inc=0.2, omega=1.0, M=0.5)
    sim.move_to_com()
    sim.integrator = "pfvi"
    return sim


@pytest.mark.parametrize("build, T, interval, times", [
    (_sun_jupiter_saturn_comet, 100.0, 3.7, "even 40"),
    (_sun_jupiter_saturn_comet, 100.0, 1.3, "random 300"),
    (encke, 10.0, 0.37, "even 40"),
    (lambda: kepler(e=0.9), 60.0, 2.9, "random 300"),
])
def test_every_snapshot_written_during_outputs_restarts_bit_identically(tmp_path, build, T, interval, times):
    # issue 40, item 5: REBOUND writes a snapshot of save_to_file(interval)
    # after deciding to finish on the next output, with sim.dt cut to reach
    # it, and (where the run's last step passed that output) with the run's
    # state, before the call that shows it. Restarted, that cut capped the
    # next step (2.6e-8 off at t = 100 on the first scene's snapshot at
    # t = 2.52; the issue saw 10 of 28). Each snapshot, restarted with the
    # outputs still to come and with one call, ends where the run ended.
    kind, n = times.split()
    times = (np.linspace(0.0, T, int(n) + 1)[1:].tolist() if kind == "even"
             else cadence(T, 1.0, rand=int(n), seed=3))
    path = str(tmp_path / "run.bin")
    sim = build()
    sim.save_to_file(path, interval=interval)
    for t in times:
        sim.integrate(t)
    final = state(sim).tobytes()
    archive = rebound.Simulationarchive(path)
    assert len(archive) >= T/interval
    cut = 0
    for i in range(len(archive)):
        for single in (False, True):
            snap = archive[i]
            cut += snap.dt != snap.integrator.dt_proposed
            for t in ([T] if single else [t for t in times if t > snap.t]):
                snap.integrate(t)
            assert state(snap).tobytes() == final, (i, single, archive[i].t)
    assert cut > 0  # the snapshots the case is about are among them


def kepler_from(t0, e=0.9):
    sim = rebound.Simulation()
    sim.add(m=1.0)
    sim.add(m=1e-3, a=1.0, e=e)
    sim.move_to_com()
    sim.t = t0
    return sim


def largest_difference(a, b):
    return max(abs(x - y) for p, q in zip(a.particles, b.particles) for x, y in zip(p.xyz, q.xyz))


@pytest.mark.parametrize("t0", [1e10, 1e13])
def test_a_run_from_a_large_t_ends_on_the_requested_time(t0):
    # The state shown for a requested time is that time's, not one within
    # 1e-12 of |t| (at t = 1e10 that took a state 0.005 early as the
    # target's: 0.017 off on Kepler e = 0.9; hostile trial).
    sim = kepler_from(t0)
    sim.integrator = "pfvi"
    sim.integrate(t0 + 20 * math.pi)
    ref = kepler_from(0.0)
    ref.integrator = "ias15"
    ref.integrator.epsilon = 1e-13
    ref.integrate(sim.t - t0)
    assert largest_difference(sim, ref) < 1e-5   # (3.1e-7 from t = 0)


def test_outputs_from_a_large_t_are_the_requested_times():
    t0 = 1e9
    sim = kepler_from(t0)
    sim.integrator = "pfvi"
    sim.integrator.epsilon = 1e-8
    ref = kepler_from(0.0)
    ref.integrator = "ias15"
    ref.integrator.epsilon = 1e-13
    worst = 0.0
    for k in range(1, 301):
        sim.integrate(t0 + k * 20 * math.pi / 300)
        ref.integrate(sim.t - t0)
        worst = max(worst, largest_difference(sim, ref))
    assert worst < 1e-6   # (2.7e-3 before, with 3000 outputs; IAS15 itself 1e-4 there)


def _two_planets():
    sim = rebound.Simulation()
    sim.add(m=1.0)
    sim.add(m=1e-3, a=1.0, e=0.5)
    sim.add(m=1e-3, a=2.2, e=0.1, inc=0.2)
    sim.move_to_com()
    return sim


def _with_force(integrator, change_at, velocity_dependent):
    """A force read from a variable the callback owns, changed at an output."""
    k = {"on": 0.0}

    def force(sim_pointer):
        p = sim_pointer.contents.particles[1]
        if velocity_dependent:
            p.ax -= k["on"]*p.vx
            p.ay -= k["on"]*p.vy
        else:
            p.ax += k["on"]

    sim = _two_planets()
    sim.additional_forces = force
    sim.force_is_velocity_dependent = int(velocity_dependent)
    sim.integrator = integrator
    sim.integrator.epsilon = 1e-10 if integrator == "pfvi" else 1e-12
    sim.integrate(change_at)
    k["on"] = 0.02
    sim.integrate(9.7)
    return state(sim)


@pytest.mark.parametrize("velocity_dependent", [False, True])
@pytest.mark.parametrize("change_at", [3.3, 5.05])
def test_a_force_changed_between_calls_acts_from_the_output(change_at, velocity_dependent):
    # The run's step past the output was made with the old force; one
    # evaluation at its state shows the change, and the run goes on from the
    # output as after an edit (before: from the step's end, 2.4e-3 off IAS15).
    pfvi = _with_force("pfvi", change_at, velocity_dependent)
    ias15 = _with_force("ias15", change_at, velocity_dependent)
    assert np.max(np.abs(pfvi[:, :3] - ias15[:, :3])) < 1e-9*np.max(np.abs(ias15[:, :3]))


@pytest.mark.parametrize("velocity_dependent", [False, True])
@pytest.mark.parametrize("stages, outputs", [(8, 40), (8, 400), (3, 400)])
def test_an_unchanged_force_keeps_the_run_independent_of_its_outputs(velocity_dependent, stages, outputs):
    # The check evaluates the force again at the run's state; with nothing
    # changed it finds the step's bits (with a velocity-dependent force: the
    # evaluation made when the output was shown), so the run is not restarted
    # at any output: 40 outputs take the steps of one call (a check that
    # misfired took 113 steps for 44 here). With a velocity-dependent force
    # a second output inside one step replaced the run's end force (the end
    # stage's, at the stage velocity) by the force at the end velocity, and
    # the run ended up to 2e-14 from the single call (s = 8); it now keeps it
    # (pfvi_step_start's keep_end).
    def build():
        sim = _two_planets()

        def force(sim_pointer):
            p = sim_pointer.contents.particles[1]
            p.ax -= 1e-3*p.vx if velocity_dependent else -1e-4
        sim.additional_forces = force
        sim.force_is_velocity_dependent = int(velocity_dependent)
        sim.integrator = "pfvi"
        sim.integrator.epsilon = 1e-9
        sim.integrator.stages = stages
        return sim

    one, many = build(), build()
    one.integrate(12.0)
    for t in np.linspace(0.3, 12.0, outputs):
        many.integrate(t)
    assert many.integrator.n_outputs >= 0.75*outputs
    assert many.integrator.n_steps == one.integrator.n_steps
    assert state(many).tobytes() == state(one).tobytes()


@pytest.mark.parametrize("outputs", [40, 1000])
def test_a_force_that_reads_t_keeps_the_run_independent_of_its_outputs(outputs):
    # The check at an output evaluated the force at the run's t after its
    # relabelling (t's rounding folded in), an ulp from the t0 + h the step
    # evaluated it at: a force reading t differed in its last bits there, the
    # run was taken as edited, and 1000 outputs took 290 steps against one
    # call's 262, 3.4e-12 apart (a hostile trial, Kepler e = 0.99).
    def build():
        sim = rebound.Simulation()
        sim.add(m=1.0)
        sim.add(m=1e-3, a=1.0, e=0.99)
        sim.add(m=1e-4, a=3.0, e=0.3, inc=0.2)
        sim.move_to_com()

        def force(sim_pointer):
            s = sim_pointer.contents
            for k in (1, 2):
                s.particles[k].ax += 1e-3*math.sin(s.t)
        sim.additional_forces = force
        sim.integrator = "pfvi"
        sim.integrator.epsilon = 1e-9
        return sim

    one, many = build(), build()
    one.integrate(30.0)
    for t in np.linspace(0.0, 30.0, outputs + 1)[1:]:
        many.integrate(t)
    assert many.integrator.n_steps == one.integrator.n_steps
    assert state(many).tobytes() == state(one).tobytes()


def _approach():
    # Two planets on circular orbits 0.3 apart: their separation first
    # falls below the tests' 0.29 at t = 3.577 (the search on from the start).
    sim = rebound.Simulation()
    sim.add(m=1.0)
    sim.add(m=1e-3, a=1.0, e=0.0)
    sim.add(m=1e-3, a=1.3, e=0.0, f=1.2)
    sim.move_to_com()
    sim.integrator = "pfvi"
    sim.integrator.epsilon = 1e-10
    return sim


@pytest.mark.parametrize("how", ["exit_min_distance", "radii"])
def test_a_contact_search_set_at_an_output_searches_the_rest_of_the_step(how):
    limit = 0.29

    def arm(sim):
        if how == "exit_min_distance":
            sim.exit_min_distance = limit
        else:
            sim.collision = "direct"
            sim.collision_resolve = "halt"
            for p in sim.particles[1:]:
                p.r = limit/2

    def contact(sim, t_out):
        if t_out is None:
            arm(sim)
        else:
            sim.integrate(t_out)
            arm(sim)
        with pytest.raises((rebound.Encounter, rebound.Collision)):
            sim.integrate(20.0)
        return sim.t

    first = contact(_approach(), None)
    for t_out in np.linspace(first - 1.0, first - 0.01, 9):
        # (each output inside one of the run's steps, or on its end)
        # (From the output the run restarts: its contact time moves by the
        # output step's error, 1.3e-9 here; before, the contact was missed or
        # found 0.016 late.)
        assert contact(_approach(), t_out) == pytest.approx(first, abs=1e-7)


def periodic_box(ghosts, light=False, boundary="periodic"):
    """A box of 10 that bodies cross: REBOUND wraps them after each step
    (boundary 'periodic'), with or without a layer of ghost boxes, or
    removes them (boundary 'open')."""
    sim = rebound.Simulation()
    sim.root_size = 10.0
    sim.N_root_x = sim.N_root_y = sim.N_root_z = 1
    sim.boundary = boundary
    sim.N_ghost_x = sim.N_ghost_y = ghosts
    if light:   # one body of 1e-3 and two test particles it barely pulls
        sim.add(m=1e-3, x=1.0, vy=0.3)
        sim.add(m=0.0, x=-2.0, y=1.0, vx=0.4)
        sim.add(m=0.0, x=3.0, y=-3.0, vz=0.2)
    else:       # a star, a planet, a test particle and two bodies leaving
        sim.add(m=1.0)
        sim.add(m=1e-3, a=1.0, e=0.3)
        sim.add(m=0.0, a=2.0, e=0.2, f=1.0)
        sim.add(m=0.0, x=-2.0, y=1.0, vx=1.4)
        sim.add(m=1e-4, x=3.0, y=-3.0, vz=0.3, vx=1.1)
    sim.integrator = "pfvi"
    return sim


@pytest.mark.parametrize("ghosts, light", [(0, False), (1, False), (0, True), (1, True)])
@pytest.mark.parametrize("outputs", ["100 even", "300 random"])
def test_outputs_in_a_periodic_box_leave_the_run_bit_identical(ghosts, light, outputs):
    # REBOUND's periodic wrap after each step met the output shown, not the
    # run's own end behind it: the run went on from the output (the build
    # before: 63 steps against one call's 58 at 100 outputs, 0.34 apart;
    # the light box 12 against 9 at 40). pfvi wraps the run's end as a
    # single call has it (pfvi_output.c, pfvi_output_boundary).
    T = 30.0
    build = lambda: periodic_box(ghosts, light)  # noqa: E731
    one = run(build, [T])
    times = cadence(T, T/100, per_orbit=1) if outputs == "100 even" else cadence(T, T, rand=300)
    many, shown, jumps = build(), [], 0
    for t in times:
        many.integrate(t)
        shown.append(state(many)[:, :3])
    # The case is about wraps: bodies jump by the box between outputs.
    jumps = sum(int((abs(b - a) > 5.0).any()) for a, b in zip(shown, shown[1:]))
    assert jumps >= 2
    assert state(many).tobytes() == state(one).tobytes()
    a, b = one.integrator, many.integrator
    assert (b.n_steps, b.n_rejected, b.n_asymmetric) == (a.n_steps, a.n_rejected, a.n_asymmetric)
    assert b.n_outputs >= len(times) - 1


@pytest.mark.parametrize("epsilon", [1e-6, 1e-9])
@pytest.mark.parametrize("outputs", ["100 even", "300 random"])
def test_outputs_in_an_open_box_leave_the_run_bit_identical(epsilon, outputs):
    # REBOUND removes a body that left an open box after each step: behind
    # an output, from the output, and the run went on from there (the build
    # before: 477 of 1022 random open boxes off the single call,
    # benchmarks/outputs_edges.py). pfvi removes it from the run's end before
    # the output is drawn, as a single call has it (pfvi_output_removed).
    T = 30.0
    def build():
        sim = periodic_box(0, boundary="open")
        sim.integrator.epsilon = epsilon
        return sim

    one = run(build, [T])
    times = cadence(T, T/100, per_orbit=1) if outputs == "100 even" else cadence(T, T, rand=300)
    many = run(build, times)
    assert many.N == one.N < build().N   # bodies left the box
    assert state(many).tobytes() == state(one).tobytes()
    a, b = one.integrator, many.integrator
    assert (b.n_steps, b.n_rejected, b.n_asymmetric) == (a.n_steps, a.n_rejected, a.n_asymmetric)
    assert b.n_outputs >= len(times) - 1


@pytest.mark.parametrize("outputs", [10, 100])
def test_a_hook_over_free_motion_keeps_the_runs_step_after_each_output(outputs):
    # With a post-timestep hook REBOUND cuts each call's last step to its
    # time and starts the next call from the step it restores (here 0.001,
    # the capped first one's). Once the test particles have left the open
    # box the body left moves freely (u = 0, the step as it was), and the
    # build before kept that cap for good: 3012 steps at 10 outputs, 3561 at
    # 100, against one call's 2. A cap holds one step; the next is the run's.
    def build():
        sim = rebound.Simulation()
        sim.root_size = 6.0
        sim.N_root_x = sim.N_root_y = sim.N_root_z = 1
        sim.boundary = "open"
        sim.softening = 0.02
        sim.add(m=1e-3, vx=0.1, vy=-0.05)
        sim.add(m=0.0, x=1.57, y=-2.26, z=0.39, vx=0.93, vy=0.22, vz=-0.28)
        sim.add(m=0.0, x=2.77, y=1.49, z=2.68, vx=0.09, vy=0.25, vz=0.40)
        sim.integrator = "pfvi"
        return sim

    T = 5.0
    one = run(build, [T])
    many = build()
    many.post_timestep_modifications = lambda simp: None
    for k in range(outputs):
        many.integrate(T*(k + 1)/outputs)
    assert many.N == one.N == 1
    # At most the cut and the capped first step of each call beyond one call's.
    assert many.integrator.n_steps <= one.integrator.n_steps + 2*outputs
    assert np.abs(state(many) - state(one)).max() < 1e-14


@pytest.mark.parametrize("first", [2e-4, 9.9e-4])
@pytest.mark.parametrize("sign", [1, -1])
def test_a_first_output_within_rebounds_first_dt_leaves_the_run_bit_identical(first, sign):
    # A new simulation's first integrate() to a time within REBOUND's 0.001:
    # REBOUND cuts its 0.001 to that time and restores 0.001 after the call.
    # The build before took that for a value the user set, and the next call
    # capped the run's first step with it (34 steps against one call's 31,
    # 7.3e-9 apart). pfvi now knows it for REBOUND's (pfvi_step,
    # dt_call_first_cut), as it does after a first call of whole steps.
    def build():
        sim = rebound.Simulation()
        sim.add(m=1.0)
        sim.add(m=1e-3, a=1.0, e=0.5)
        sim.add(m=0.0, a=2.2, e=0.3, inc=2.5)   # a retrograde test particle
        sim.integrator = "pfvi"
        return sim

    T = sign*20.0
    one = run(build, [T])
    many = run(build, [sign*first, T/3, T])
    assert state(many).tobytes() == state(one).tobytes()
    assert many.integrator.n_steps == one.integrator.n_steps
    # A sim.dt the user set before such a call still caps, as before; so
    # does a 0.001 the user sets after a call that began with another value
    # (REBOUND restored that one: pfvi reads what the call began with where
    # REBOUND synchronizes, right before its cut; a hostile trial).
    for before, after in ((0.1, None), (0.01, 0.001)):
        capped = build()
        capped.dt = sign*before
        capped.integrate(sign*first)
        if after:
            capped.dt = sign*after
        capped.integrate(T)
        assert capped.integrator.n_steps > one.integrator.n_steps


@pytest.mark.parametrize("stages", [4, 8])
def test_outputs_on_a_way_back_to_zero_leave_the_run_bit_identical(stages):
    # A run whose step ends exactly at t = 0 (a way back to the start) took
    # every output inside that step as an output step that had failed (its
    # marker was 0, the time itself), and cut the run's step there: a
    # hyperbolic flyby's way back with 40 outputs took 4 steps against one
    # call's 2 (s = 8).
    def build():
        sim = rebound.Simulation()
        sim.add(m=1.0)
        sim.add(m=0.0, a=-2.0, e=3.0, f=-1.0)
        sim.move_to_com()
        sim.integrator = "pfvi"
        sim.integrator.stages = stages
        return sim

    T = 5.0
    one = run(build, [T, 0.0])
    many = run(build, [T*(k + 1)/40 for k in range(40)] + [T*(39 - k)/40 for k in range(40)])
    assert many.integrator.n_outputs >= 60
    assert many.integrator.n_steps == one.integrator.n_steps
    assert state(many).tobytes() == state(one).tobytes()
