"""A short demonstration: pfvi beside IAS15 and WHFast on two Kepler orbits.

Two bodies (m = 1 and 1e-3, a = 1, centre-of-mass frame), one circular and
one with e = 0.95, integrated for a number of orbits. For each integrator it
prints the relative energy error, the error of the relative position against
the exact Kepler solution (from REBOUND's orbital elements, M advanced by n t)
and the wall time: pfvi at its defaults (what ``sim.integrator = "pfvi"``
gives), the seed's two-point scheme with fixed steps (second order: what the
paper's scheme does at a fixed step), IAS15 and WHFast at theirs. WHFast is
exact on a pure two-body problem (up to round-off), so this demo shows
accuracy, not a fair race; docs/results.md does the comparisons.
"""
import math
import time
import warnings
from typing import Any, Callable, Dict, List, Tuple

import rebound

from . import INTEGRATOR_NAME  # noqa: F401  (registers "pfvi")
from . import checks
from .integrators import configure as configure_integrator, pfvi_options
from .scenes import kepler_relative, orbit_elements

M_PLANET = 1e-3
#: pfvi's defaults' wall time over IAS15's at equal position error, least and
#: largest over the pages of docs/results.md with gravity, as README.md
#: states it: ``python3 -P benchmarks/pages_summary.py`` computes it from
#: the pages' JSON, and tests/test_stated_figures.py checks all three agree.
PAGES_IAS15_RATIO = (0.18, 0.73)


def kepler_pair(e: float) -> rebound.Simulation:
    """Two bodies (m = 1 and M_PLANET) at a = 1 with eccentricity e, in the centre-of-mass frame."""
    sim = rebound.Simulation()
    sim.add(m=1.0)
    sim.add(m=M_PLANET, a=1.0, e=e)
    sim.move_to_com()
    return sim


def exact_relative_position(sim0: rebound.Simulation, t: float) -> Tuple[float, float, float]:
    """Relative position of body 1 about body 0 at time t, from the elements at t = 0."""
    d = kepler_relative(sim0.G, sim0.particles[0].m, sim0.particles[1].m, orbit_elements(sim0), t)
    return d.x, d.y, d.z


#: The demo's integrators, as the table names them.
PFVI_DEFAULTS = "pfvi (defaults)"
PFVI_SEED = "pfvi seed s=2 phase, fixed dt"
INTEGRATORS = (PFVI_DEFAULTS, PFVI_SEED, "ias15", "whfast")


def configure(sim: rebound.Simulation, name: str, period: float, steps_per_orbit: int) -> None:
    """Sets the integrator `name` (one of :data:`INTEGRATORS`) as the demo runs it."""
    if name == PFVI_DEFAULTS:
        configure_integrator(sim, "pfvi")
    elif name == PFVI_SEED:
        # the seed's two-point scheme (its fitting, frequency and centre), fixed steps of dt
        configure_integrator(sim, "pfvi", dt=period / steps_per_orbit, epsilon=0.,
                             **pfvi_options({"stages": 2, "fitting": "phase"}))
    elif name == "whfast":
        configure_integrator(sim, "whfast", dt=period / 100)
    else:
        configure_integrator(sim, "ias15")


def run_case(e: float, name: str, orbits: float, steps_per_orbit: int) -> Dict[str, Any]:
    """One integrator on one orbit: steps, relative energy error, position error, wall time."""
    sim = kepler_pair(e)
    start = sim.copy()
    period = sim.particles[1].P
    E0 = sim.energy()
    configure(sim, name, period, steps_per_orbit)
    # pfvi's warnings (the seed's fixed step at e = 0.95 is too long for its
    # pericentre) are the demo's findings: kept for a note under the table
    # instead of printed by Python in its middle, with a site-packages path.
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", RuntimeWarning)
        tick = time.perf_counter()
        sim.integrate(orbits * period)
        wall = time.perf_counter() - tick
    d = sim.particles[1] - sim.particles[0]
    exact = exact_relative_position(start, sim.t)
    position_error = math.dist((d.x, d.y, d.z), exact)
    return {"e": e, "integrator": name, "steps": sim.steps_done,
            "energy_error": abs(sim.energy() / E0 - 1), "position_error": position_error,
            "wall_s": wall, "warnings": [str(w.message) for w in caught]}


def run_demo(orbits: int = 100, write: Callable[[str], Any] = print) -> List[Dict[str, Any]]:
    """Prints (through `write`) and returns the demo's table. orbits: a
    positive integer, as ``--orbits`` takes (ValueError otherwise)."""
    orbits = checks.positive_int(orbits, "orbits")
    write(f"Two bodies (m = 1, {M_PLANET:g}), a = 1, centre-of-mass frame, {orbits} orbits.")
    write("pfvi (defaults): s = 8, adaptive symmetric steps, epsilon 1e-6; the seed's two-point scheme: fixed "
          "steps (steps per orbit in brackets), second order; IAS15 adaptive; WHFast 100 steps per orbit.")
    write(f"{'e':>5}  {'integrator':<38} {'steps':>9} {'rel. energy err':>16} {'position err':>13} {'wall [s]':>9}")
    cases = [(0.0, 100), (0.95, 20000)]
    rows = []
    for e, steps_per_orbit in cases:
        for name in INTEGRATORS:
            row = run_case(e, name, orbits, steps_per_orbit)
            label = f"{name} [{steps_per_orbit}]" if name == PFVI_SEED else name
            write(f"{e:>5.2f}  {label:<38} {row['steps']:>9d} {row['energy_error']:>16.2e} "
                  f"{row['position_error']:>13.2e} {row['wall_s']:>9.3f}")
            rows.append(row)
    for row in rows:
        label = row["integrator"]
        for message in dict.fromkeys(row["warnings"]):
            write(f"Note ({label}, e = {row['e']:.2f}): {message}")
    write(f"pfvi's epsilon is a position error per orbit relative to the orbit's size: over {orbits} orbits "
          f"its defaults allow {1e-6 * orbits:.0e} of a; IAS15's default (epsilon 1e-9) overshoots its own "
          f"request. At equal error pfvi's defaults took {PAGES_IAS15_RATIO[0]:.2f}-{PAGES_IAS15_RATIO[1]:.2f} "
          "of IAS15's wall time on the pages with gravity (docs/results.md).")
    return rows
