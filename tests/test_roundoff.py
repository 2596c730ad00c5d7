"""Round-off as a random walk (issue 25; docs/roundoff.md): the classical
step's coefficients keep the identities its symplecticity and symmetry rest
on exactly in doubles, round trips return to round-off, and an ensemble's
energy error has no bias and spreads like t^(1/2)."""
import math
from fractions import Fraction

import pytest
import rebound

import rebound_pfvi

from conftest import needs_python_heartbeat, two_body

STAGES = [s for s in rebound_pfvi.STAGES if s >= 3]


@pytest.mark.parametrize("s", STAGES)
def test_classical_coefficients_keep_their_identities_exactly(s):
    # Read as exact rationals: the identities hold with no rounding at all.
    c, nu, _ = rebound_pfvi.nystrom(s)
    c = [Fraction(x) for x in c]
    nu = [[Fraction(x) for x in row] for row in nu]
    n = s - 1
    grid = Fraction(1, 2**50)
    for i in range(s):
        assert c[n - i] == 1 - c[i]
        assert nu[0][i] == 0 and nu[i][n] == 0       # Q_1 = q_k; the end force acts in the next step
        assert nu[n][i] == 1 - c[i]                   # Q_s = q_k+1 (the IIIB update)
        for j in range(s):
            assert (nu[i][j] / grid).denominator == 1
            assert nu[i][j] - nu[j][i] == c[i] - c[j]            # symplectic
            assert nu[n - i][n - j] == nu[i][j] + c[j] - c[i]    # symmetric


@pytest.mark.parametrize("s", STAGES)
def test_classical_coefficients_are_the_lobatto_pair(s):
    # Lobatto IIIA-IIIB in Nystrom form: Q_i exact for q(t) = t^(m+2), i.e.
    # sum_j nu_ij w_j c_j^m = c_i^(m+2)/((m+1)(m+2)) for m <= s - 3, and the
    # IIIB stage velocities exact for v(t) = t^(m+1); to the grid's 2^-50.
    c, nu, mu_hat = rebound_pfvi.nystrom(s)
    _, w, _ = rebound_pfvi.lobatto(s)
    worst_q = worst_v = 0.0
    for i in range(s):
        for m in range(s - 2):
            q = sum(Fraction(nu[i][j]) * Fraction(w[j]) * Fraction(c[j])**m for j in range(s))
            worst_q = max(worst_q, abs(float(q - Fraction(c[i])**(m + 2) / ((m + 1) * (m + 2)))))
            v = sum(Fraction(mu_hat[i][j]) * Fraction(w[j]) * Fraction(c[j])**m for j in range(s))
            worst_v = max(worst_v, abs(float(v - Fraction(c[i])**(m + 1) / (m + 1))))
    # measured: at most 1.3e-15 (positions) and 2.8e-16 (velocities)
    assert worst_q < 3e-15 and worst_v < 1e-15


def round_trip(sim, steps):
    start = [(p.x, p.y, p.vx, p.vy) for p in sim.particles]
    sim.steps(steps)
    sim.dt = -sim.dt
    sim.steps(steps)
    return max(abs(a - b) for p, q in zip(sim.particles, start) for a, b in zip((p.x, p.y, p.vx, p.vy), q))


@pytest.mark.parametrize("s", STAGES)
def test_fixed_steps_return_over_ten_thousand_steps(s):
    # 100 orbits at e = 0.5, 100 steps per orbit, and back: measured 3.0e-12
    # to 9.9e-12 (s = 3 ... 8), the along-track random walk of Brouwer's law
    # (about 2^-52 N^(3/2) = 2.2e-10 for N = 10^4 steps, times the steps'
    # share of an orbit).
    sim = two_body(1e-3, e=0.5)
    sim.integrator = "pfvi"
    sim.integrator.epsilon = 0.0
    sim.integrator.stages = s
    sim.dt = sim.particles[1].P / 100
    assert round_trip(sim, 10_000) < 1e-10


@pytest.mark.parametrize("s", [4, 8])
def test_symmetric_steps_return_over_ten_thousand_steps(s):
    # The default control at e = 0.9: 10^4 steps and back, measured 2.8e-11
    # (s = 4) and 5.2e-10 (s = 8; 286 orbits, pericentre speed 4.4): the
    # grid of steps retraces to round-off, which then grows along the orbit.
    sim = two_body(1e-3, e=0.9)
    sim.integrator = "pfvi"
    sim.integrator.stages = s
    assert round_trip(sim, 10_000) < 5e-9
    assert sim.integrator.n_asymmetric == 0


def ensemble(e, orbits, members, phases=False, a=1.0, per_orbit=None, **options):
    """Relative energy errors of `members` runs whose semi-major axes differ
    by k 2^-40 (about 1e-12: far below what the truncation error feels, far
    enough apart that their round-off is independent), at 10 times (no step
    shortened to reach them). Members a single ulp apart are not independent
    under the Newton stage solve, which lands each step on the exact fixed
    point in doubles: their round-off walks stay together for hundreds of
    orbits (16 such members at e = 0.9, epsilon 1e-12: the ensemble mean
    reached 4.6 of its standard errors by 800 orbits and then stayed put,
    while members 2^-40 apart stay within 1.3). per_orbit: fixed steps of
    that fraction of the period."""
    runs = []
    for k in range(members):
        sim = rebound.Simulation()
        sim.add(m=1.0)
        # (phases: each member from its own phase, as a circular orbit needs:
        # from one phase its members' roundings stay alike)
        sim.add(m=1e-3, a=a * (1.0 + k * 2.0**-40), e=e, f=0.3 * k if phases else 0.0)
        sim.move_to_com()
        sim.integrator = "pfvi"
        for name, value in options.items():
            setattr(sim.integrator, name, value)
        period, energy0 = sim.particles[1].P, sim.energy()
        if per_orbit:
            sim.integrator.epsilon = 0.0
            sim.dt = period / per_orbit
        errors = []
        for j in range(1, 11):
            sim.integrate(orbits * period * j / 10, exact_finish_time=0)
            errors.append(sim.energy() / energy0 - 1.0)
        runs.append(errors)
    means = [sum(r[j] for r in runs) / members for j in range(10)]
    spreads = [math.sqrt(sum((r[j] - means[j])**2 for r in runs) / (members - 1)) for j in range(10)]
    xs = [math.log(j + 1) for j in range(10)]
    ys = [math.log(v) for v in spreads]
    mx, my = sum(xs) / 10, sum(ys) / 10
    slope = sum((x - mx) * (y - my) for x, y in zip(xs, ys)) / sum((x - mx)**2 for x in xs)
    bias = max(abs(m) / (sd / math.sqrt(members)) for m, sd in zip(means, spreads))
    return bias, slope


def test_an_ensembles_energy_error_is_unbiased_and_spreads_like_a_random_walk():
    # 16 runs x 2000 orbits at e = 0.9, epsilon 1e-12 (truncation below
    # round-off). Measured with the Newton stage solve: the mean at most 0.90
    # standard errors from zero, the spread growing as t^0.59 (32 members:
    # within 1.2). With the fixed-point solve, members 2^-52 apart: 0.95 to
    # 2.1 standard errors, t^0.47 to t^0.71; before the classical form and
    # the stop rule of docs/roundoff.md the mean drifted to 14 standard
    # errors (8 runs) and the spread did not grow (t^-0.02).
    bias, slope = ensemble(0.9, 2000, 16, epsilon=1e-12)
    assert bias < 4.0
    assert 0.2 < slope < 0.85


def test_a_circular_orbits_round_off_keeps_no_large_bias():
    # On a circular orbit every step is the same step turned, so a stop rule
    # that keeps the same small error in every step shows there first: the
    # stage solve's early stop tried on 2026-11-27 (docs/performance.md)
    # drove this ensemble (12 members at their own phases, e = 0, epsilon
    # 1e-11, 3000 orbits) to 35 standard errors, linearly, where eccentric
    # ensembles stayed within 2.1. This build measured 1.15 here; the build
    # before, whose step ended on the Newton iterate's own end increment
    # (test below), 3.4.
    bias, slope = ensemble(0.0, 3000, 12, phases=True, epsilon=1e-11)
    assert bias < 4.0


def test_a_circular_orbit_with_fixed_steps_keeps_no_bias():
    # The bias circular orbits showed until 2026-11-27 (docs/roundoff.md):
    # the step ended on the Newton iterate's own end increment, which keeps
    # the rest of its last correction below the doubles' last place, the same
    # in every step of a circular orbit; the energy fell linearly. Now the end
    # is the IIIA-IIIB update from the stages' forces, carried in two parts.
    # This ensemble (16 members at their own phases, a = 0.7, fixed steps of
    # P/25, 9000 orbits) measured 1.6 standard errors; the build before 6.5
    # (11 after 3e4 orbits).
    bias, _ = ensemble(0.0, 9000, 16, phases=True, a=0.7, per_orbit=25)
    assert bias < 4.0


def test_at_the_defaults_the_round_off_spread_grows_like_a_random_walk():
    # The defaults' energy error is the truncation's (the same in every run);
    # its spread over the ensemble is round-off: measured t^0.32 with the
    # Newton stage solve (the fixed-point solve, members 2^-52 apart: four
    # ensembles of 16 gave t^0.45 to t^0.61).
    _, slope = ensemble(0.9, 2000, 16)
    assert 0.2 < slope < 0.85


def kepler_phase_error(integrator, epsilon, f, orbits):
    """Kepler e = 0.95 (AU, yr, Msun) from true anomaly f: the error in mean
    anomaly after `orbits` orbits against the exact motion (the distance
    from the exact position over v/n: the phase error round-off leaves,
    whatever point of the orbit the run ends at)."""
    sim = rebound.Simulation()
    sim.G = 4.0 * math.pi**2
    sim.add(m=1.0)
    sim.add(m=1e-3, a=1.0, e=0.95, f=f)
    sim.move_to_com()
    o = sim.particles[1].orbit(primary=sim.particles[0])
    sim.integrator = integrator
    sim.integrator.epsilon = epsilon
    sim.integrate(orbits * o.P)
    exact = rebound.Simulation()
    exact.G = sim.G
    exact.add(m=1.0)
    exact.add(m=1e-3, a=o.a, e=o.e, omega=o.omega, M=(o.M + o.n * sim.t) % (2.0 * math.pi))
    d, de = sim.particles[1] - sim.particles[0], exact.particles[1] - exact.particles[0]
    return math.dist(d.xyz, de.xyz) / math.hypot(de.vx, de.vy, de.vz) * o.n


def test_the_round_off_floor_on_a_short_eccentric_run():
    # Issue 42, item 4. 20 orbits at e = 0.95, 8 phases, epsilon 1e-13
    # (truncation far below round-off): median phase error measured 1.6e-12
    # rad, IAS15 at epsilon 1e-10 1.2e-12 (benchmarks/roundoff_floor.py has
    # 100 orbits and 16 phases: 2.0e-11 against 6.5e-12).
    phases = [2.0 * math.pi * i / 8 + 0.01 for i in range(8)]
    pfvi = sorted(kepler_phase_error("pfvi", 1e-13, f, 20) for f in phases)
    ias15 = sorted(kepler_phase_error("ias15", 1e-10, f, 20) for f in phases)
    median = 0.5 * (pfvi[3] + pfvi[4])
    assert median < 4e-12
    assert median < 3.0 * 0.5 * (ias15[3] + ias15[4])


def outer_solar_system(member, integrator, epsilon, t, exact_finish_time=1):
    from rebound_pfvi import scenes

    sim = scenes.make("outer-solar-system").build()
    sim.particles[1].x *= 1.0 + member * 2.0**-40
    sim.integrator = integrator
    sim.integrator.epsilon = epsilon
    sim.integrate(t, exact_finish_time=exact_finish_time)
    return sim


def test_a_held_track_keeps_t_to_its_last_place():
    # The steady track holds the steps constant, so t + h lost the same
    # rounding every step: kept aside and never folded into t, it reached
    # 2.7e-11 yr in 1600 steps (250 of t's last places), and the state was
    # shown at t while it was at t + 2.7e-11 (Jupiter 1e-11 off).
    from rebound_pfvi import scenes

    t_end = scenes.make("outer-solar-system").t_end
    sim = outer_solar_system(0, "pfvi", 1e-13, t_end, exact_finish_time=0)
    assert sim.integrator.steady_hold == 1
    assert sim.integrator.n_steps > 1000
    assert abs(sim.integrator.t_compensation) <= 0.5 * math.ulp(sim.t)


def test_the_round_off_floor_on_the_outer_solar_system():
    # Issue 42, item 4: Jupiter after 992 yr at epsilon 1e-13 against IAS15
    # at 1e-12, four members 2^-40 apart. With t's rounding left unfolded
    # on the held track: 6.0e-12 ... 2.4e-11 (median 1.0e-11); folded:
    # 1.5e-12 ... 3.7e-12 (IAS15 at 1e-10 against the same reference,
    # benchmarks/roundoff_floor.py: median 7.8e-13 over 8 members).
    from rebound_pfvi import scenes

    t_end = scenes.make("outer-solar-system").t_end
    errors = []
    for member in range(4):
        got = outer_solar_system(member, "pfvi", 1e-13, t_end).particles
        ref = outer_solar_system(member, "ias15", 1e-12, t_end).particles
        d = [(got[1].x - got[0].x) - (ref[1].x - ref[0].x), (got[1].y - got[0].y) - (ref[1].y - ref[0].y),
             (got[1].z - got[0].z) - (ref[1].z - ref[0].z)]
        errors.append(math.hypot(*d) / math.dist(ref[1].xyz, ref[0].xyz))
    errors.sort()
    assert 0.5 * (errors[1] + errors[2]) < 4e-12


def _circle_at_fixed_steps():
    sim = rebound.Simulation()
    sim.add(m=1.0)
    sim.add(m=0.0, x=1.0, vy=1.0)
    sim.integrator = "pfvi"
    sim.integrator.epsilon = 0.0
    sim.dt = 2.0 * math.pi / 100
    return sim


def _bits(sim):
    return [(p.x, p.y, p.z, p.vx, p.vy, p.vz) for p in sim.particles]


def test_a_velocity_component_near_zero_at_a_call_boundary_keeps_its_compensation(tmp_path):
    # After 25 steps of 100 an orbit the body is at a turning point: vy is
    # 4e-16, and the velocity's carried rounding (the increment's, about
    # 1e-18) is larger than 1e-10 vx. Judged by its own component the
    # carried part was dropped at the next call's start, and the run split
    # there (or continued from an archive or a copy) no longer gave the
    # bits of one call (1.5e-15 to 4e-14 apart).
    one = _circle_at_fixed_steps()
    one.steps(100)
    split = _circle_at_fixed_steps()
    split.steps(25)
    assert abs(split.particles[1].vy) < 1e-14
    path = str(tmp_path / "turning.bin")
    split.save_to_file(path)
    copied = split.copy()
    split.steps(75)
    assert _bits(split) == _bits(one)
    restored = rebound.Simulation(path)
    restored.steps(75)
    assert _bits(restored) == _bits(one)
    copied.steps(75)
    assert _bits(copied) == _bits(one)


@needs_python_heartbeat
def test_a_heartbeat_that_does_nothing_keeps_a_turning_points_compensation():
    # A heartbeat has every step start anew, judging the carried parts as a
    # call's start does (the test above).
    one = _circle_at_fixed_steps()
    one.steps(100)
    beating = _circle_at_fixed_steps()
    beating.heartbeat = lambda simp: None
    beating.steps(100)
    assert _bits(beating) == _bits(one)
