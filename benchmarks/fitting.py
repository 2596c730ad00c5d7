"""What fitting buys: the measured payoff of every fitting, frequency and
centre against the classical scheme ("none"), with fixed steps.

    python -P benchmarks/fitting.py --output docs/results/fitting.md [--quick]

Writes the markdown page docs/results/fitting.md (its tables are the
figures quoted in README.md and docs/method.md; about 15 minutes). Four measurements, each with fixed steps
(epsilon = 0) so that only the discrete Lagrangian differs:

A. Error at equal steps: two bodies (m = 1 and 1e-3, a = 1, COM frame) at
   e = 0, 0.1, 0.3, 0.6, 0.9, 0.95, s = 2, 3, 4, 6, 10 orbits. The error is
   the largest distance (relative to a) from the exact Kepler position
   (REBOUND's elements, mean anomaly advanced by n t) over the run, sampled
   20 times per orbit. The steps per orbit are 25 (1 - e)^-1.5 times a power
   of two: doubled while "none"'s error exceeds 1e-4, halved while it is
   below 1e-8 and the halved step still meets 1e-4, so that it lies far
   above round-off; the table gives "none"'s error over each fitting's
   (> 1: the fitting is more accurate).
B. Steps at equal energy error (the seed's Figure 1 protocol): the fewest
   steps per orbit (bisection over integers) at which the largest relative
   energy error over 10 orbits, sampled 40 times per orbit, is at most
   1e-6, for e = 0.3, 0.6, 0.95; the ratio "none"/fitted.
C. A hierarchical system: star 1, planet 1e-3 at a = 1 (e = 0.05), moon
   1e-7 at 0.005 around the planet (e = 0.1, inclined 0.1), where the moon's
   circle is not about the origin and the planet's tightest pair is, at
   times, its moon; 40 steps per moon orbit, 90 moon orbits (about one
   planet orbit); the moon's largest distance, relative to the planet's,
   from IAS15 (epsilon 1e-12) run alongside, sampled once per moon orbit,
   relative to the moon's distance.
D. Long-term energy: e = 0.95, P/2000 steps, 2000 orbits, s = 2 and 4: the
   largest relative energy error in the first and last tenth, sampled 20
   times per orbit.
E. Under the default adaptive step control (symmetric, epsilon 1e-6 and
   1e-9, s = 4 and 6): steps, final position error and wall time (best of
   2) of "none", the seed's "phase" and "exact radial" on Kepler e = 0.5,
   0.9, 0.95 (20 periods), the comet and the triple (1 period): what the
   default fitting is chosen from.
--quick: fewer cases and shorter runs (a smoke test of the script, not the
page's figures).
"""
from __future__ import annotations

import argparse
import math
import os
import platform
import sys
import time
from typing import Any, Dict, List, Optional, Sequence, Tuple

import rebound

import rebound_pfvi  # noqa: F401  (registers "pfvi")
from rebound_pfvi.integrators import configure
from rebound_pfvi.scenes import Kepler, new_simulation

# (label, fitting, frequency, centre): the classical scheme, the seed's
# scheme as printed, and the new fitting with each frequency and centre.
NONE = ("none", "none", "curvature", "origin")
ORBITS_A = 10.0
SCHEMES: Sequence[Tuple[str, str, str, str]] = (
    ("seed phase", "phase", "curvature", "origin"),
    ("exact curvature", "exact", "curvature", "partner"),
    ("exact radial", "exact", "radial", "partner"),
    ("exact mean-motion", "exact", "mean-motion", "partner"),
    ("exact radial, barycentre", "exact", "radial", "barycentre"),
)


def _pfvi(sim: rebound.Simulation, scheme: Tuple[str, str, str, str], stages: int, dt: float) -> None:
    _, fitting, frequency, centre = scheme
    configure(sim, "pfvi", dt=dt, stages=stages, fitting=fitting, frequency=frequency, centre=centre, epsilon=0.0,
              u_max=1.5)


def _kepler_error(e: float, stages: int, scheme, per_orbit: int, orbits: float = 10.0) -> float:
    """Largest position error of body 1 relative to body 0 over the run (20
    samples per orbit) against the exact Kepler orbit, relative to a: the
    final error alone swings with the phase at which the run ends."""
    scene = Kepler(e=e, periods=orbits)
    sim = scene.build()
    reference = scene.reference()
    _pfvi(sim, scheme, stages, scene.period/per_orbit)
    total, samples = int(round(orbits*per_orbit)), int(round(20*orbits))
    worst, done = 0.0, 0
    try:
        for k in range(1, samples + 1):
            target = (total*k)//samples
            sim.steps(target - done)
            done = target
            worst = max(worst, scene.position_error(sim, reference))
    except RuntimeError:
        return math.inf
    return worst/scene.a


def error_at_equal_steps(eccentricities: Sequence[float], stages: Sequence[int]) -> List[Dict[str, Any]]:
    rows = []
    for e in eccentricities:
        for s in stages:
            per_orbit = int(math.ceil(25.0*(1.0 - e)**-1.5))
            err_none = _kepler_error(e, s, NONE, per_orbit, ORBITS_A)
            while err_none > 1e-4:
                per_orbit *= 2
                err_none = _kepler_error(e, s, NONE, per_orbit, ORBITS_A)
            while err_none < 1e-8 and per_orbit > 8:
                fewer = (per_orbit + 1)//2
                err_fewer = _kepler_error(e, s, NONE, fewer, ORBITS_A)
                if not err_fewer <= 1e-4:
                    break
                per_orbit, err_none = fewer, err_fewer
            ratios = {label: err_none/max(_kepler_error(e, s, sch, per_orbit, ORBITS_A), 1e-300)
                      for sch in SCHEMES for label in [sch[0]]}
            rows.append({"e": e, "s": s, "per_orbit": per_orbit, "none": err_none, "ratios": ratios})
            print(f"A e={e} s={s} n={per_orbit} none={err_none:.2e} "
                  + " ".join(f"{k}={v:.3g}" for k, v in ratios.items()), file=sys.stderr)
    return rows


def _max_energy_error(sim: rebound.Simulation, per_orbit: int, orbits: int, samples_per_orbit: int) -> float:
    E0 = sim.energy()
    worst = 0.0
    chunk = max(1, per_orbit//samples_per_orbit)
    total = orbits*per_orbit
    done = 0
    while done < total:
        n = min(chunk, total - done)
        sim.steps(n)
        done += n
        worst = max(worst, abs((sim.energy() - E0)/E0))
    return worst


def _steps_for_energy(e: float, stages: int, scheme, target: float, orbits: int) -> Optional[int]:
    def ok(n: int) -> bool:
        scene = Kepler(e=e, periods=orbits)
        sim = scene.build()
        _pfvi(sim, scheme, stages, scene.period/n)
        try:
            return _max_energy_error(sim, n, orbits, 40) <= target
        except RuntimeError:
            return False
    lo, hi = 4, 8
    while not ok(hi):
        lo, hi = hi, hi*2
        if hi > 2**22:
            return None
    while hi - lo > max(1, lo//100):
        mid = (lo + hi)//2
        if ok(mid):
            hi = mid
        else:
            lo = mid
    return hi


def steps_at_equal_energy(eccentricities: Sequence[float], stages: Sequence[int], target: float,
                          orbits: int) -> List[Dict[str, Any]]:
    rows = []
    for e in eccentricities:
        for s in stages:
            n_none = _steps_for_energy(e, s, NONE, target, orbits)
            steps = {sch[0]: _steps_for_energy(e, s, sch, target, orbits) for sch in SCHEMES}
            rows.append({"e": e, "s": s, "none": n_none, "steps": steps})
            print(f"B e={e} s={s} none={n_none} {steps}", file=sys.stderr)
    return rows


def _hierarchy() -> rebound.Simulation:
    sim = new_simulation()
    sim.add(m=1.0)
    sim.add(m=1e-3, a=1.0, e=0.05)
    sim.add(m=1e-7, a=0.005, e=0.1, primary=sim.particles[1], inc=0.1)
    sim.move_to_com()
    return sim


def hierarchical(stages: Sequence[int], moon_orbits: int) -> List[Dict[str, Any]]:
    """The moon's largest error relative to the planet over the run, sampled
    once per moon orbit against IAS15 run alongside, relative to its distance."""
    probe = _hierarchy()
    moon_period = probe.particles[2].orbit(primary=probe.particles[1]).P
    d0 = probe.particles[2] - probe.particles[1]
    r_moon = math.sqrt(d0.x**2 + d0.y**2 + d0.z**2)
    rows = []
    for s in stages:
        errors = {}
        for scheme in (NONE,) + tuple(SCHEMES):
            sim, ref = _hierarchy(), _hierarchy()
            _pfvi(sim, scheme, s, moon_period/40)
            configure(ref, "ias15", epsilon=1e-12)
            worst = 0.0
            try:
                for _ in range(moon_orbits):
                    sim.steps(40)
                    ref.integrate(sim.t, exact_finish_time=1)
                    d, dr = sim.particles[2] - sim.particles[1], ref.particles[2] - ref.particles[1]
                    worst = max(worst, math.dist((d.x, d.y, d.z), (dr.x, dr.y, dr.z))/r_moon)
            except RuntimeError as error:
                worst = math.inf
                print(f"C s={s} {scheme[0]}: {error}", file=sys.stderr)
            errors[scheme[0]] = worst
        rows.append({"s": s, "steps": 40*moon_orbits, "errors": errors})
        print(f"C s={s} {errors}", file=sys.stderr)
    return rows


def long_term(stages: Sequence[int], orbits: int, per_orbit: int) -> List[Dict[str, Any]]:
    rows = []
    for s in stages:
        for scheme in (NONE,) + tuple(SCHEMES[:4]):
            scene = Kepler(e=0.95, periods=orbits)
            sim = scene.build()
            _pfvi(sim, scheme, s, scene.period/per_orbit)
            E0 = sim.energy()
            errors = []
            start = time.perf_counter()
            try:
                for _ in range(orbits*20):
                    sim.steps(per_orbit//20)
                    errors.append(abs((sim.energy() - E0)/E0))
            except RuntimeError as error:
                print(f"D s={s} {scheme[0]}: {error}", file=sys.stderr)
                errors.append(math.inf)
            tenth = max(1, len(errors)//10)
            first, last = max(errors[:tenth]), max(errors[-tenth:])
            rows.append({"s": s, "scheme": scheme[0], "first": first, "last": last,
                         "seconds": time.perf_counter() - start})
            print(f"D s={s} {scheme[0]} first={first:.2e} last={last:.2e}", file=sys.stderr)
    return rows


def adaptive(epsilons: Sequence[float], stages: Sequence[int], periods: float) -> List[Dict[str, Any]]:
    from rebound_pfvi.scenes import Comet, Triple

    rows = []
    scenes = [Kepler(e=e, periods=20*periods) for e in (0.5, 0.9, 0.95)] + [Comet(periods=periods),
                                                                            Triple(periods=periods)]
    for scene in scenes:
        reference = scene.reference()
        for epsilon in epsilons:
            for s in stages:
                for scheme in (NONE, SCHEMES[0], SCHEMES[2]):
                    _, fitting, frequency, centre = scheme
                    best, sim = math.inf, None
                    for _ in range(2):
                        sim = scene.build()
                        configure(sim, "pfvi", dt=scene.period/100, stages=s, epsilon=epsilon, fitting=fitting,
                                  frequency=frequency, centre=centre)
                        start = time.perf_counter()
                        sim.integrate(scene.t_end, exact_finish_time=1)
                        best = min(best, time.perf_counter() - start)
                    assert sim is not None
                    rows.append({"scene": scene.slug, "epsilon": epsilon, "s": s, "scheme": scheme[0],
                                 "steps": sim.integrator.n_steps, "error": scene.position_error(sim, reference),
                                 "seconds": best})
                    print(f"E {rows[-1]}", file=sys.stderr)
    return rows


def _g(x: Optional[float], digits: int = 2) -> str:
    if x is None:
        return "-"
    if x == math.inf:
        return "fails"
    return f"{x:.{digits}g}"


def markdown(A, B, C, D, E, args, seconds: float) -> str:
    labels = [sch[0] for sch in SCHEMES]
    out = ["# What fitting buys: measured", "",
           f"Produced by `python -P benchmarks/fitting.py{' --quick' if args.quick else ''}` "
           f"({seconds:.0f} s on {platform.machine()}, {os.cpu_count()} cores, Python {platform.python_version()}, "
           f"REBOUND {rebound.__version__}). The method is in `benchmarks/fitting.py`'s docstring; every run "
           "uses fixed steps (epsilon = 0) and u_max = 1.5. Schemes: **none** is the classical "
           "Lobatto discrete Lagrangian (velocity Verlet at s = 2); **seed phase** is K&V's scheme as "
           "printed in section 3/6, divided by gamma (fitting 'phase', centre 'origin', frequency "
           "'curvature'); **exact ...** is fitting 'exact' with centre 'partner' (or 'barycentre') and "
           "the frequency named.", "",
           "## A. Error ratio at equal steps (\"none\"'s largest position error over 10 orbits / the "
           "fitting's; > 1: fitting better)", "",
           "| e | s | steps/orbit | none's error | " + " | ".join(labels) + " |",
           "|---|---|---|---|" + "---|"*len(labels)]
    for r in A:
        out.append(f"| {r['e']:g} | {r['s']} | {r['per_orbit']} | {r['none']:.1e} | "
                   + " | ".join(_g(r['ratios'][k]) for k in labels) + " |")
    out += ["", f"## B. Steps per orbit at equal energy error (largest relative energy error <= {args.target:g} "
                f"over {args.orbits_b} orbits)", "",
            "| e | s | none | " + " | ".join(labels) + " | best ratio none/fitted |",
            "|---|---|---|" + "---|"*len(labels) + "---|"]
    for r in B:
        fitted = [r['steps'][k] for k in labels]
        best = min((n for n in fitted if n), default=None)
        ratio = (r['none']/best) if (best and r['none']) else None
        out.append(f"| {r['e']:g} | {r['s']} | {_g(r['none'], 6)} | " + " | ".join(_g(n, 6) for n in fitted)
                   + f" | {_g(ratio, 3)} |")
    out += ["", "## C. Hierarchical: a moon around a planet around a star", "",
            f"The moon's largest error relative to the planet over {C[0]['steps']//40} moon orbits, against "
            "IAS15 (epsilon 1e-12), relative to its distance.", "",
            "| s | steps | none | " + " | ".join(labels) + " |", "|---|---|---|" + "---|"*len(labels)]
    for r in C:
        out.append(f"| {r['s']} | {r['steps']} | {r['errors']['none']:.1e} | "
                   + " | ".join(_g(r['errors'][k]) for k in labels) + " |")
    out += ["", f"## D. Long-term energy: e = 0.95, P/{args.per_orbit_d} steps, {args.orbits_d} orbits", "",
            "| s | scheme | max energy error, first tenth | last tenth | last/first | seconds |",
            "|---|---|---|---|---|---|"]
    for r in D:
        out.append(f"| {r['s']} | {r['scheme']} | {r['first']:.2e} | {r['last']:.2e} | "
                   f"{r['last']/r['first'] if r['first'] > 0 else math.nan:.2f} | {r['seconds']:.1f} |")
    out += ["", "## E. The default adaptive step control (symmetric): what fitting changes there", "",
            "Final position error [AU] and wall time (best of 2) at the steps the default control chose; "
            "time relative to \"none\" in brackets.", "",
            "| scene | epsilon | s | steps (none / phase / exact) | none | seed phase | exact radial |",
            "|---|---|---|---|---|---|---|"]
    for k in range(0, len(E), 3):
        group = E[k:k + 3]
        base = group[0]["seconds"]
        out.append(f"| {group[0]['scene']} | {group[0]['epsilon']:g} | {group[0]['s']} | "
                   + " / ".join(str(r["steps"]) for r in group) + " | "
                   + " | ".join(f"{r['error']:.1e}, {r['seconds']:.3f} s ({r['seconds']/base:.2f})" for r in group)
                   + " |")
    return "\n".join(out) + "\n"


def main(argv: Optional[Sequence[str]] = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--output", default=None,
                        help="write the markdown page here (docs/results/fitting.md; default: stdout)")
    parser.add_argument("--quick", action="store_true", help="a short smoke run, not the page's figures")
    args = parser.parse_args(argv)
    start = time.perf_counter()
    if args.quick:
        ecc, stages, args.target, args.orbits_b, args.orbits_d, args.per_orbit_d = (0.1, 0.6), (2, 4), 1e-6, 2, 20, 2000
        ecc_b, stages_b, moon_orbits = (0.3,), (2,), 9
    else:
        ecc, stages, args.target, args.orbits_b, args.orbits_d, args.per_orbit_d = (
            (0.0, 0.1, 0.3, 0.6, 0.9, 0.95), (2, 3, 4, 6), 1e-6, 10, 2000, 2000)
        ecc_b, stages_b, moon_orbits = (0.3, 0.6, 0.95), (2, 4), 90
    A = error_at_equal_steps(ecc, stages)
    B = steps_at_equal_energy(ecc_b, stages_b, args.target, args.orbits_b)
    C = hierarchical((2, 4), moon_orbits)
    D = long_term((2, 4) if not args.quick else (4,), args.orbits_d, args.per_orbit_d)
    E = adaptive((1e-6,) if args.quick else (1e-6, 1e-9), (4,) if args.quick else (4, 6),
                 0.2 if args.quick else 1.0)
    page = markdown(A, B, C, D, E, args, time.perf_counter() - start)
    if args.output:
        with open(args.output, "w") as f:
            f.write(page)
    else:
        sys.stdout.write(page)


if __name__ == "__main__":
    main()
