"""Stiff and extreme cases: does each integrator finish, how wrong is it, and what happened?

``rebound-pfvi stability`` runs every case of :data:`CASES` with pfvi (its
defaults first; then every fitting of the seed, with its frequency and centre
(``SEED_MODEL``), and "none", at s = 2 and 4; adaptive steps unless the case
prescribes fixed ones) beside IAS15 and WHFast. Every run is a separate process with a wall-time
budget (:mod:`rebound_pfvi.runner`, ``fresh=True``), so that a run which
crashes, hangs or crawls becomes a row of the report ("crashed", "killed",
"stopped by the budget") instead of taking the report down with it. Every row
is a :class:`rebound_pfvi.runs.Run`, and gives: the verdict (accurate,
inaccurate, refused, crashed, over budget; :mod:`rebound_pfvi.verdict`,
judged against the case's tolerance) with its detail, the time reached, the
relative energy error (final and largest over 100 checkpoints), the position
error against a reference at the time reached, steps, wall time, and what
the integrator reported (u limited, steps rejected, asymmetric reversible
steps).

Units are AU, yr and Msun (G from REBOUND) unless a case says otherwise.
References: the exact two-body solution where there is one (REBOUND's
elements with the mean anomaly advanced; the radial Kepler equation for the
infall); otherwise IAS15 at epsilon 1e-11, with its distance to a run at
1e-10 reported as the reference's uncertainty.
"""
from __future__ import annotations

import math
import threading
import time
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Callable, Dict, List, Optional, Sequence, Tuple

from . import checks, runner, runs, scenes, verdict
from . import DEFAULTS
from .integrators import configure as configure_integrator, pfvi_label, pfvi_options
from .runs import ProgressCallback, Run

if TYPE_CHECKING:
    import rebound

Vector = Tuple[float, float, float]

FITTINGS = ("phase", "phase-literal", "none")
STAGES = (2, 4)
CHECKPOINTS = 100
#: A run still busy this long after its budget is killed (see rebound_pfvi.runner).
GRACE_SECONDS = runner.GRACE_SECONDS


@dataclass
class Case(scenes.Scene):
    """One extreme case, a scene like those of ``compare``: how to build it,
    how long to run it, how to judge it."""

    name: str = field()  # required (field(): the scenes' class attribute `name` is no default here)
    title: str = field()
    builder: Callable[[], rebound.Simulation]  # a new simulation at t = 0
    duration: float  # how long to run it (t_end)
    time_scale: float  # the shortest dynamical time (period); sets first steps
    reference_kind: str = "ias15"  # or "kepler" (exact two-body) or "radial" (exact infall)
    fixed_dt: Optional[float] = None  # fixed steps for pfvi (epsilon = 0) and WHFast
    whfast_dt: Optional[float] = None  # default time_scale / 100
    note: str = ""
    exact: Optional[Callable[[float], Vector]] = None  # callable(t) -> relative position (x, y, z) for exact references
    tolerance: verdict.Tolerance = verdict.DEFAULT  # what "accurate" means for this case

    families = ("pfvi", "ias15", "whfast")

    def build(self, counter: scenes.Counter = None) -> rebound.Simulation:
        # counter: unused, as in every scene whose force is REBOUND's gravity
        # (counts_own_forces False: compare counts through additional_forces).
        return self.builder()

    @property
    def params(self) -> Dict[str, Any]:
        return {"case": self.name, "t_end": self.duration, "time_scale": self.time_scale,
                "reference": self.reference_kind, "fixed_dt": self.fixed_dt}

    @property
    def period(self) -> float:
        return self.time_scale

    @property
    def periods(self) -> float:  # type: ignore[override]
        return self.duration / self.time_scale

    @property
    def t_end(self) -> float:
        return self.duration

    def describe(self) -> str:
        return self.title

    @property
    def slug(self) -> str:
        return self.name

    def reference(self) -> Dict[str, Any]:
        """As a scene's: every particle's position at t_end (IAS15), or for an
        exact case the relative position of body 1 about body 0."""
        if self.exact is None:
            return super().reference()
        return {"relative": self.exact(self.duration), "uncertainty": 0.0, "how": "exact"}

    def position_error(self, sim: rebound.Simulation, reference: Dict[str, Any]) -> float:
        if "relative" not in reference:
            return super().position_error(sim, reference)
        d = sim.particles[1] - sim.particles[0]
        return math.dist((d.x, d.y, d.z), reference["relative"])

    def relative_position_error(self, sim: rebound.Simulation, reference: Dict[str, Any]) -> Optional[float]:
        if "relative" not in reference:
            return super().relative_position_error(sim, reference)
        d = sim.particles[1] - sim.particles[0]
        return verdict.relative_vector_error((d.x, d.y, d.z), reference["relative"])

    @property
    def whfast_step(self) -> float:
        if self.fixed_dt is not None:
            return self.fixed_dt
        return self.whfast_dt if self.whfast_dt is not None else self.time_scale / 100.0


# --- the cases ---------------------------------------------------------------

def _G():
    return scenes.rebound_G()


def _two_body(e, m=1e-3, a=1.0, f=math.pi, mass=1.0):
    def build():
        sim = scenes.new_simulation()
        sim.add(m=mass)
        sim.add(m=m, a=a, e=e, f=f)
        sim.move_to_com()
        return sim
    return build


def _kepler_exact(build):
    sim = build()
    elements = scenes.orbit_elements(sim)
    mass, m = sim.particles[0].m, sim.particles[1].m

    def exact(t):
        d = scenes.kepler_relative(_G(), mass, m, elements, t)
        return d.x, d.y, d.z
    return exact


def _period(a, mass):
    return 2.0 * math.pi * math.sqrt(a**3 / (_G() * mass))


def _kepler_case(name, title, e, periods, m=1e-3, fixed_dt=None, note="", tolerance=verdict.DEFAULT):
    build = _two_body(e, m=m)
    period = _period(1.0, 1.0 + m)
    return Case(name, title, build, periods * period, period, reference_kind="kepler", note=note,
                fixed_dt=(fixed_dt * period if fixed_dt is not None else None), exact=_kepler_exact(build),
                tolerance=tolerance)


def _conic(q, e, f0, m=1e-3, mass=1.0):
    """A body on a conic of pericentre q and eccentricity e >= 1 (or any e), at true anomaly f0."""
    def build():
        G = _G()
        p = q * (1.0 + e)
        r = p / (1.0 + e * math.cos(f0))
        k = math.sqrt(G * (mass + m) / p)
        sim = scenes.new_simulation()
        sim.add(m=mass)
        sim.add(m=m, x=r * math.cos(f0), y=r * math.sin(f0), vx=-k * math.sin(f0), vy=k * (e + math.cos(f0)))
        sim.move_to_com()
        return sim
    return build


def _time_from_pericentre(q, e, f, mass):
    """Time from pericentre to true anomaly f on a parabola or hyperbola."""
    G = _G()
    if e == 1.0:
        D = math.tan(f / 2.0)
        p = 2.0 * q
        return 0.5 * math.sqrt(p**3 / (G * mass)) * (D + D**3 / 3.0)
    a = q / (e - 1.0)
    F = 2.0 * math.atanh(math.sqrt((e - 1.0) / (e + 1.0)) * math.tan(f / 2.0))
    return (e * math.sinh(F) - F) * math.sqrt(a**3 / (G * mass))


def _flyby_case(e):
    q, m = 0.005, 1e-3
    f_limit = math.pi if e == 1.0 else math.acos(-1.0 / e)
    f0 = -(170.0 / 180.0 * math.pi if e == 1.0 else 0.95 * f_limit)
    t_half = abs(_time_from_pericentre(q, e, f0, 1.0 + m))
    kind = "parabolic" if e == 1.0 else "hyperbolic"
    # Time scale: the pericentre passage, q / v_q.
    v_q = math.sqrt(_G() * (1.0 + m) * (1.0 + e) / q)
    return Case(f"flyby-e{e:g}", f"{kind} flyby, e = {e:g}: Jupiter-mass body past a Sun at q = {q} AU, "
                f"true anomaly {math.degrees(f0):.0f} to {math.degrees(-f0):.0f} deg",
                _conic(q, e, f0, m), 2.0 * t_half, 2.0 * math.pi * q / v_q)


def _radial_infall():
    """A Jupiter-mass body released at rest at r0 = 1 AU falls onto a Sun: zero
    angular momentum, curvature frequency 0; stopped at r = 0.01 AU."""
    r0, r_stop, m = 1.0, 0.01, 1e-3
    a = r0 / 2.0
    G = _G()
    scale = math.sqrt(a**3 / (G * (1.0 + m)))

    def eccentric_anomaly(t):
        # r = a (1 - cos E), t = scale (E - sin E - pi), from E = pi at rest.
        target = t / scale + math.pi
        E = math.pi + 1e-3
        for _ in range(100):
            step = (E - math.sin(E) - target) / (1.0 - math.cos(E))
            E -= step
            if abs(step) < 1e-16:
                break
        return E

    E_stop = 2.0 * math.pi - math.acos(1.0 - r_stop / a)
    t_stop = scale * (E_stop - math.sin(E_stop) - math.pi)

    def build():
        sim = scenes.new_simulation()
        sim.add(m=1.0)
        sim.add(m=m, x=r0)
        sim.move_to_com()
        return sim

    def exact(t):
        return a * (1.0 - math.cos(eccentric_anomaly(t))), 0.0, 0.0

    free_fall = scale * math.pi
    return Case("radial-infall", f"radial infall of a Jupiter-mass body from rest at {r0:g} AU (zero angular momentum, curvature "
                f"frequency 0), stopped at r = {r_stop:g} AU, {t_stop / free_fall:.4f} of the free-fall time",
                build, t_stop, 2.0 * math.pi * math.sqrt(r_stop**3 / G), reference_kind="radial", exact=exact,
                note="The last hundredth of the fall is left out: the collision itself is a singularity.")


def _pythagorean():
    """Burrau's problem: masses 3, 4, 5 at rest at the corners of a 3-4-5 triangle."""
    def build():
        sim = scenes.new_simulation()
        for m, x, y in ((3.0, 1.0, 3.0), (4.0, -2.0, -1.0), (5.0, 1.0, -1.0)):
            sim.add(m=m, x=x, y=y)
        sim.move_to_com()
        return sim
    # In G = 1 units the first very close approach is near t = 15.8; run to 20.
    unit = 1.0 / math.sqrt(_G())
    return Case("pythagorean", "start from zero velocity: Burrau's three bodies (3, 4, 5 Msun at rest on a "
                "3-4-5 AU triangle), through its close approaches to t = 20 in G = 1 units",
                build, 20.0 * unit, 0.1 * unit)


def _jupiter_encounter(radius: float = 0.0) -> Case:
    """Two Jupiter-mass planets on crossing orbits, 0.006 AU apart at mid-run
    (with a radius, each that large, REBOUND's collisions "direct" and "merge")."""
    half = 0.3

    def build():
        G = _G()
        sim = scenes.new_simulation()
        sim.add(m=1.0)
        sim.add(m=1e-3, a=1.0, e=0.0)
        v = math.sqrt(G)
        # The second planet, near the first, on an eccentric orbit crossing its path.
        sim.add(m=1e-3, x=1.005, y=0.003, z=0.001, vx=0.45 * v, vy=1.1 * v, vz=0.0)
        sim.move_to_com()
        sim.integrator = "ias15"
        sim.integrator.epsilon = 1e-12
        sim.dt = -1e-4
        sim.integrate(-half, exact_finish_time=1)
        sim.t = 0.0
        sim.integrator = "leapfrog"  # drops IAS15's state; the runner chooses the integrator and dt
        sim.steps_done = 0
        if radius > 0.:
            sim.particles[1].r = radius
            sim.particles[2].r = radius
            sim.collision = "direct"
            sim.collision_resolve = "merge"
        return sim
    if radius > 0.:
        return Case("jupiter-merger", f"the close encounter of jupiter-encounter with radii of {radius:g} AU: the "
                    "planets meet and merge (REBOUND's collisions 'direct', resolve 'merge') inside the step that "
                    "passes 0.006 AU", build, 2.0 * half, _period(1.0, 1.0),
                    note="The merger is found by each integrator's own collision search; pfvi's steps end at the "
                         "contact (docs/collisions.md). Judged by the positions alone: the merger takes 12% of "
                         "the energy.",
                    tolerance=verdict.Tolerance(energy=math.inf, position=verdict.DEFAULT.position))
    return Case("jupiter-encounter", "close encounter of two Jupiter-mass planets on crossing orbits (a = 1 AU "
                "circular; e ~ 0.4), 0.006 AU (0.09 Hill radii) apart at t = 0.3 yr", build, 2.0 * half,
                _period(1.0, 1.0), note="WHFast's Jacobi splitting is not meant for close encounters.")


def _stiff_binary():
    """A tight binary (P = 0.001 yr) with a companion whose period is 10^4 times longer."""
    a_in, e_in = 0.01, 0.5
    P_in = _period(a_in, 1.0)
    a_out = (_G() * 1.1 * (1e4 * P_in / (2.0 * math.pi)) ** 2) ** (1.0 / 3.0)

    def build():
        sim = scenes.new_simulation()
        sim.add(m=0.5)
        sim.add(m=0.5, a=a_in, e=e_in)
        sim.add(m=0.1, a=a_out, e=0.3, inc=0.5)
        sim.move_to_com()
        return sim
    return Case("stiff-binary", f"stiff: 0.5 + 0.5 Msun binary, a = {a_in} AU, e = {e_in} (P = {P_in:.3g} yr) with a "
                f"0.1 Msun companion at a = {a_out:.3g} AU (periods 10^4 apart), one outer period",
                build, 1e4 * P_in, P_in)


#: A compact system of five planets (Kepler-11-like): (a [AU], m [Msun]) about a Sun, e = 0.02.
COMPACT_PLANETS = ((0.091, 1.3e-5), (0.107, 2.7e-5), (0.155, 2.4e-5), (0.195, 2.5e-5), (0.25, 2.5e-5))


def compact_planets() -> rebound.Simulation:
    """Five planets of 13 to 27 Earth masses at 0.091 to 0.25 AU about a Sun
    (e = 0.02, inclinations 0 to 2 deg): a compact multi-planet system, whose
    step density has as many frequencies as planets."""
    sim = scenes.new_simulation()
    sim.add(m=1.0)
    for i, (a, m) in enumerate(COMPACT_PLANETS):
        sim.add(m=m, a=a, e=0.02, inc=math.radians(0.5 * i), M=1.0 + 2.1 * i, omega=0.7 * i,
                primary=sim.particles[0])
    sim.move_to_com()
    return sim


def compact_planets_period() -> float:
    """The innermost planet's period: the orbits the compact system counts."""
    return _period(COMPACT_PLANETS[0][0], 1.0)


def _planetary_energy_case():
    """The outer solar system over 1000 Jupiter orbits, held to 1e-9 in energy."""
    scene = scenes.make("outer-solar-system")
    jupiter = _period(5.2026, 1.0)
    return Case("planetary-energy", "outer solar system (the Sun, four giants and a Pluto-like body) over 1000 "
                "Jupiter orbits, 1.2e4 yr: a planetary system's energy at the defaults, held to 1e-9",
                scene.build, 1000.0 * jupiter, jupiter, tolerance=verdict.Tolerance(energy=1e-9, position=1e-2),
                note="docs/roundoff.md and benchmarks/planetary_energy.py: before the planets' encounter terms "
                     "were weighted by their pull (issue 36), the step track's corrections (asymmetric steps) "
                     "made pfvi's energy error at the defaults grow over 1e4 and more orbits.")


def _compact_planets_case():
    period = compact_planets_period()
    return Case("compact-planets", "compact system: five planets of 13-27 Earth masses at 0.091-0.25 AU "
                "(Kepler-11-like), 1000 orbits of the innermost, held to 1e-7 in energy", compact_planets,
                1000.0 * period, period, tolerance=verdict.Tolerance(energy=1e-7, position=1e-2))


#: The Centaur: a massless body (a = 7.5 AU, e = 0.35, inclination 6 deg)
#: crossing Jupiter's and Saturn's orbits.
CENTAUR = dict(a=7.5, e=0.35, inc=math.radians(6.0), Omega=0.3, omega=1.1, M=0.5)


def centaur(**elements: float) -> rebound.Simulation:
    """The Sun, Jupiter, Saturn and a massless Centaur crossing both orbits
    (closest approaches: 0.22 AU to Jupiter, within its Hill radius, and
    0.6 AU to Saturn within 411 yr); `elements` replace CENTAUR's."""
    sim = scenes.new_simulation()
    sim.add(m=1.0)
    sim.add(m=scenes.JUPITER["m"], a=scenes.JUPITER["a"], e=scenes.JUPITER["e"])
    sim.add(m=2.857e-4, a=9.5549, e=0.0555, inc=math.radians(2.49), M=2.0)
    sim.add(m=0.0, **{**CENTAUR, **elements})
    sim.move_to_com()
    return sim


def _centaur_case():
    period = _period(CENTAUR["a"], 1.0)
    return Case("centaur", "massless Centaur (a = 7.5 AU, e = 0.35) crossing Jupiter's and Saturn's orbits, "
                "20 of its orbits (411 yr): encounters with two giants, 0.22 AU from Jupiter at the closest",
                centaur, 20.0 * period, _period(scenes.JUPITER["a"], 1.0),
                note="Chaotic: a shift of 1e-10 AU grows 1.3e7-fold over the run (IAS15 at 1e-11), so "
                     "every run's position error is its error per orbit amplified (docs/stability.md).")


def _u_at_pericentre_dt(e, u):
    """The step at which u = omega dt at pericentre of a unit orbit (Sun + 1e-3) equals u."""
    G, mass, a = _G(), 1.001, 1.0
    r = a * (1.0 - e)
    v = math.sqrt(G * mass * (1.0 + e) / r)
    omega = (G * mass / r**2) / v  # |v x a| / |v|^2 at pericentre
    return u / omega / _period(a, mass)  # in periods


def _build_cases():
    cases = []
    for e in (0.99, 0.999, 0.9999):
        cases.append(_kepler_case(f"kepler-e{e:g}", f"Kepler e = {e:g}, 10 periods from apocentre", e, 10.0))
    for e in (1.0, 1.5, 5.0):
        cases.append(_flyby_case(e))
    cases.append(_radial_infall())
    cases.append(_pythagorean())
    cases.append(_jupiter_encounter())
    cases.append(_jupiter_encounter(radius=0.005))
    for m in (1e-12, 1e-6, 1e-3, 1.0):
        cases.append(_kepler_case(f"mass-ratio-{m:g}", f"mass ratio {m:g}: Kepler e = 0.5, 10 periods, "
                                  "centre-of-mass frame", 0.5, 10.0, m=m))
    e = 0.9
    for label, u in (("at", 1.0), ("4x", 4.0), ("40x", 40.0)):
        dt = _u_at_pericentre_dt(e, u)
        cases.append(_kepler_case(f"fixed-u-{label}", f"fixed steps of {dt:.3g} periods, u = omega dt = {u:g} at "
                                  f"pericentre ({label} u_max = 1), Kepler e = {e}, 3 periods", e, 3.0,
                                  fixed_dt=dt))
    # 1000 steps of 1e-12 periods move the body by 1e-9 of its orbit: any
    # error above round-off (1e-12 leaves room for 1000 steps of it) is a fault.
    tiny = _kepler_case("fixed-1e-12", "fixed steps of 1e-12 periods, 1000 steps, Kepler e = 0.9", 0.9,
                        1000 * 1e-12, fixed_dt=1e-12, tolerance=verdict.Tolerance(energy=1e-12, position=1e-12))
    cases.append(tiny)
    cases.append(_kepler_case("long-e0.99", "10^5 periods at e = 0.99 (stopped by the budget if slower)",
                              0.99, 1e5))
    cases.append(_stiff_binary())
    cases.append(_planetary_energy_case())
    cases.append(_compact_planets_case())
    cases.append(_centaur_case())
    return {c.name: c for c in cases}


_CASES = None


def cases() -> Dict[str, Case]:
    """Every case, by name (built once per process: some need G from REBOUND)."""
    global _CASES
    if _CASES is None:
        _CASES = _build_cases()
    return _CASES


# --- the integrators -----------------------------------------------------------

@dataclass(frozen=True)
class Config:
    family: str  # pfvi, ias15, whfast
    #: pfvi's options beyond its defaults, (name, value) pairs (as compare.Setting's).
    options: Tuple[Tuple[str, Any], ...] = ()
    epsilon: Optional[float] = None

    @property
    def label(self) -> str:
        if self.family == "pfvi":
            return pfvi_label(dict(self.options))
        return self.family.upper() if self.family != "whfast" else "WHFast"


#: The integrator families of the stability cases.
FAMILIES = ("pfvi", "ias15", "whfast")


def default_configs(integrators: Sequence[str] = FAMILIES, fittings: Sequence[str] = FITTINGS,
                    stages: Sequence[int] = STAGES, epsilon: float = 1e-6,
                    ias15_epsilon: float = 1e-9) -> List[Config]:
    """pfvi at its defaults first (but epsilon), then each fitting at each
    of `stages` (the seed's with its frequency and centre); IAS15; WHFast."""
    configs = []
    for family in checks.names(integrators, FAMILIES, "integrators", "an integrator"):
        if family == "pfvi":
            configs.append(Config("pfvi", (), epsilon))
            configs += [Config("pfvi", (("stages", s),) + ((("fitting", f),) if f != DEFAULTS["fitting"] else ()),
                               epsilon) for s in stages for f in fittings]
        elif family == "ias15":
            configs.append(Config("ias15", epsilon=ias15_epsilon))
        else:
            configs.append(Config("whfast"))
    return configs


def configure(sim: rebound.Simulation, case: Case, config: Config) -> None:
    if config.family == "pfvi":
        fixed = case.fixed_dt is not None
        # dt: the fixed step, or the cap on adaptive steps
        configure_integrator(sim, "pfvi", dt=case.fixed_dt if fixed else case.time_scale / 10.0,
                             epsilon=0.0 if fixed else config.epsilon, **pfvi_options(dict(config.options)))
    elif config.family == "ias15":
        configure_integrator(sim, "ias15", dt=case.fixed_dt if case.fixed_dt is not None else case.time_scale / 100.0,
                             epsilon=config.epsilon)
    else:
        configure_integrator(sim, "whfast", dt=case.whfast_step)


# --- one run -------------------------------------------------------------------

def _energies(sim):
    T = 0.0
    com = sim.com()
    for p in sim.particles:
        T += 0.5 * p.m * ((p.vx - com.vx) ** 2 + (p.vy - com.vy) ** 2 + (p.vz - com.vz) ** 2)
    E = sim.energy()
    return E, T


def _energy_scale(sim):
    """|E0|, or |T0| + |V0| where E0 is round-off of a cancellation (a parabola)."""
    E, T = _energies(sim)
    magnitude = abs(T) + abs(E - T)
    return abs(E) if abs(E) > 1e-6 * magnitude else magnitude


def _positions(sim):
    return [(p.x, p.y, p.z) for p in sim.particles]


def _identity(case_name: str, config: Config, budget: float) -> Run:
    """A run of `config` on a case before it has run (no finite state yet)."""
    return Run(runs.STABILITY, case_name, config.family, config.label, budget_s=budget, finite=False,
               options=_row_options(config))


def _row_options(config: Config) -> Dict[str, Any]:
    """What a report row records of a run's options: pfvi's fitting and s as run."""
    if config.family != "pfvi":
        return {"fitting": None, "stages": None, "epsilon": config.epsilon}
    opts = {**DEFAULTS, **dict(config.options)}
    return {"fitting": opts["fitting"], "stages": opts["stages"], "epsilon": config.epsilon}


def run(case_name: str, config: Config, budget: float) -> Run:
    """One run of `config` on a case, within `budget` seconds of integration (not yet judged)."""
    case = cases()[case_name]
    row = _identity(case_name, config, budget)
    row.status = "finished"
    sim = case.build()
    configure(sim, case, config)
    E0 = sim.energy()
    scale = _energy_scale(sim)
    worst = 0.0
    # The budget is enforced inside integrate(): REBOUND releases the GIL
    # while it integrates, so a timer thread can call sim.stop(), which ends
    # the integration after the step under way (a run whose steps collapse
    # may otherwise not reach its next checkpoint at all).
    out_of_time = threading.Event()

    def stop():
        out_of_time.set()
        sim.stop()

    timer = threading.Timer(budget, stop)
    tick = time.perf_counter()
    timer.start()
    try:
        for k in range(1, CHECKPOINTS + 1):
            last = k == CHECKPOINTS
            sim.integrate(case.t_end * k / CHECKPOINTS, exact_finish_time=1 if last else 0)
            worst = max(worst, abs(sim.energy() - E0) / scale)
            if out_of_time.is_set():
                row.status = f"stopped by the budget of {budget:g} s"
                break
    except RuntimeError as error:  # pfvi refuses a step (state unchanged) or REBOUND stops
        row.status = f"refused: {error}"
    except Exception as error:  # noqa: BLE001 - any other failure is a result of the run, kept with its type
        row.status = f"error: {type(error).__name__}: {error}"
    finally:
        timer.cancel()
    wall = time.perf_counter() - tick
    E = sim.energy()
    row.t, row.fraction, row.wall_s, row.steps = float(sim.t), float(sim.t) / case.t_end, wall, int(sim.steps_done)
    row.energy_error_final, row.energy_error_max = abs(E - E0) / scale, max(worst, abs(E - E0) / scale)
    row.positions = _positions(sim)
    row.finite = all(math.isfinite(x) for p in row.positions for x in p)
    if config.family == "pfvi":
        row.pfvi = runs.pfvi_counts(sim)
    return row


def reference_positions(case_name: str, t: float, epsilon: float = scenes.REFERENCE_EPSILON) -> Any:
    """Every particle's position at t from IAS15 (or the exact solution, relative to particle 0)."""
    case = cases()[case_name]
    if case.exact is not None:  # the "kepler" and "radial" references
        return case.exact(t)
    sim = case.build()
    sim.integrator = "ias15"
    sim.integrator.epsilon = epsilon
    sim.dt = case.time_scale / 100.0
    if t != 0.0:
        sim.integrate(t, exact_finish_time=1)
    return _positions(sim)


def position_error(case: Case, row: Run, reference: Any) -> float:
    """The largest distance from the reference at the time reached (two-body cases: of the relative vector)."""
    positions = row.positions
    assert positions is not None, "a run without a state has no position error"
    if case.reference_kind in ("kepler", "radial"):
        d = [positions[1][k] - positions[0][k] for k in range(3)]
        return math.dist(d, reference)
    return max(math.dist(p, q) for p, q in zip(positions, reference))


def relative_position_error(case: Case, row: Run, reference: Any) -> float:
    """The position error the verdict is judged by: relative to each body's
    reference distance from particle 0 (see :mod:`rebound_pfvi.verdict`)."""
    positions = row.positions
    assert positions is not None, "a run without a state has no position error"
    if case.reference_kind in ("kepler", "radial"):
        d = [positions[1][k] - positions[0][k] for k in range(3)]
        return verdict.relative_vector_error(d, reference)
    if len(positions) != len(reference):
        # (a collision the run made and the reference did not, or the other
        # way round: no body-by-body error, and no accurate verdict)
        return math.inf
    return verdict.relative_position_error(positions, reference)


def judge(case: Case, row: Run) -> Tuple[str, str]:
    """(verdict, detail) of a run (:func:`rebound_pfvi.runs.judge`) against the case's tolerance."""
    return runs.judge(row, case.tolerance)


# --- running many, each in its own process -------------------------------------

def _reference_pair(case_name: str, t: float) -> Dict[str, Any]:
    """The IAS15 reference at t, and the looser run its uncertainty is taken from."""
    return {"best": reference_positions(case_name, t),
            "check": reference_positions(case_name, t, scenes.REFERENCE_CHECK_EPSILON)}


@dataclass
class Report:
    """The runs of every case with every config, and the references they were judged against."""

    rows: List[Run]
    references: Dict[str, Any] = field(default_factory=dict)
    budget: float = 0.0
    wall_s: float = 0.0

    def to_dict(self) -> Dict[str, Any]:
        """The report as JSON-ready data (stability.json, without the command)."""
        return {"budget_s": self.budget, "wall_s": self.wall_s, "rows": [r.to_dict() for r in self.rows],
                "references": self.references,
                "cases": {name: {"title": c.title, "t_end": c.t_end, "reference": c.reference_kind,
                                 "fixed_dt": c.fixed_dt, "whfast_dt": c.whfast_step, "note": c.note}
                          for name, c in cases().items() if name in self.references}}


def what_happened(row: Run) -> str:
    """The verdict with its detail (else the status), and what pfvi counted on the way."""
    parts = [row.verdict_detail if row.verdict_detail else row.status]
    if row.family == "pfvi" and row.pfvi is not None:
        if row.pfvi["n_u_limited"]:
            parts.append(f"u limited in {row.pfvi['n_u_limited']} particle-steps")
        if row.pfvi["n_rejected"]:
            parts.append(f"{row.pfvi['n_rejected']} trial steps rejected")
        if row.pfvi["n_asymmetric"]:
            parts.append(f"{row.pfvi['n_asymmetric']} steps not time-symmetric (n_asymmetric)")
        if row.pfvi.get("n_unresolved"):
            parts.append(f"{row.pfvi['n_unresolved']} steps kept with forces no shorter step resolved (n_unresolved)")
    if row.status == "finished" and not row.finite:
        parts.append("NON-FINITE STATE")
    return "; ".join(parts)


def run_all(case_names: Optional[Sequence[str]] = None, configs: Optional[Sequence[Config]] = None,
            budget: Any = 60.0, workers: int = 2, progress: Optional[ProgressCallback] = None) -> Report:
    """Every case x every config, each run in a process of its own (rebound_pfvi.runner);
    references first. progress(done, total, run) is called as each run ends (before it is judged:
    the runs are judged once all have ended). budget: seconds of integration per run, or a time
    Quantity (``60 * u.s``)."""
    # The command line's checks (rebound_pfvi.checks), with the arguments' names.
    budget, workers = checks.seconds(budget, "budget"), checks.positive_int(workers, "workers")
    table = cases()
    names = checks.names(case_names, table, "case_names", "a case") if case_names else list(table)
    configs = configs or default_configs()
    tick = time.perf_counter()
    references = {}
    integrated = [n for n in names if table[n].reference_kind == "ias15"]
    ref_tasks = [runner.Task(_reference_pair, (n, table[n].t_end)) for n in integrated]
    for name, outcome in zip(integrated, runner.run_tasks(ref_tasks, workers, fresh=True)):
        if outcome[0] != "ok":
            raise RuntimeError(f"the IAS15 reference of case {name} failed: {outcome}")
        best, check = outcome[1]["best"], outcome[1]["check"]
        references[name] = {"positions": best, "uncertainty": max(math.dist(a, b) for a, b in zip(best, check)),
                            "how": f"IAS15 epsilon {scenes.REFERENCE_EPSILON:g}; uncertainty: distance to "
                                   f"epsilon {scenes.REFERENCE_CHECK_EPSILON:g}"}
    for name in names:
        if table[name].reference_kind != "ias15":
            references[name] = {"uncertainty": 0.0, "how": "exact" if table[name].reference_kind == "kepler"
                                else "exact (radial Kepler equation)"}
    pairs = [(n, c) for n in names for c in configs]
    tasks = [runner.Task(run, (n, c, budget), budget + GRACE_SECONDS) for n, c in pairs]
    ended = 0

    def record(index: int, outcome: runner.Outcome) -> None:
        nonlocal ended
        ended += 1
        if progress:
            row = runs.from_outcome(_identity(*pairs[index], budget), outcome)
            if row.status not in runs.FINISHED:  # refused, over budget, crashed: judged without the reference
                row.verdict, row.verdict_detail = judge(table[pairs[index][0]], row)
            progress(ended, len(tasks), row)

    outcomes = runner.run_tasks(tasks, workers, fresh=True, done=record)
    rows = []
    for (name, config), outcome in zip(pairs, outcomes):
        case = table[name]
        row = runs.from_outcome(_identity(name, config, budget), outcome)
        if row.positions is not None and row.finite:
            assert row.t is not None
            if case.reference_kind == "ias15" and row.t != case.t_end:
                reference = reference_positions(name, row.t)
            elif case.reference_kind == "ias15":
                reference = references[name]["positions"]
            else:
                assert case.exact is not None, f"case {name}: an exact reference needs exact(t)"
                reference = case.exact(row.t)
            row.position_error = position_error(case, row, reference)
            row.relative_position_error = relative_position_error(case, row, reference)
        row.verdict, row.verdict_detail = judge(case, row)
        row.what_happened = what_happened(row)
        rows.append(row)
    return Report(rows, references, budget, time.perf_counter() - tick)
