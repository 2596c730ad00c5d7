"""Outputs where REBOUND changes the state after a step, and steps without
pairs: does a run with many integrate(t) calls end on the same bits, in the
same steps, as one call? (docs/outputs.md, "Periodic boxes, open boxes and
steps without pairs".)

    python -P benchmarks/outputs_edges.py                        # 40 boxes, under 1 s
    python -P benchmarks/outputs_edges.py --seeds 0:200 --boundary open

Boxes: random systems (seeded) in a box of 4, 6 or 10 with boundary
'periodic' (REBOUND wraps a body that leaves it, after every step) or 'open'
(REBOUND removes it): a star with planets, test particles and fast bodies
that cross the edge, or a loose cloud; ghost boxes 0 or 1, softening 0 or
0.02; 5 or 20 time units. Each runs once with one integrate() call and once
with 60 random output times, 10 and 100 even ones. Without pairs: three test
particles in a Kepler potential from additional_forces with gravity off, at
s = 3 and 8, 40 and 7 outputs over 20 time units. Printed: how many runs end
off the single call (not the same bits, or not the same steps), and each
such run (a seed whose body is drawn outside the box, or whose open box
empties, is skipped and counted). With --hook the many-output runs carry a
post-timestep hook that does nothing (REBOUND's own outputs: the bits
differ), and a run is off where it takes more than two steps an output
beyond the single call. Against another build: run it with that build on PYTHONPATH.
"""
import argparse
import math
import random

import rebound

import rebound_pfvi  # noqa: F401  (registers "pfvi")


def box(seed, boundary):
    rng = random.Random(seed)
    sim = rebound.Simulation()
    L = rng.choice([4.0, 6.0, 10.0])
    sim.root_size = L
    sim.N_root_x = sim.N_root_y = sim.N_root_z = 1
    sim.boundary = boundary
    g = rng.choice([0, 1])
    sim.N_ghost_x = sim.N_ghost_y = g
    sim.N_ghost_z = rng.choice([0, g])
    sim.softening = rng.choice([0.0, 0.02])
    kind = rng.choice(["star", "cloud", "light"])
    if kind == "star":
        sim.add(m=1.0)
        for _ in range(rng.randint(1, 3)):
            sim.add(m=rng.choice([0.0, 1e-3]), a=rng.uniform(0.5, 1.5), e=rng.uniform(0.0, 0.7),
                    f=rng.uniform(0.0, 6.28), inc=rng.uniform(0.0, 3.1))
        for _ in range(rng.randint(1, 3)):
            sim.add(m=rng.choice([0.0, 1e-4]), x=rng.uniform(-L/2, L/2), y=rng.uniform(-L/2, L/2),
                    z=rng.uniform(-L/2, L/2), vx=rng.uniform(-2, 2), vy=rng.uniform(-2, 2), vz=rng.uniform(-1, 1))
    else:
        m = 1e-3 if kind == "cloud" else 0.0
        sim.add(m=1e-3, x=0.1, vy=0.2)
        for _ in range(rng.randint(2, 5)):
            sim.add(m=rng.choice([m, 0.0]), x=rng.uniform(-L/2, L/2), y=rng.uniform(-L/2, L/2),
                    z=rng.uniform(-L/2, L/2), vx=rng.uniform(-1, 1), vy=rng.uniform(-1, 1), vz=rng.uniform(-0.5, 0.5))
    sim.move_to_com()
    sim.integrator = "pfvi"
    return sim, rng.choice([5.0, 20.0])


def kepler_potential(simp):
    for i in range(simp.contents.N):
        p = simp.contents.particles[i]
        r2 = p.x*p.x + p.y*p.y + p.z*p.z
        f = -1.0/(r2*math.sqrt(r2))
        p.ax += f*p.x
        p.ay += f*p.y
        p.az += f*p.z


def unpaired(stages):
    sim = rebound.Simulation()
    sim.gravity = "none"
    for k in range(3):
        sim.add(m=0.0, x=1.0 + 0.2*k, y=0.1*k, vy=1.0 - 0.1*k, vz=0.05*k)
    sim.additional_forces = kepler_potential
    sim.integrator = "pfvi"
    sim.integrator.stages = stages
    return sim


def compare(build, T, times, hook=False):
    one = build()
    one.integrate(T)
    many = build()
    if hook:
        # A post-timestep hook that does nothing: outputs are then REBOUND's
        # own (each call's last step cut to its time), so the bits differ;
        # the price is at most two steps an output (the cut, and the first
        # step of the next call, capped at the sim.dt REBOUND restores).
        many.post_timestep_modifications = lambda simp: None
    for t in times:
        many.integrate(t)
    same = (one.N == many.N and one.t == many.t
            and all(p.xyz == q.xyz and p.vxyz == q.vxyz for p, q in zip(one.particles, many.particles)))
    steps = (one.integrator.n_steps, many.integrator.n_steps)
    apart = (max(math.dist(p.xyz, q.xyz) for p, q in zip(one.particles, many.particles))
             if one.N == many.N else float("nan"))
    off = steps[1] > steps[0] + 2*len(times) if hook else not (same and steps[0] == steps[1])
    return off, steps, apart


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seeds", default="0:40", help="boxes' seeds, first:last (exclusive)")
    parser.add_argument("--boundary", default="periodic", choices=["periodic", "open"])
    parser.add_argument("--hook", action="store_true",
                        help="the many-output runs with a post-timestep hook that does nothing: a run is off "
                             "where it takes more than two steps an output beyond the single call's")
    args = parser.parse_args()
    lo, hi = (int(x) for x in args.seeds.split(":"))
    off = total = skipped = 0
    largest = 0.0
    for seed in range(lo, hi):
        try:
            T = box(seed, args.boundary)[1]
        except RuntimeError:   # a body drawn outside the box: REBOUND refuses it
            skipped += 1
            continue
        for cadence in ("60 random", "10 even", "100 even"):
            n = int(cadence.split()[0])
            times = (sorted(random.Random(seed + 7).uniform(0.0, T) for _ in range(n)) + [T]
                     if cadence.endswith("random") else [T*(k + 1)/n for k in range(n - 1)] + [T])
            try:
                result = compare(lambda: box(seed, args.boundary)[0], T, times, args.hook)
            except rebound.NoParticles:   # an open box emptied
                skipped += 1
                continue
            total += 1
            if result[2] == result[2]:   # (NaN where the runs end with different bodies)
                largest = max(largest, result[2])
            if result[0]:
                off += 1
                print(f"box seed {seed}, {cadence} outputs: steps {result[1][0]} (one call) against "
                      f"{result[1][1]}, {result[2]:.2g} apart")
    print(f"boxes ({args.boundary}): {off} of {total} runs off the single call ({skipped} seeds or runs skipped: "
          f"a body drawn outside the box, or an open box emptied); the largest distance from it {largest:.2g}")
    off_u = 0
    for stages in (3, 8):
        for n in (40, 7):
            result = compare(lambda: unpaired(stages), 20.0, [20.0*(k + 1)/n for k in range(n - 1)] + [20.0], args.hook)
            if result[0]:
                off_u += 1
                print(f"without pairs, s = {stages}, {n} outputs: steps {result[1][0]} (one call) against "
                      f"{result[1][1]}, {result[2]:.2g} apart")
    print(f"without pairs: {off_u} of 4 runs off the single call")


if __name__ == "__main__":
    main()
