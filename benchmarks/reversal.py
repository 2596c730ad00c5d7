"""Reversal after a flip and integrate-back over a grid of eccentricities and
starting phases (issue 36, item 2).

For each configuration (stages, epsilon), eccentricity and starting true
anomaly, a Kepler pair (a = 1, m = 1e-3 about 1 Msun, G = 1) is

- stepped n times, sim.dt flipped, stepped n times again ("flip"), and
- integrated to T and back to 0 with integrate() ("back"),

and the largest relative miss in t (|t_back|/t_turn) and in position
(max |x_back - x_0| / max |x_0|) is reported, with the asymmetric steps.

    python -P benchmarks/reversal.py                 # the full grid (e every 0.01, 8 phases, 4 configs)
    python -P benchmarks/reversal.py --quick         # e every 0.05, 4 phases, defaults only
"""
import argparse
import math
import time

import rebound

import rebound_pfvi  # noqa: F401  (registers "pfvi")

CONFIGS = [(8, 1e-6), (8, 1e-10), (6, 1e-8), (4, 1e-6)]


def kepler(e, f, stages, epsilon):
    sim = rebound.Simulation()
    sim.add(m=1.0)
    sim.add(m=1e-3, a=1.0, e=e, f=f)
    sim.move_to_com()
    sim.integrator = "pfvi"
    sim.integrator.stages = stages
    sim.integrator.epsilon = epsilon
    return sim


def positions(sim):
    return [(p.x, p.y, p.z) for p in sim.particles]


def miss(sim, start, t_turn):
    scale = max(math.hypot(*x) for x in start)
    dx = max(math.dist(a, b) for a, b in zip(start, positions(sim)))
    return abs(sim.t)/abs(t_turn), dx/scale


def flip(e, f, stages, epsilon, n):
    sim = kepler(e, f, stages, epsilon)
    start = positions(sim)
    sim.steps(n)
    t_turn = sim.t
    sim.dt = -sim.dt
    sim.steps(n)
    return miss(sim, start, t_turn) + (sim.integrator.n_asymmetric,)


def back(e, f, stages, epsilon, T):
    sim = kepler(e, f, stages, epsilon)
    start = positions(sim)
    sim.integrate(T)
    sim.integrate(0.0)
    return miss(sim, start, T) + (sim.integrator.n_asymmetric,)


def grid(es, phases, configs, n, T, tolerance=1e-10):
    rows = []
    for stages, epsilon in configs:
        worst = {"flip": (0.0, 0.0, None), "back": (0.0, 0.0, None)}
        failures = []
        t0 = time.time()
        for e in es:
            for f in phases:
                for kind, run, arg in (("flip", flip, n), ("back", back, T)):
                    dt, dx, asym = run(e, f, stages, epsilon, arg)
                    if max(dt, dx) > max(worst[kind][:2]):
                        worst[kind] = (dt, dx, (e, f))
                    if not (dt <= tolerance and dx <= tolerance):
                        failures.append((kind, e, f, dt, dx, asym))
        rows.append((stages, epsilon, worst, failures, time.time() - t0))
    return rows


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--steps", type=int, default=1000, help="steps before the flip (default 1000)")
    parser.add_argument("--T", type=float, default=400.0, help="integrate to T and back (default 400)")
    args = parser.parse_args()
    if args.quick:
        es = [round(0.05*k, 2) for k in range(20)]
        phases = [math.pi*k/2 for k in range(4)]
        configs = CONFIGS[:1]
    else:
        es = [round(0.01*k, 2) for k in range(100)]
        phases = [2*math.pi*k/8 for k in range(8)]
        configs = CONFIGS
    print(f"e: {es[0]} ... {es[-1]} ({len(es)}), phases (true anomaly): {len(phases)} incl. apocentre (pi), "
          f"flip after {args.steps} steps, integrate to {args.T:g} and back; tolerance 1e-10 relative")
    print("| s | epsilon | worst flip: t, x (e, f) | worst integrate-back: t, x (e, f) | cases over 1e-10 | wall |")
    print("|---|---|---|---|---|---|")
    for stages, epsilon, worst, failures, wall in grid(es, phases, configs, args.steps, args.T):
        cells = []
        for kind in ("flip", "back"):
            dt, dx, where = worst[kind]
            at = f"(e {where[0]:g}, f {where[1]:.2f})" if where else ""
            cells.append(f"{dt:.1e}, {dx:.1e} {at}")
        print(f"| {stages} | {epsilon:g} | {cells[0]} | {cells[1]} | {len(failures)} of {2*len(es)*len(phases)} | {wall:.0f} s |")
        for failure in failures[:10]:
            print("    over:", failure)


if __name__ == "__main__":
    main()
