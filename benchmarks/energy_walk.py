"""How fast round-off walks the energy, per orbit: pfvi against IAS15 on Kepler
pairs, and this build against another (--baseline), each member sampled
densely so that the walk's step is measured, not one run's end.

    python -P benchmarks/energy_walk.py [--e 0.99,0.5] [--epsilon 1e-12] [--orbits 1e4]
                                        [--members 16] [--ias15] [--baseline "PYTHONPATH=... python3"]

Each member is Kepler e (m = 1 and 1e-3, a = 1 + k 2^-40, mean anomaly
0.37 k, COM frame, G = 1), sampled 2000 times over the run without
shortening a step (exact_finish_time = 0). The relative energy error's
increments over a lag L are collected over every member and sample, and
their RMS printed for L = 5, 20, 80, 320 and 1280 orbits' worth (at the
default --orbits): a random walk grows as L^(1/2) (a factor 2 per row), a
drift as L. Members walk at different rates (4 members of e = 0.99 gave
3.3e-14 or 3.9e-14 at one lag, by which 4), so the shortest lag's RMS is
given with its standard error from the spread over the members; the longer
lags have fewer independent increments. docs/roundoff.md quotes it.
"""
import argparse
import math
import shlex
import subprocess
import sys

SAMPLES = 2000
LAGS = (1, 4, 16, 64, 256)

CHILD = r"""
import json, sys
from multiprocessing import Pool
import rebound, rebound_pfvi
e, epsilon, orbits, members, family = float(sys.argv[1]), float(sys.argv[2]), float(sys.argv[3]), int(sys.argv[4]), sys.argv[5]
SAMPLES = int(sys.argv[6])

def run(k):
    sim = rebound.Simulation()
    sim.G = 1.0
    sim.add(m=1.0)
    sim.add(m=1e-3, a=1.0 + k*2.0**-40, e=e, M=0.37*k)
    sim.move_to_com()
    period = sim.particles[1].P
    sim.integrator = family
    sim.integrator.epsilon = epsilon
    energy0 = sim.energy()
    out = []
    for j in range(1, SAMPLES + 1):
        sim.integrate(orbits*period*j/SAMPLES, exact_finish_time=0)
        out.append(sim.energy()/energy0 - 1.0)
    return out, sim.steps_done

with Pool(2) as pool:
    print(json.dumps(pool.map(run, range(members))))
"""


def walk(prefix, e, epsilon, orbits, members, family):
    cmd = shlex.split(prefix) + ["-c", CHILD, str(e), str(epsilon), str(orbits), str(members), family, str(SAMPLES)]
    run = subprocess.run(cmd, capture_output=True, text=True)
    if run.returncode != 0:
        raise RuntimeError(f"child failed: {run.stderr[-2000:]}")
    import json
    series = json.loads(run.stdout.strip().splitlines()[-1])
    rows = []
    for lag in LAGS:
        values = [(s[i + lag] - s[i])**2 for s, _ in series for i in range(SAMPLES - lag)]
        rows.append(math.sqrt(sum(values) / len(values)))
    # The shortest lag's mean square member by member: members walk at
    # different rates (their orbits' phases against the steps), so its
    # standard error comes from their spread, not from the count of increments.
    per = [sum((s[i + LAGS[0]] - s[i])**2 for i in range(SAMPLES - LAGS[0])) / (SAMPLES - LAGS[0]) for s, _ in series]
    mean = sum(per) / len(per)
    se = math.sqrt(sum((v - mean)**2 for v in per) / (len(per) - 1) / len(per)) if len(per) > 1 else float("nan")
    steps = series[0][1] / orbits
    return rows, steps, 0.5 * se / mean


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--e", default="0.99,0.5", help="eccentricities, comma-separated")
    parser.add_argument("--epsilon", type=float, default=1e-12)
    parser.add_argument("--orbits", type=float, default=1e4)
    parser.add_argument("--members", type=int, default=16)
    parser.add_argument("--ias15", action="store_true", help="IAS15 too, at the same epsilon")
    parser.add_argument("--baseline", help="another build's python command, e.g. 'env PYTHONPATH=... python3'")
    args = parser.parse_args(argv)
    settings = [("pfvi", "pfvi", sys.executable + " -P")]
    if args.baseline:
        settings.append(("pfvi (baseline)", "pfvi", args.baseline + " -P"))
    if args.ias15:
        settings.append(("ias15", "ias15", sys.executable + " -P"))
    lags = [lag * args.orbits / SAMPLES for lag in LAGS]
    print(f"Energy walk: RMS of the relative energy error's increments over a lag; epsilon {args.epsilon:g}, "
          f"{args.orbits:g} orbits, {args.members} members")
    print()
    print("| e | integrator | steps/orbit | " + " | ".join(f"lag {lag:g} orbits" for lag in lags) + " |")
    print("|---|---|---|" + "---|" * len(lags))
    for e in (float(x) for x in args.e.split(",")):
        for label, family, prefix in settings:
            rows, steps, relative = walk(prefix, e, args.epsilon, args.orbits, args.members, family)
            print(f"| {e:g} | {label} | {steps:.1f} | {rows[0]:.3g} (+-{100 * relative:.0f}%) | "
                  + " | ".join(f"{v:.3g}" for v in rows[1:]) + " |", flush=True)


if __name__ == "__main__":
    main()
