"""The error falls as epsilon does (issue 42, item 3), on a reduced grid:
below kappa's cap, where epsilon sets the steps."""
import math

import pytest

from rebound_pfvi import scenes
from rebound_pfvi.integrators import configure


def relative_positions(sim):
    return [(p.x - sim.particles[0].x, p.y - sim.particles[0].y, p.z - sim.particles[0].z) for p in sim.particles[1:]]


def ladder(scene, epsilons):
    # The reference is IAS15 at epsilon 1e-12 for every scene (3.8e-12 AU
    # from the exact Kepler orbit with rebound 5.2.2): the exact one is
    # REBOUND's element conversion, which rebound 5.0.0 (the oldest this
    # package supports) gets 1.3e-8 AU wrong on Kepler e = 0.5.
    reference = scene.build()
    configure(reference, "ias15", epsilon=1e-12)
    reference.integrate(scene.t_end, exact_finish_time=1)
    scales = scenes.orbit_scales(scene.build(), scene.t_end)
    out = []
    for epsilon in epsilons:
        sim = scene.build()
        configure(sim, "pfvi", epsilon=epsilon)
        sim.integrate(scene.t_end, exact_finish_time=1)
        error = max(math.dist(a, b) for a, b in zip(relative_positions(sim), relative_positions(reference)))
        out.append((epsilon, error, error / (epsilon * min(a * n for a, n in scales)), sim.integrator.n_steps))
    return out


@pytest.mark.parametrize("name", ["kepler", "triple"])
def test_the_error_falls_as_epsilon_does(name):
    # A decade ladder from kappa's cap (s = 8: 1.2e-7) down to 1e-10 on the
    # Kepler pair of e = 0.5 (100 orbits) and the hierarchical triple: every
    # decade ends closer to the reference than the one above it, within the
    # step control's goal of 10 epsilon a n, in more steps (measured: Kepler
    # 4.2e-7, 2.8e-8, 4.1e-9, 3.0e-10 AU; the triple 2.8e-6, 4.9e-8, 7.9e-9,
    # 8.4e-10 AU). Above the cap the steps are the cap's, so the error does
    # not follow epsilon there: the triple at the default, 1e-6, ends 2.5e-7
    # AU off, closer than at 1e-7 (docs/solve.md, issue 42's measurement).
    scene = scenes.make(name, e=0.5) if name == "kepler" else scenes.make(name)
    rows = ladder(scene, [1e-7, 1e-8, 1e-9, 1e-10])
    assert rows[0][2] < 10.0, rows
    for (_, error0, _, steps0), (_, error1, goal1, steps1) in zip(rows, rows[1:]):
        assert error1 < error0, rows
        assert steps1 > steps0, rows
        assert goal1 < 10.0, rows
