"""pfvi's own gravity pass (pfvi_gravity.c) against REBOUND's gravity routine.

Where REBOUND would compute only its basic gravity, pfvi computes the forces
of every stage of a round in one pass; with additional forces (a callback,
REBOUNDx) it computes the gravity so and calls them at each stage beside
it; variational particles of first order, each a variation of every
particle (MEGNO's, add_variation()'s), get REBOUND's variational gravity in
the same pass's way, with or without additional forces; anything else (a test particle's variation, ignored
terms, another gravity module, the ghost boxes of a shearing sheet) goes
through REBOUND stage by stage. A test particle's variation forces
REBOUND's path without changing the real particles' trajectory, so the two
runs must agree bit for bit: the same terms summed in the same order.
"""
import ctypes
import math

import pytest
import rebound

import rebound_pfvi  # noqa: F401


def state(sim):
    return [(p.x, p.y, p.z, p.vx, p.vy, p.vz) for p in sim.particles] + [sim.t]


def both_paths(build, t_end, configure=None):
    runs = []
    for forced in (False, True):
        sim = build()
        sim.integrator = "pfvi"
        if configure:
            configure(sim)
        if forced:
            # REBOUND's path, the same physics: a test particle's variation
            # (the real trajectory is bit-identical with or without it)
            sim.add_variation(testparticle=1)
        sim.integrate(t_end)
        runs.append((state(sim), sim.integrator.n_steps, sim.integrator.n_force_evaluations))
    return runs


def planets(G=1.0, softening=0.0, N_active=None, testparticle_type=0, inc=0.3):
    def build():
        sim = rebound.Simulation()
        sim.G = G
        sim.softening = softening
        sim.add(m=1.0)
        sim.add(m=1e-3, a=1.0, e=0.4, inc=0.1, f=0.3)
        sim.add(m=5e-4, a=2.3, e=0.2, inc=inc, f=2.0)
        sim.add(m=1e-5 if N_active is None else 1e-7, a=0.6, e=0.7, inc=2.8, f=4.0)  # retrograde
        sim.add(m=0.0 if N_active is None else 1e-9, a=3.5, e=0.85, inc=1.2, f=1.0)
        if N_active is not None:
            sim.N_active = N_active
            sim.testparticle_type = testparticle_type
            sim.testparticle_hidewarnings = 1  # light bodies beyond N_active on purpose
        sim.move_to_com()
        return sim
    return build


@pytest.mark.parametrize("G, softening", [(1.0, 0.0), (39.476926421373, 0.0), (1.0, 0.05)])
def test_own_gravity_is_reboundss_bit_for_bit(G, softening):
    (a, steps_a, f_a), (b, steps_b, f_b) = both_paths(planets(G=G, softening=softening), 30.0)
    assert steps_a == steps_b and f_a == f_b
    assert a == b


@pytest.mark.parametrize("testparticle_type", [0, 1])
@pytest.mark.parametrize("N_active", [1, 3])
def test_own_gravity_with_test_particles(N_active, testparticle_type):
    (a, _, _), (b, _, _) = both_paths(planets(N_active=N_active, testparticle_type=testparticle_type), 20.0)
    assert a == b


@pytest.mark.parametrize("stages, fitting", [(3, "none"), (5, "phase"), (6, "exact"), (8, "none"), (8, "phase")])
def test_own_gravity_every_scheme(stages, fitting):
    def configure(sim):
        sim.integrator.stages = stages
        sim.integrator.fitting = fitting
    (a, _, _), (b, _, _) = both_paths(planets(), 10.0, configure)
    assert a == b


def test_own_gravity_flyby_and_binary():
    def build():
        sim = rebound.Simulation()
        sim.add(m=1.0)
        sim.add(m=0.3, a=0.2, e=0.3)                        # a binary
        sim.add(m=1e-3, a=3.0, e=0.1, primary=None)          # a circumbinary planet
        sim.add(m=0.5, x=-40.0, y=1.5, vx=3.0)               # a star flying by
        sim.move_to_com()
        return sim
    (a, _, _), (b, _, _) = both_paths(build, 25.0)
    assert a == b
    assert all(math.isfinite(v) for row in a[:-1] for v in row)


def test_own_gravity_with_outputs_and_reversal():
    def run(forced):
        sim = planets()()
        sim.integrator = "pfvi"
        if forced:
            sim.additional_forces = lambda simp: None
        for t in (1.0, 2.5, 7.0):
            sim.integrate(t)
        sim.dt *= -1
        sim.integrate(0.0)
        return state(sim)
    assert run(False) == run(True)


def box(ghosts=(1, 1, 0), N_active=None, testparticle_type=0, boundary="periodic"):
    def build():
        sim = rebound.Simulation()
        sim.root_size = 4.0
        sim.boundary = boundary
        if boundary == "shear":
            sim.OMEGA = 1.0
        sim.N_ghost_x, sim.N_ghost_y, sim.N_ghost_z = ghosts
        sim.softening = 0.02
        for x, y, z, vx, vy in ((1.35, -0.9, 0.1, 0.0, 1.2), (-1.35, 0.9, -0.2, 0.0, -1.2), (0.0, 0.6, 0.0, 0.3, 0.0),
                                (0.0, 0.9, 0.3, -0.3, 0.0), (1.9, 1.9, 1.8, 0.2, 0.1)):
            sim.add(m=1e-3, x=x, y=y, z=z, vx=vx, vy=vy)
        if N_active is not None:
            sim.N_active = N_active
            sim.testparticle_type = testparticle_type
            sim.testparticle_hidewarnings = 1
        return sim
    return build


@pytest.mark.parametrize("ghosts, N_active, testparticle_type", [((1, 1, 0), None, 0), ((1, 1, 1), None, 0),
                                                                  ((2, 0, 1), 3, 0), ((1, 1, 1), 3, 1)])
def test_own_gravity_sums_ghost_boxes_as_rebound_does(ghosts, N_active, testparticle_type):
    # (a periodic box's images: each box's pairs in REBOUND's order)
    own, forced = both_paths(box(ghosts, N_active, testparticle_type), 3.0,
                             lambda sim: setattr(sim.integrator, "epsilon", 1e-8))
    assert own == forced and own[1] > 5


def test_a_shearing_sheet_goes_through_rebound():
    # (its images move with t, and the stages of a pass are at different times)
    own, forced = both_paths(box(boundary="shear"), 1.0, lambda sim: setattr(sim.integrator, "epsilon", 1e-8))
    assert own == forced


def test_routes_that_need_rebound_still_work():
    """A test particle's variation and the compensated gravity module go
    through REBOUND's routine: the runs end where IAS15's do."""
    def run(integrator, gravity):
        sim = planets()()
        sim.gravity = gravity
        sim.integrator = integrator
        if integrator == "ias15":
            sim.integrator.epsilon = 1e-11
        else:
            sim.integrator.epsilon = 1e-10
        var = sim.add_variation(testparticle=2) if gravity == "basic" else None
        if var is not None:
            var.particles[0].x = 1.0
        sim.integrate(5.0)
        return sim, var
    for gravity in ("basic", "compensated"):
        sim, var = run("pfvi", gravity)
        ref, rvar = run("ias15", gravity)
        assert math.dist(sim.particles[2].xyz, ref.particles[2].xyz) < 1e-8
        if var is not None:
            assert math.dist(var.particles[0].xyz, rvar.particles[0].xyz) < 1e-6 * math.hypot(*rvar.particles[0].xyz)


def two_bodies(change=None, m=1e-3):
    def build():
        sim = rebound.Simulation()
        sim.add(m=1.0)
        sim.add(m=m, a=1.0, e=0.6, inc=0.2)
        if change:
            change(sim)
        sim.move_to_com()
        return sim
    return build


def pulled(sim):
    def push(reb_sim):
        sim.particles[1].ax += 1e-3
    sim.additional_forces = push


def ghosts(sim):
    sim.root_size = 20.0
    sim.boundary = "periodic"
    sim.N_ghost_x = sim.N_ghost_y = 1


def third(sim):
    sim.add(m=1e-6, a=2.0)


def active_one(sim):
    sim.N_active = 1
    sim.testparticle_type = 1


# (whose only force is their mutual pull: the predictor's rest is round-off)
@pytest.mark.parametrize("build, alone", [
    (two_bodies(), True), (two_bodies(m=0.0), True), (two_bodies(lambda sim: setattr(sim, "softening", 0.05)), True),
    (two_bodies(lambda sim: sim.init_megno(seed=1)), True),
    (two_bodies(third), False), (two_bodies(pulled), False), (two_bodies(ghosts), False),
    (two_bodies(active_one), False), (two_bodies(lambda sim: setattr(sim, "gravity", "compensated")), False),
    (two_bodies(lambda sim: setattr(sim, "gravity", "none")), False),
    (two_bodies(lambda sim: setattr(sim, "G", -1.0)), False)],
    ids=["pair", "test-particle", "softened", "megno", "three", "force", "ghost-boxes", "N_active-1", "compensated",
         "no-gravity", "repulsive"])
def test_the_predictor_takes_two_bodies_alone_only_where_nothing_else_acts(build, alone):
    """Two bodies whose only force is their mutual pull: each body's
    acceleration is the pair's Kepler pull about a barycentre that moves
    uniformly, so the predictor extrapolates no rest beside it (what it
    would extrapolate is round-off). Anything else acting (a third body,
    a force, ghost images, a body outside N_active that pulls without being
    pulled, another gravity module, a repulsive G, whose force the
    predictor does not draw as a Kepler orbit) keeps the rest. The runs end
    where IAS15's do."""
    sim = build()
    sim.integrator = "pfvi"
    assert rebound_pfvi._lib.pfvi_two_alone(ctypes.byref(sim)) == int(alone)
    sim.integrator.epsilon = 1e-10
    ref = build()
    ref.integrator = "ias15"
    ref.integrator.epsilon = 1e-11
    t = 4.0 * 2.0 * math.pi
    sim.integrate(t)
    ref.integrate(sim.t, exact_finish_time=1)
    assert math.dist(sim.particles[1].xyz, ref.particles[1].xyz) < 1e-8


def with_variations(kind):
    # (the variations of every particle: MEGNO's, or two sets of
    # add_variation(), one of them varying a mass)
    def configure(sim):
        if kind == "megno":
            sim.init_megno(seed=3)
            return
        var = sim.add_variation()
        var.particles[1].x, var.particles[2].vy, var.particles[1].m = 1e-3, 1e-4, 1e-5
        other = sim.add_variation()
        other.particles[3].x, other.particles[4].vz = 1e-6, -2e-6
    return configure


def variational_state(sim):
    ps = sim._particles_var
    return [(ps[i].x, ps[i].y, ps[i].z, ps[i].vx, ps[i].vy, ps[i].vz) for i in range(sim.N_var)]


@pytest.mark.parametrize("kind", ["megno", "sets"])
@pytest.mark.parametrize("build", [planets(), planets(softening=0.05), planets(N_active=3, testparticle_type=0),
                                   planets(N_active=3, testparticle_type=1)],
                         ids=["planets", "softened", "test particles", "test particles pulling"])
def test_own_variational_gravity_is_reboundss_bit_for_bit(build, kind):
    # Variations of every particle take pfvi's own pass (REBOUND's
    # variational gravity, stages as lanes); a callback that adds nothing
    # sends the same run through REBOUND's routine stage by stage. The real
    # and the variational particles, MEGNO and the evaluations must agree
    # bit for bit, also after a reversal.
    def run(forced):
        sim = build()
        sim.integrator = "pfvi"
        with_variations(kind)(sim)
        if forced:
            sim.additional_forces = lambda simp: None
            sim.force_is_velocity_dependent = 0
        sim.integrate(20.0)
        first = (state(sim), variational_state(sim), sim.megno() if kind == "megno" else None,
                 sim.integrator.n_force_evaluations)
        sim.dt *= -1
        sim.integrate(5.0)
        return first, (state(sim), variational_state(sim))
    own, forced = run(False), run(True)
    assert own == forced
    assert own[0][3] > 500 and any(v != 0. for row in own[0][1] for v in row)


def j2_like(simp):
    # (a force of the positions alone, pulling each body toward the plane z = 0)
    for p in simp.contents.particles[:simp.contents.N]:
        p.az -= 0.01 * p.z


@pytest.mark.parametrize("build", [planets(), planets(N_active=3, testparticle_type=1), box((1, 1, 1))],
                         ids=["planets", "test particles", "periodic box"])
def test_additional_forces_beside_the_own_gravity_pass(build):
    # With a force callback the gravity of a round is pfvi's own pass and the
    # callback is called at each stage beside it: the same sums and calls as
    # REBOUND's path, forced by a variational particle.
    def configure(sim):
        sim.additional_forces = j2_like
        sim.integrator.epsilon = 1e-9
    beside, forced = both_paths(build, 4.0, configure)
    assert beside == forced and beside[1] > 5
    plain, _ = both_paths(build, 4.0, lambda sim: setattr(sim.integrator, "epsilon", 1e-9))
    assert plain[0] != beside[0]   # (the force acted)


def test_a_velocity_dependent_force_sees_reboundss_gravity_at_every_stage():
    # With a force of velocities too (a drag here, REBOUNDx's gr in use) the
    # gravity it is called beside is the own pass's: at every stage the
    # accelerations it finds are those REBOUND's routine computes for the
    # same positions, bit for bit (a twin simulation, REBOUND's update).
    import ctypes

    twin = planets(softening=0.01, N_active=3, testparticle_type=1)()
    seen = {"calls": 0, "differ": 0}

    def drag(simp):
        sim = simp.contents
        ps = sim.particles
        for i in range(sim.N):
            twin.particles[i].x, twin.particles[i].y, twin.particles[i].z = ps[i].x, ps[i].y, ps[i].z
        rebound.clibrebound.reb_simulation_update_acceleration(ctypes.byref(twin))
        seen["calls"] += 1
        seen["differ"] += sum((ps[i].ax, ps[i].ay, ps[i].az) != (twin.particles[i].ax, twin.particles[i].ay,
                                                                 twin.particles[i].az) for i in range(sim.N))
        for i in range(1, sim.N):
            ps[i].ax -= 0.01 * ps[i].vx
            ps[i].ay -= 0.01 * ps[i].vy

    sim = planets(softening=0.01, N_active=3, testparticle_type=1)()
    sim.integrator = "pfvi"
    sim.additional_forces = drag
    sim.force_is_velocity_dependent = 1
    sim.integrate(3.0)
    assert seen["calls"] > 100 and seen["differ"] == 0


@pytest.mark.parametrize("kind", ["megno", "sets"])
def test_a_force_beside_the_variational_pass_sees_reboundss_gravity_at_every_stage(kind):
    # With variational particles and a force callback (here J2-like, its
    # variational term added too) the real and the variational gravity are
    # the own pass's and the callback is called at each stage beside it:
    # at every stage, the real solve's rounds and the tangent solve's own,
    # the accelerations it finds are those REBOUND's routine computes for the
    # same positions, real and variational, bit for bit (a twin simulation).
    import ctypes

    build = planets(softening=0.01, N_active=3, testparticle_type=1)
    twin = build()
    with_variations(kind)(twin)
    seen = {"calls": 0, "differ": 0}

    def force(simp):
        sim = simp.contents
        ps, pv = sim.particles, sim._particles_var
        for i in range(sim.N):
            twin.particles[i].x, twin.particles[i].y, twin.particles[i].z = ps[i].x, ps[i].y, ps[i].z
        for v in range(sim.N_var):
            tv = twin._particles_var[v]
            tv.x, tv.y, tv.z, tv.m = pv[v].x, pv[v].y, pv[v].z, pv[v].m
        rebound.clibrebound.reb_simulation_update_acceleration(ctypes.byref(twin))
        seen["calls"] += 1
        seen["differ"] += sum((ps[i].ax, ps[i].ay, ps[i].az) != (twin.particles[i].ax, twin.particles[i].ay,
                                                                 twin.particles[i].az) for i in range(sim.N))
        seen["differ"] += sum((pv[v].ax, pv[v].ay, pv[v].az) != (twin._particles_var[v].ax, twin._particles_var[v].ay,
                                                                 twin._particles_var[v].az) for v in range(sim.N_var))
        for i in range(sim.N):
            ps[i].az -= 0.01 * ps[i].z
        for v in range(sim.N_var):
            pv[v].az -= 0.01 * pv[v].z

    sim = build()
    sim.integrator = "pfvi"
    with_variations(kind)(sim)
    sim.additional_forces = force
    sim.force_is_velocity_dependent = 0
    sim.integrate(3.0)
    assert seen["calls"] > 100 and seen["differ"] == 0
    assert any(sim._particles_var[v].az != 0. for v in range(sim.N_var))


def test_ignored_terms_switched_in_a_callback_are_rebounds_from_the_next_stage():
    # REBOUND's gravity_ignore_terms is outside the force model pfvi holds
    # for a step: switched by a callback, the next stage's forces come from
    # REBOUND's routine with it, as before the gravity pass took up the
    # callbacks (a hostile trial: the rest of the round kept the 0-1 term).
    import ctypes

    sim = planets()()
    twin = planets()()
    twin.gravity_ignore = 1
    seen = {"calls": 0, "checked": 0, "differ": 0}

    def force(simp):
        s = simp.contents
        seen["calls"] += 1
        if seen["calls"] == 2:
            s.gravity_ignore = 1
        elif seen["calls"] in (3, 4, 5):
            for i in range(s.N):
                twin.particles[i].x, twin.particles[i].y, twin.particles[i].z = (s.particles[i].x, s.particles[i].y,
                                                                                 s.particles[i].z)
            rebound.clibrebound.reb_simulation_update_acceleration(ctypes.byref(twin))
            seen["checked"] += 1
            seen["differ"] += sum((s.particles[i].ax, s.particles[i].ay) != (twin.particles[i].ax, twin.particles[i].ay)
                                  for i in range(s.N))

    sim.integrator = "pfvi"
    sim.integrator.stages = 8
    sim.integrator.epsilon = 0.0
    sim.dt = 0.05
    sim.additional_forces = force
    sim.steps(1)
    assert seen["checked"] == 3 and seen["differ"] == 0
