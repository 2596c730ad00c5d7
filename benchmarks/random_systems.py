"""Random systems against IAS15: where pfvi's error leaves what epsilon
promises, outside the scenes it was designed on.

    python -P benchmarks/random_systems.py [--seeds 0:200] [--epsilons 1e-6,1e-7,1e-9] [--json out.json]

Each seed draws a system (G = 1): a star of mass 1 and 1 to 4 bodies of
10^-9 to 0.03 on orbits of e up to 0.995 (half of them 0.85 and above), of
one of these kinds: planets (inclinations to 0.3), a binary companion of
0.05-1 with planets beyond it, test particles beside a planet, a star
passing by on a hyperbola, and planets at any inclination up to retrograde.
It runs 20 orbits of its fastest body (at most t = 200) with 23 outputs,
with IAS15 at epsilon 1e-11 as the reference and pfvi at each epsilon. A
further IAS15 run per body, that body moved along x by 1e-12 of its scale,
measures how much the dynamics amplify a small error: a body's A is its
largest end shift over these runs, over 1e-12 of its scale. A body's error
is the largest over the outputs of its distance to the reference over
epsilon_effective a n t_end (a, n its initial orbit about the star, or its
distance and v/r if unbound): the goal is 10. A run with a body over 10
whose A is below 1e3 is flagged: that error is pfvi's, not the dynamics'.

Prints one line per flagged run and a summary per epsilon: runs, flagged,
the largest error among runs with A < 1e3, and the work (steps plus
rejected trial steps). Compare builds by running it under each
(PYTHONPATH=<build> python3 -P ...) with the same seeds.
"""
import argparse
import json
import math
import random
import sys

import rebound

import rebound_pfvi  # noqa: F401  (registers "pfvi")

KINDS = ("planets", "binary", "test-particles", "flyby", "retrograde")
OUTPUTS = 23
GOAL = 10.0
AMPLIFICATION_MAX = 1e3


def build(seed):
    """The seed's system and its kind."""
    rng = random.Random(seed)
    kind = rng.choice(KINDS)
    sim = rebound.Simulation()
    sim.add(m=1.0)
    base = 0.5
    if kind == "binary":
        sim.add(m=rng.uniform(0.05, 1.0), a=rng.uniform(0.2, 1.0), e=rng.uniform(0.0, 0.9), f=rng.uniform(0, 2 * math.pi))
        base = 4.0
    for k in range(rng.randint(1, 4)):
        m = 0.0 if (kind == "test-particles" and k > 0) else 10 ** rng.uniform(-9, -1.5)
        a = base * 1.6 ** k * rng.uniform(1.0, 1.5)
        e = rng.uniform(0.0, 0.3) if rng.random() < 0.5 else rng.uniform(0.85, 0.995)
        inc = rng.uniform(0.0, math.pi) if kind == "retrograde" else rng.uniform(0.0, 0.3)
        sim.add(m=m, a=a, e=e, inc=inc, Omega=rng.uniform(0, 2 * math.pi), omega=rng.uniform(0, 2 * math.pi),
                f=rng.uniform(0, 2 * math.pi))
    if kind == "flyby":
        sim.add(m=rng.uniform(0.01, 0.5), x=-30.0, y=rng.uniform(2.0, 8.0), z=rng.uniform(-1.0, 1.0),
                vx=rng.uniform(0.5, 2.0))
    sim.move_to_com()
    return sim, kind


def scales(sim):
    """(a, n) per particle: its initial orbit about the star, or its distance
    and v/r where unbound (the star gets the first body's)."""
    star = sim.particles[0]
    out = []
    for p in sim.particles[1:]:
        o = p.orbit(primary=star)
        if 0.0 < o.e < 1.0 and o.a > 0.0:
            out.append((o.a, o.n))
        else:
            r = math.dist(p.xyz, star.xyz)
            out.append((r, math.dist(p.vxyz, star.vxyz) / r))
    return [out[0]] + out


def run(seed, t_end, integrator, epsilon, shift=None):
    """The states at the outputs; shift = (body, dx) moves that body first."""
    sim, _ = build(seed)
    if shift:
        sim.particles[shift[0]].x += shift[1]
    sim.integrator = integrator
    sim.integrator.epsilon = epsilon
    states = []
    for j in range(1, OUTPUTS + 1):
        sim.integrate(t_end * j / OUTPUTS)
        states.append([p.xyz for p in sim.particles])
    return states, sim


def measure(seed, epsilons):
    sim, kind = build(seed)
    sc = scales(sim)
    t_end = min(20 * 2 * math.pi / max(n for _, n in sc[1:]), 200.0)
    reference, _ = run(seed, t_end, "ias15", 1e-11)
    amplification = [0.0] * sim.N
    for k in range(1, sim.N):
        shifted, _ = run(seed, t_end, "ias15", 1e-11, shift=(k, 1e-12 * sc[k][0]))
        for i, (a, b) in enumerate(zip(reference[-1], shifted[-1])):
            amplification[i] = max(amplification[i], math.dist(a, b) / (1e-12 * sc[i][0]))
    rows = []
    for epsilon in epsilons:
        states, s = run(seed, t_end, "pfvi", epsilon)
        used = float(s.integrator.epsilon_effective)
        per_body = [max(math.dist(ref[i], got[i]) for ref, got in zip(reference, states))
                    / (used * sc[i][0] * sc[i][1] * t_end) for i in range(1, sim.N)]
        # The body whose error counts: the largest among those the dynamics
        # do not amplify beyond AMPLIFICATION_MAX, else the largest of all.
        calm = [(e, amplification[i + 1]) for i, e in enumerate(per_body) if amplification[i + 1] < AMPLIFICATION_MAX]
        error, amp = max(calm) if calm else max(zip(per_body, amplification[1:]))
        rows.append(dict(seed=seed, kind=kind, N=sim.N, epsilon=epsilon, error=error, amplification=amp,
                         steps=int(s.integrator.n_steps), rejected=int(s.integrator.n_rejected),
                         asymmetric=int(s.integrator.n_asymmetric)))
    return rows


def parse_seeds(text):
    a, _, b = text.partition(":")
    return range(int(a), int(b)) if b else [int(a)]


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seeds", default="0:200", help="a range first:last+1, or one seed (default 0:200)")
    parser.add_argument("--epsilons", default="1e-6,1e-7,1e-9", help="pfvi's epsilons (default 1e-6,1e-7,1e-9)")
    parser.add_argument("--json", default=None, help="write every run's row to this file")
    args = parser.parse_args(argv)
    epsilons = [float(x) for x in args.epsilons.split(",")]
    rows = []
    for seed in parse_seeds(args.seeds):
        for row in measure(seed, epsilons):
            rows.append(row)
            if row["error"] > GOAL and row["amplification"] < AMPLIFICATION_MAX:
                print(f"flagged: seed {row['seed']} ({row['kind']}, N = {row['N']}) epsilon {row['epsilon']:g}: "
                      f"{row['error']:.3g} epsilon a n, A = {row['amplification']:.3g}", flush=True)
    print("| epsilon | runs | flagged (> 10 epsilon a n, A < 1e3) | largest error with A < 1e3 | steps + rejected |")
    print("|---|---|---|---|---|")
    for epsilon in epsilons:
        mine = [r for r in rows if r["epsilon"] == epsilon]
        calm = [r["error"] for r in mine if r["amplification"] < AMPLIFICATION_MAX]
        flagged = sum(1 for r in mine if r["error"] > GOAL and r["amplification"] < AMPLIFICATION_MAX)
        work = sum(r["steps"] + r["rejected"] for r in mine)
        print(f"| {epsilon:g} | {len(mine)} | {flagged} | {max(calm) if calm else float('nan'):.3g} | {work} |")
    if args.json:
        with open(args.json, "w", encoding="utf-8") as f:
            json.dump(rows, f, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
