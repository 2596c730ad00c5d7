"""The symmetric step control where a body's partner pair does not show its
time scale (issue 24): flybys, crossings, a circumbinary planet, a periodic
box, forces no pair shows; the checks of a step's end; epsilon's range;
reversal and convergence at the default settings."""
import ctypes
import math

import pytest
import rebound

import rebound_pfvi
from rebound_pfvi import scenes
from rebound_pfvi.integrators import configure

DEFAULT_EPSILON = 1e-6  # the field's default, asserted in test_help_and_repr


def positions(sim):
    return [(p.x, p.y, p.z) for p in sim.particles]


def goal_ratio(scene, sim, reference, epsilon):
    """The largest position error of any body in units of epsilon a n (a its
    orbit's size, n its orbits over the run): the issue's goal is <= 10. The
    reference must be good to one unit."""
    scales = scenes.orbit_scales(scene.build(), scene.t_end)
    assert reference["uncertainty"] < min(epsilon * a * n for a, n in scales)
    return max(math.dist(p, q) / (epsilon * a * n)
               for p, q, (a, n) in zip(positions(sim), reference["positions"], scales))


@pytest.fixture(scope="module")
def references():
    return {name: scenes.make(name).reference() for name in ("jupiter-comet", "retrograde", "circumbinary")}


@pytest.mark.parametrize("epsilon", [DEFAULT_EPSILON, 1e-10])
@pytest.mark.parametrize("name", ["jupiter-comet", "retrograde", "circumbinary"])
def test_hard_scenes_keep_epsilon(references, name, epsilon):
    # Today's partner-only density left the flyby at 1.6e-3 AU (default
    # epsilon), the crossing at 1.9e-2 AU and drifted on the circumbinary
    # planet; measured now (s = 8): at most 4.7 of the allowed 10.
    scene = scenes.make(name)
    sim = scene.build()
    configure(sim, "pfvi", epsilon=epsilon)
    sim.integrate(scene.t_end)
    assert goal_ratio(scene, sim, references[name], epsilon) < 10.0


def test_a_pair_that_meets_through_the_boundary_is_seen():
    # Two bodies pass 0.3 AU apart through the periodic boundary (ghost
    # images); a density from direct separations took 4 steps and ended
    # 2.1e-3 AU off at epsilon 1e-6.
    scene = scenes.make("periodic-box")
    reference = scene.reference()
    for epsilon in (1e-6, 1e-10):
        sim = scene.build()
        configure(sim, "pfvi", epsilon=epsilon)
        sim.integrate(scene.t_end)
        worst = max(math.dist(p, q) for p, q in zip(positions(sim), reference["positions"]))
        assert worst < 10.0 * epsilon * scene.SIZE, (epsilon, worst)


def hidden_perturber(mass=1e-3, b=0.05, v=30.0, t_pass=0.5):
    """Sun and an Earth on a circular orbit; a mass that is no particle
    (a force callback) crosses the Earth's path at t_pass, b from it at speed
    v: no pair of the density shows it."""
    sim = rebound.Simulation()
    sim.units = ("AU", "yr", "Msun")
    sim.add(m=1.0)
    sim.add(m=3e-6, a=1.0)
    sim.move_to_com()
    p = sim.particles[1]
    # The Earth's position at t_pass, and the perturber's straight path through it, b off.
    n = 2 * math.pi
    x0, y0 = math.cos(n * t_pass), math.sin(n * t_pass)
    G = sim.G

    def force(simp):
        s = simp.contents
        t = s.t
        qx, qy, qz = x0, y0 + v * (t - t_pass), b
        ps = s.particles
        for i in range(s.N):
            dx, dy, dz = qx - ps[i].x, qy - ps[i].y, qz - ps[i].z
            r3 = (dx * dx + dy * dy + dz * dz) ** 1.5
            ps[i].ax += G * mass * dx / r3
            ps[i].ay += G * mass * dy / r3
            ps[i].az += G * mass * dz / r3

    sim.additional_forces = force
    del p
    return sim


def test_the_stages_catch_a_force_no_pair_shows():
    # A passing mass the density cannot see (it is no particle): the stages'
    # check retakes the steps it under-resolves and raises the density's
    # scale, and the run keeps epsilon against IAS15 at a tight tolerance.
    ref = hidden_perturber()
    ref.integrator = "ias15"
    ref.integrator.epsilon = 1e-11
    ref.integrate(1.0)
    for epsilon in (1e-6, 1e-9):
        sim = hidden_perturber()
        configure(sim, "pfvi", epsilon=epsilon)
        sim.integrate(1.0)
        assert sim.integrator.n_rejected > 0
        assert math.dist(positions(sim)[1], positions(ref)[1]) < 10.0 * epsilon


@pytest.mark.parametrize("s", [2, 4, 6, 8])
@pytest.mark.parametrize("e", [0.0, 0.5, 0.9, 0.99])
def test_the_checks_never_fire_along_a_kepler_orbit(s, e):
    sim = scenes.Kepler(e=e).build()
    configure(sim, "pfvi", stages=s, epsilon=1e-4 if s == 2 else 1e-8)
    sim.integrate(3 * scenes.Kepler(e=e).period)
    assert sim.integrator.n_rejected == 0 and sim.integrator.n_asymmetric == 0
    assert sim.integrator.density_scale == 1.0


def test_a_force_that_jumps_within_a_step_is_kept_unresolved():
    # A kick that switches on at t = 0.3 (a step function in time): no
    # shorter step resolves it better, so the step is kept, counted, and the
    # density's scale is left alone (it would otherwise grow without end).
    sim = rebound.Simulation()
    sim.add(m=1.0)
    sim.add(m=1e-3, a=1.0, e=0.3)
    sim.move_to_com()

    def switch(simp):
        s = simp.contents
        if s.t > 0.3:
            s.particles[1].ax += 0.5

    sim.additional_forces = switch
    configure(sim, "pfvi")
    sim.integrate(20.0)
    assert 0 < sim.integrator.n_unresolved < 5
    assert sim.integrator.density_scale == 1.0
    assert sim.integrator.n_steps < 300


def step_counts(build, duration, s, epsilons):
    counts = []
    for epsilon in epsilons:
        sim = build()
        configure(sim, "pfvi", stages=s, epsilon=epsilon)
        sim.integrate(duration)
        counts.append(sim.integrator.n_steps)
    return counts


@pytest.mark.parametrize("s", [4, 6, 8])
@pytest.mark.parametrize("name", ["kepler", "jupiter-comet", "circumbinary"])
def test_steps_rise_as_epsilon_falls(name, s):
    scene = scenes.make(name, **({"e": 0.9, "periods": 3} if name == "kepler" else {"periods": 1}))
    epsilons = (1e-8, 1e-10, 1e-12)
    counts = step_counts(scene.build, scene.t_end, s, epsilons)
    assert counts[0] < counts[1] < counts[2], counts


@pytest.mark.parametrize("s, floor", [(4, 1e-13), (8, 1e-14)])
def test_epsilon_below_what_doubles_deliver_is_held_at_the_floor(s, floor):
    # epsilon = 1e-300 used to take 2.57e6 steps to t = 8.9e-16.
    scene = scenes.Kepler(e=0.5, periods=1)
    at_floor, below = step_counts(scene.build, scene.t_end, s, (floor, 1e-300))
    assert at_floor == below
    sim = scene.build()
    configure(sim, "pfvi", stages=s, epsilon=1e-300)
    sim.integrate(1.0)
    assert sim.integrator.epsilon_effective == floor


def test_epsilon_above_kappa_cap_takes_the_cap_steps():
    # s = 8: kappa reaches 1 at epsilon = C_8 = 1.2e-7; above, the steps are
    # those (the stage solve converges no further), with an error below epsilon.
    scene = scenes.Kepler(e=0.5, periods=2)
    counts = step_counts(scene.build, scene.t_end, 8, (1e-6, 1e-3, 1.2e-7))
    assert counts[0] == counts[1] == counts[2]
    sim = scene.build()
    configure(sim, "pfvi", epsilon=1e-3)
    sim.integrate(1.0)
    assert sim.integrator.epsilon_effective == pytest.approx(1.2e-7)


def steps_warned(sim, seconds):
    """The warnings a run gives within its first `seconds` of simulated time."""
    import warnings
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        sim.integrate(seconds)
        sim.integrate(2 * seconds)
    return [str(w.message) for w in caught if "steps an orbit" in str(w.message)]


@pytest.mark.parametrize("s, epsilon, warned", [(2, 1e-8, True), (2, 1e-6, False), (3, 1e-12, False),
                                                (8, 1e-14, False)])
def test_a_request_of_millions_of_steps_an_orbit_is_said_once(s, epsilon, warned):
    # s = 2 at epsilon 1e-12 (held at 1e-10) took 7e7 steps an orbit of e = 0.9
    # without a word: a user takes it for a hang. The steps it says are those taken.
    sim = rebound.Simulation()
    sim.add(m=1.0)
    sim.add(m=1e-3, a=1.0)
    sim.move_to_com()
    configure(sim, "pfvi", stages=s, epsilon=epsilon)
    period = sim.particles[1].P
    said = steps_warned(sim, 0.01 * period)
    assert len(said) == (1 if warned else 0), said
    if warned:
        import re
        stated = float(re.search(r"about ([0-9.e+-]+) steps an orbit", said[0]).group(1))
        taken = sim.integrator.n_steps / 0.02
        assert 0.8 < taken / stated < 1.25, (taken, stated)
        assert f"stages = {s}" in said[0] and "stages = 8: about" in said[0]


def relative_state_error(sim, start):
    t0, state0 = start
    worst = 0.0
    for p, (r0, v0) in zip(sim.particles, state0):
        worst = max(worst, math.dist((p.x, p.y, p.z), r0) / math.hypot(*r0),
                    math.dist((p.vx, p.vy, p.vz), v0) / math.hypot(*v0))
    return worst, abs(sim.t - t0)


def kepler_defaults(e):
    sim = scenes.Kepler(e=e).build()
    sim.integrator = "pfvi"  # everything at its default, sim.dt REBOUND's 0.001 included
    return sim, (sim.t, [((p.x, p.y, p.z), (p.vx, p.vy, p.vz)) for p in sim.particles])


@pytest.mark.parametrize("e", [0.1, 0.6, 0.9, 0.99])
def test_n_steps_forward_and_back_return_to_the_start(e):
    # REBOUND's default dt capped the first step and the track began only at
    # the second: forward 300 steps and back ended at t = -5.76 (e = 0.6).
    sim, start = kepler_defaults(e)
    sim.steps(300)
    sim.dt = -sim.dt
    sim.steps(300)
    worst, dt = relative_state_error(sim, start)
    assert worst < 1e-10 and dt < 1e-10, (worst, dt)


@pytest.mark.parametrize("e", [0.1, 0.6, 0.9])
def test_integrate_there_and_back_retraces(e):
    # integrate(T) ends with a step REBOUND shortens; integrate(0) retraces
    # that part first and then the track (10 periods: measured 1e-13 ...
    # 4e-11; at e = 0.99 3e-9, round-off: docs/step-control.md).
    sim, start = kepler_defaults(e)
    sim.integrate(10.3)
    sim.integrate(0.0)
    worst, dt = relative_state_error(sim, start)
    assert worst < 1e-10 and dt == 0.0, worst
    assert sim.integrator.n_rejected == 0


@pytest.mark.parametrize("e", [0.0, 0.3, 0.6, 0.9, 0.99, 0.999])
@pytest.mark.parametrize("exact_finish_time", [0, 1])
def test_no_step_is_halved_at_the_defaults(e, exact_finish_time):
    # s = 8 at kappa's cap: 249 halved steps over 2000 orbits at e = 0.6 used
    # to break the symmetry (the energy grew 11x).
    sim, _ = kepler_defaults(e)
    period = 2 * math.pi / math.sqrt(sim.G * 1.001)
    for k in range(1, 201):
        sim.integrate(k * period / 10, exact_finish_time=exact_finish_time)
    assert sim.integrator.n_rejected == 0 and sim.integrator.n_asymmetric == 0


def test_tree_code_sees_only_plausible_stage_points():
    # gravity = "tree" in a 20 AU box: after a first step capped at 0.001 the
    # next was 404x longer, its predicted stage points left the box (1833 AU)
    # and REBOUND broke the simulation. Now the run matches IAS15.
    def build():
        sim = rebound.Simulation()
        sim.units = ("AU", "yr", "Msun")
        sim.gravity = "tree"
        sim.root_size = 20.0
        sim.opening_angle2 = 0.25
        sim.add(m=1.0)
        sim.add(m=9.5e-4, a=5.2, e=0.05)
        sim.add(m=2.9e-4, a=9.5, e=0.05, M=1.0)
        sim.move_to_com()
        return sim

    ref = build()
    ref.integrator = "ias15"
    ref.integrate(10.0)
    for dt in (None, 0.001):  # REBOUND's default, and a dt the user set: a capped first step
        sim = build()
        sim.integrator = "pfvi"
        if dt:
            sim.dt = dt
        sim.integrate(10.0)
        assert max(math.dist(p, q) for p, q in zip(positions(sim), positions(ref))) < 1e-9


def density(sim, s=8):
    out = (ctypes.c_double * 2)()
    assert rebound_pfvi._lib.pfvi_density_of(ctypes.byref(sim), s, out) == 1
    return out[0], out[1]


@pytest.mark.parametrize("name", ["jupiter-comet", "retrograde", "circumbinary", "periodic-box", "triple"])
def test_the_density_rate_is_its_time_derivative(name):
    # G = d log(sigma)/dt drives the track; checked against a central
    # difference of log(sigma) along an IAS15 run, at 20 times of the run.
    scene = scenes.make(name)
    sim = scene.build()
    sim.integrator = "ias15"
    sim.integrator.epsilon = 1e-12
    dt = 1e-5 * scene.period
    for k in range(1, 21):
        sim.integrate(k * scene.t_end / 21)
        sigma, rate = density(sim.copy())
        ahead, behind = sim.copy(), sim.copy()
        for other, sign in ((ahead, 1.0), (behind, -1.0)):
            other.integrator = "ias15"
            other.integrator.epsilon = 1e-12
            other.integrate(sim.t + sign * dt)
        difference = (math.log(density(ahead)[0]) - math.log(density(behind)[0])) / (2 * dt)
        assert abs(difference - rate) < 1e-5 * (abs(rate) + sigma), (sim.t, rate, difference)


def test_density_cost_is_its_pairs():
    # The density is O(N N_active): a swarm of test particles about a star
    # and a planet has one encounter term per test particle and active body.
    sim = rebound.Simulation()
    sim.add(m=1.0)
    sim.add(m=1e-3, a=1.0)
    for k in range(40):
        sim.add(m=0.0, a=1.5 + 0.05 * k, f=0.3 * k)
    sim.N_active = 2
    sigma, _ = density(sim)
    assert sigma > 0.0


def test_lambda_falls_back_to_exactly_one_and_the_track_goes_on():
    """The density scale lowered after retakes was lambda*(1/lambda), which
    can round to 0.9999999999999999; the next step took that for a damaged
    value and restarted the track (a retrograde crossing at 0.24 AU, s = 8,
    epsilon 1e-10: 1143 steps and 4 retakes instead of a track that goes on)."""
    sim = scenes.new_simulation()
    sim.add(m=1.0)
    scenes._jupiter(sim)
    sim.add(m=0.0, a=scenes.Retrograde.A, e=0.6, inc=2.5, Omega=1.0, omega=0.0, M=0.0)
    sim.move_to_com()
    sim.integrator = "pfvi"
    sim.integrator.epsilon = 1e-10
    t_end = 45 * 2 * math.pi * math.sqrt(scenes.Retrograde.A**3 / sim.G)
    lowest = math.inf
    while sim.t < t_end:
        sim.steps(1)
        lowest = min(lowest, sim.integrator.density_scale)
    assert sim.integrator.n_rejected > 0  # the scale was raised, so it had to come down
    assert lowest == 1.0


def test_a_step_kept_unresolved_is_said_once():
    # A drag read from the velocities without force_is_velocity_dependent:
    # the stages see forces that do not follow from the positions, no
    # retake resolves them, and the steps are kept (n_unresolved). It used to
    # be silent (40 times IAS15's error at the default epsilon): REBOUND is
    # now told once per simulation.
    import warnings

    def run(flag):
        sim = rebound.Simulation()
        sim.add(m=1.0)
        sim.add(m=1e-3, a=1.0, e=0.3)
        sim.move_to_com()

        def drag(simp):
            p = simp.contents.particles[1]
            p.ax -= 0.05*p.vx
            p.ay -= 0.05*p.vy

        sim.additional_forces = drag
        sim.force_is_velocity_dependent = flag
        sim.integrator = "pfvi"
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            sim.integrate(10.0)
        return sim, [str(w.message) for w in caught if "kept unresolved" in str(w.message)]

    sim, said = run(0)
    assert sim.integrator.n_unresolved > 1 and len(said) == 1
    assert "force_is_velocity_dependent" in said[0]
    sim, said = run(1)
    assert sim.integrator.n_unresolved == 0 and said == []
