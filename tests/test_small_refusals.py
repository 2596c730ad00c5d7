"""Issue 40, item 8: bad or extreme input refused clearly (naming the field or
the cause, t and every particle bit-identical), or made right."""
import math
import warnings

import pytest
import rebound

import rebound_pfvi  # noqa: F401  (registers "pfvi")


def snapshot(sim):
    return (sim.t, [(p.x, p.y, p.z, p.vx, p.vy, p.vz, p.m) for p in sim.particles])


def kepler(e=0.5, f=0.0):
    sim = rebound.Simulation()
    sim.add(m=1.0)
    sim.add(m=1e-3, a=1.0, e=e, f=f)
    sim.move_to_com()
    sim.integrator = "pfvi"
    return sim


@pytest.mark.parametrize("value", [-0.1, float("nan")])
def test_an_invalid_exit_min_distance_is_refused_naming_it(value):
    # REBOUND squares it (a negative one acted as positive there), pfvi's
    # search inside a step read it as off: neither refused it.
    sim = kepler()
    sim.exit_min_distance = value
    before = snapshot(sim)
    with pytest.raises(RuntimeError, match=r"sim\.exit_min_distance = .* is not valid; it must be finite and >= 0"):
        sim.integrate(10.0)
    assert snapshot(sim) == before


def test_fixed_steps_across_a_pericentre_are_refused_not_ejecting_the_body():
    # epsilon 0, 3 steps per orbit at e = 0.9 from apocentre: the second step
    # crosses the pericentre with its ends 2.6 radians of the fastest orbit
    # apart. It ejected the body (e 1.6, 29 AU off) with a warning of 0.093
    # per orbit; now refused, naming the pericentre.
    for stages in (8, 4):
        sim = kepler(0.9, math.pi)
        sim.integrator.epsilon = 0.0
        sim.integrator.stages = stages
        sim.dt = 2 * math.pi / 3
        sim.steps(1)
        before = snapshot(sim)
        with pytest.raises(RuntimeError, match=r"spans 9\d\.\d radians of the fastest orbit .*particle 1 passes its "
                                               r"pericentre inside it"):
            sim.steps(1)
        assert snapshot(sim) == before
        assert sim.particles[1].orbit(primary=sim.particles[0]).e < 0.901   # not ejected


def test_a_coarse_fixed_step_warning_gives_the_span_and_a_lower_bound():
    sim = kepler(0.6)
    sim.integrator.epsilon = 0.0
    sim.integrator.stages = 4
    sim.dt = 1.0
    with pytest.warns(RuntimeWarning, match=r"spans \d\.\d+ radians of the fastest orbit; particle \d's stages imply "
                                            r"a position error of at least"):
        sim.steps(6)


def test_fixed_steps_whose_estimate_saturates_warn_by_the_density():
    # e = 0.9 at sim.dt = 0.1: 5.7 radians at pericentre, where the stages'
    # estimate saturates (1.1e-3 per orbit). Before, no warning while a fell
    # by 14% in 10 orbits; steps of 0.03 (3.5 radians) stay silent and right.
    sim = kepler(0.9)
    sim.integrator.epsilon = 0.0
    sim.dt = 0.1
    with pytest.warns(RuntimeWarning, match=r"fixed step dt = 0\.1 from t = .* spans \d\.\d+ radians of the fastest "
                                            r"orbit, where steps err by more than 1e-2 per orbit \(above 2\.2\)"):
        sim.integrate(20 * math.pi)
    sim = kepler(0.9)
    sim.integrator.epsilon = 0.0
    sim.dt = 0.03
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        sim.integrate(20 * math.pi)
    assert abs(sim.particles[1].orbit(primary=sim.particles[0]).a / kepler(0.9).particles[1].orbit(
        primary=kepler(0.9).particles[0]).a - 1.0) < 1e-6


def test_fixed_steps_without_pairs_warn_where_their_stages_saturate():
    # A test particle in a Kepler potential from additional_forces (no
    # massive body, so no density to measure the step against): 170 off at
    # sim.dt = 1 without a word before.
    def potential(simp):
        for p in simp.contents.particles:
            r3 = (p.x * p.x + p.y * p.y + p.z * p.z) ** 1.5
            p.ax -= p.x / r3
            p.ay -= p.y / r3
            p.az -= p.z / r3

    for dt, warns in ((1.0, True), (0.1, True), (0.01, False)):
        sim = rebound.Simulation()
        sim.add(m=1.0)
        sim.add(m=0.0, a=1.0, e=0.9)
        sim.remove(0)
        sim.additional_forces = potential
        sim.integrator = "pfvi"
        sim.integrator.epsilon = 0.0
        sim.dt = dt
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            sim.integrate(2 * math.pi)
        said = [str(w.message) for w in caught if "is not resolved" in str(w.message)]
        assert bool(said) == warns, (dt, said)
        if warns:
            assert "no pair sets a time scale" in said[0] and len(said) == 1


def test_point_masses_colliding_are_refused_with_the_cause():
    # Two equal masses falling together head-on: the adaptive step shrinks
    # below t's rounding. The message blamed dt ("use a larger dt").
    sim = rebound.Simulation()
    sim.add(m=1.0)
    sim.add(m=1.0, x=1.0)
    sim.integrator = "pfvi"
    for _ in range(10000):
        before = snapshot(sim)
        try:
            sim.steps(1)
        except RuntimeError as error:
            message = str(error)
            break
    else:
        pytest.fail("no refusal")
    assert "particles 0 and 1," in message and "Colliding: give them radii and set sim.collision" in message
    assert "larger dt" not in message
    # Whole: REBOUND keeps 254 characters of a message and cut longer ones
    # anywhere ("... smooth it, or ": a hostile trial).
    assert message.endswith("else start t nearer 0.") and len(message) <= 254
    assert snapshot(sim) == before
    assert abs(sim.particles[1].x - sim.particles[0].x) < 1e-9


def test_an_orbit_too_fast_for_a_large_t_is_named_as_such():
    # At t = 1e15 t's last place is 0.125, longer than an e = 0.9 pericentre
    # passage: the message said the two bodies collide (hostile trial).
    sim = kepler(e=0.9)
    sim.t = 1e15
    before = snapshot(sim)
    with pytest.raises(RuntimeError, match=r"below t's last place 0\.12\. .*else start t nearer 0\."):
        sim.integrate(1e15 + 100.0)
    assert snapshot(sim) == before


def test_a_step_below_the_rounding_of_t_still_blames_dt():
    sim = kepler()
    sim.t = 1e10
    sim.dt = 1e-10
    with pytest.raises(RuntimeError, match=r"does not change t = .*Use a larger dt"):
        sim.integrate(1e10 + 1.0)


@pytest.mark.parametrize("options", [{}, {"centre": "barycentre", "stages": 4, "fitting": "exact"}])
def test_tiny_masses_move_as_their_scaled_copy(options):
    # Masses of 1e-310 (subnormal) 1e-100 apart: m x underflowed in the pair's
    # barycentre, which one step moved by half their separation; with the
    # centre "barycentre" and a fitting that uses it, in the attracting
    # bodies' barycentre (three steps moved the pair's by 5e-9 of itself,
    # and the error was 4.7 times its scaled copy's). The same
    # orbit scaled by 1e100 in length (masses 1e-10: G m/r^3 alike), run by
    # IAS15 to the same time, is the reference (the steps differ: the density
    # of subnormal masses is rounded coarser).
    def pair(m, d):
        sim = rebound.Simulation()
        sim.add(m=m)
        sim.add(m=m, x=d, vy=math.sqrt(2 * m / d) * 0.7)
        return sim
    tiny = pair(1e-310, 1e-100)
    tiny.integrator = "pfvi"
    for name, value in options.items():
        setattr(tiny.integrator, name, value)
    tiny.steps(3)
    reference = pair(1e-10, 1.0)
    reference.integrator = "ias15"
    reference.integrate(tiny.t)
    com_x = (tiny.particles[0].x + tiny.particles[1].x) / 2
    assert com_x == pytest.approx(5e-101, rel=1e-12)   # it went to 0
    for p, q in zip(tiny.particles, reference.particles):
        assert p.x * 1e100 == pytest.approx(q.x, abs=1e-9)
        assert p.y * 1e100 == pytest.approx(q.y, abs=1e-9)


@pytest.mark.parametrize("exact_finish_time", [1, 0])
def test_a_dt_set_after_an_output_is_honoured(exact_finish_time):
    # After integrate(1.0) the user sets sim.dt = 0.01: the next step is
    # 0.01, as with IAS15. With exact_finish_time = 1 (an output shown) the
    # step went on to the run's own end (0.64) instead.
    sim = kepler()
    sim.integrate(1.0, exact_finish_time=exact_finish_time)
    sim.dt = 0.01
    t0 = sim.t
    sim.steps(1)
    assert sim.t - t0 == pytest.approx(0.01, rel=1e-12)


def test_outputs_without_a_new_dt_keep_the_run_unbroken():
    # The rule above leaves the ordinary case alone: outputs at any times give
    # the single call's steps, bit for bit.
    single = kepler(0.7)
    single.integrate(20.0, exact_finish_time=0)
    many = kepler(0.7)
    for k in range(1, 40):
        many.integrate(0.5 * k)
    many.integrate(single.t, exact_finish_time=0)
    assert many.integrator.n_steps == single.integrator.n_steps
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert [p.xyz for p in many.particles] == [p.xyz for p in single.particles]


@pytest.mark.parametrize("gravity", ["mercurius", "jacobi"])
def test_a_gravity_mode_of_another_integrator_is_refused_naming_it(gravity):
    # 'mercurius': REBOUND raised mid-step, after pfvi had moved the bodies
    # (t 0.297 when the error came); 'jacobi': no force at all, free motion
    # (32 AU off after 3 orbits). Hostile trial, 2026-11-27.
    sim = kepler()
    sim.gravity = gravity
    before = snapshot(sim)
    with pytest.raises(RuntimeError, match=rf"sim\.gravity = \d+ \('{gravity}'\) is not supported"):
        sim.integrate(10.0)
    assert snapshot(sim) == before


@pytest.mark.parametrize("gravity", ["basic", "compensated", "none"])
def test_the_gravity_modes_pfvi_uses_still_run(gravity):
    sim = kepler()
    sim.gravity = gravity
    sim.integrate(1.0)
    assert sim.t == 1.0


def failing_forces_run(fail_at):
    sim = kepler()
    calls = [0]

    def forces(simp):
        calls[0] += 1
        if fail_at and calls[0] >= fail_at:
            # (from then on, and leaves forces that are not to be used)
            simp.contents.particles[1].ax += 1.0
            rebound.clibrebound.reb_simulation_error(simp, b"a force callback failed")

    sim.additional_forces = forces
    sim.force_is_velocity_dependent = 0
    return sim


def test_an_error_raised_inside_the_forces_refuses_the_step():
    # REBOUND's error inside a force evaluation (a REBOUNDx effect without its
    # parameter, a callback calling reb_simulation_error) left the step taken
    # on the forces it had left (hostile trial): now the step is refused, the
    # state is the last step's end, bit for bit, and REBOUND's message is
    # the one raised.
    sim = failing_forces_run(40)
    with pytest.raises(RuntimeError, match="a force callback failed"):
        sim.integrate(50.0)
    shown = snapshot(sim)
    reference = failing_forces_run(0)
    while reference.t < shown[0]:
        reference.steps(1)
    assert snapshot(reference) == shown
    # Each call after is refused the same way (the callback keeps failing),
    # with nothing else left in REBOUND's messages.
    with pytest.raises(RuntimeError, match="^a force callback failed$"):
        sim.integrate(50.0)
    assert snapshot(sim) == shown
