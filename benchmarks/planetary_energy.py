"""Energy of planetary systems at pfvi's defaults over long runs (issue 36, item 6).

    python -P benchmarks/planetary_energy.py --orbits 1e4 --members 4 --output docs/planetary-energy-1e4.md
    python -P benchmarks/planetary_energy.py --orbits 1e6 --members 1 --scenes outer-solar-system
    python -P benchmarks/planetary_energy.py --orbits 1e5 --members 4 --fixed-steps-per-orbit 6.89 --scenes outer-solar-system

Scenes: the outer solar system (scenes.make("outer-solar-system"); orbits
are Jupiter's) and a compact system of five planets of 13 to 27 Earth
masses at 0.091 to 0.25 AU about a Sun (Kepler-11-like; orbits are the
innermost planet's), from stability.compact_planets(). pfvi at its defaults
(epsilon 1e-6, s = 8, symmetric steps), sampled 200 times with
exact_finish_time = 0 (no step is capped by a sample). Members differ in
the last bits of planet 1's x (member k: x (1 + k 2^-52)).

Columns: the RMS of the relative energy error over the first and the last
tenth of the run (over every member's samples), their ratio (issue 36's
goal: <= 2), the slope of log RMS against log t over the ten tenths (goal
over 1e6 orbits: <= 0.5), steps not time-symmetric (n_asymmetric, per
member: goal <= 10 over 1e4 orbits) and the largest RMS of a member's
last tenth against the smallest (runs differing in the last bits should
agree: the track's random walk of issue 25 made them differ by up to
3e3x).
"""
import argparse
import math
import sys
import time
from concurrent.futures import ProcessPoolExecutor

import numpy as np

import rebound_pfvi  # noqa: F401  (registers "pfvi")
from rebound_pfvi import scenes, stability

SCENES = ("outer-solar-system", "compact-planets")
SAMPLES = 200


def build(name):
    """The simulation and the period its orbits are counted in."""
    if name == "outer-solar-system":
        sim = scenes.make("outer-solar-system").build()
        return sim, 2.0 * math.pi * math.sqrt(5.2026**3 / sim.G)
    if name == "compact-planets":
        sim = stability.compact_planets()
        return sim, stability.compact_planets_period()
    raise ValueError(f"scene {name!r}: one of {', '.join(SCENES)}")


def member(name, orbits, k, fixed=None):
    """One run: its energy errors at the samples and what pfvi counted
    (fixed: constant steps of period/fixed instead of the defaults)."""
    sim, period = build(name)
    sim.particles[1].x *= 1.0 + k * 2.0**-52
    sim.integrator = "pfvi"
    if fixed:
        sim.integrator.epsilon = 0.0
        sim.dt = period / fixed
    E0 = sim.energy()
    errors = []
    tick = time.process_time()
    for j in range(1, SAMPLES + 1):
        sim.integrate(orbits * period * j / SAMPLES, exact_finish_time=0)
        errors.append((sim.energy() - E0) / abs(E0))
    it = sim.integrator
    return {"errors": errors, "steps": int(it.n_steps), "asymmetric": int(it.n_asymmetric), "rejected": int(it.n_rejected),
            "cpu_s": time.process_time() - tick}


def summarise(name, orbits, runs):
    tenth = SAMPLES // 10
    rms = [math.sqrt(np.mean([e * e for r in runs for e in r["errors"][i * tenth:(i + 1) * tenth]]))
           for i in range(10)]
    slope = float(np.polyfit(np.log(np.arange(1, 11)), np.log(rms), 1)[0])
    lasts = [math.sqrt(np.mean([e * e for e in r["errors"][-tenth:]])) for r in runs]
    return {"scene": name, "orbits": orbits, "members": len(runs), "first": rms[0], "last": rms[-1],
            "ratio": rms[-1] / rms[0], "slope": slope, "steps": max(r["steps"] for r in runs),
            "asymmetric": max(r["asymmetric"] for r in runs), "rejected": max(r["rejected"] for r in runs),
            "member_spread": max(lasts) / min(lasts), "cpu_s": sum(r["cpu_s"] for r in runs)}


def table(rows):
    out = ["| scene | orbits | members | energy RMS, first tenth | last tenth | last/first | slope | steps | "
           "n_asymmetric (most of a member) | n_rejected | last tenth's RMS, largest/smallest member | CPU s |",
           "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        out.append(f"| {r['scene']} | {r['orbits']:.0e} | {r['members']} | {r['first']:.2e} | {r['last']:.2e} | "
                   f"{r['ratio']:.2f} | {r['slope']:.2f} | {r['steps']} | {r['asymmetric']} | {r['rejected']} | "
                   f"{r['member_spread']:.3g} | {r['cpu_s']:.0f} |")
    return "\n".join(out)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--orbits", type=float, default=1e4)
    parser.add_argument("--members", type=int, default=4)
    parser.add_argument("--scenes", default=",".join(SCENES))
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--output", help="write the table (markdown) here")
    parser.add_argument("--fixed-steps-per-orbit", type=float, default=None,
                        help="constant steps (epsilon = 0) of this many per orbit instead of the defaults")
    args = parser.parse_args(argv)
    names = args.scenes.split(",")
    jobs = [(n, args.orbits, k, args.fixed_steps_per_orbit) for n in names for k in range(args.members)]
    with ProcessPoolExecutor(args.workers) as pool:
        results = list(pool.map(member, *zip(*jobs)))
    rows = [summarise(n, args.orbits, [r for (m, *_), r in zip(jobs, results) if m == n]) for n in names]
    text = table(rows)
    print(text)
    if args.output:
        command = "python -P benchmarks/planetary_energy.py " + " ".join(sys.argv[1:] if argv is None else argv)
        with open(args.output, "w") as f:
            f.write(f"# Planetary energy at pfvi's defaults\n\nGenerated by `{command}`; "
                    "see the script's docstring for the columns.\n\n" + text + "\n")


if __name__ == "__main__":
    main()
