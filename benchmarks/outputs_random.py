"""Random runs as users make them, with outputs, against the same run in one
integrate() call (and one call back to 0): do they end on the same bits, in
the same steps? (docs/outputs.md.)

    python -P benchmarks/outputs_random.py                 # 200 runs, about 1 minute
    python -P benchmarks/outputs_random.py --seeds 0:600
    python -P benchmarks/outputs_random.py --seeds 0:150 --gr 30    # with REBOUNDx's "gr" (c = 30)

Each seed draws a scene (a Kepler pair of e up to 0.95 at any inclination,
retrograde included; a binary with a planet or test particle; a planet
and a passing star or test particle; two planets and an eccentric test
particle; a planet and a retrograde crosser), s = 3 ... 8, epsilon 1e-6,
1e-8 or 1e-10, a quarter of them with a drag of 1e-3 v (velocity-dependent),
T = 5, 10 or 20, and 3, 10, 40 or 100 random output times up to T; half of
them come back to 0 through as many random times. A run is off where its
particles' bits or its steps differ from the single calls', or where t
differs by more than REBOUND's own finish tolerance (1e-12 at t = 0).
--gr C adds REBOUNDx's "gr" force (velocity-dependent) with c = C to every
run (needs reboundx).
Printed: each such run, and the count. Against another build: run it with
that build on PYTHONPATH.
"""
import argparse
import math
import random

import rebound

import rebound_pfvi  # noqa: F401  (registers "pfvi")


def drag(simp):
    for i in range(simp.contents.N):
        p = simp.contents.particles[i]
        p.ax -= 1e-3*p.vx
        p.ay -= 1e-3*p.vy


def build(seed, gr=0.0, keep=None):
    rng = random.Random(seed)
    sim = rebound.Simulation()
    kind = rng.choice(["kepler", "binary", "flyby", "planets", "retrograde"])
    sim.add(m=1.0)
    if kind == "kepler":
        sim.add(m=rng.choice([0.0, 1e-3]), a=1.0, e=rng.uniform(0, 0.95), f=rng.uniform(0, 6.28),
                inc=rng.uniform(0, 3.1))
    elif kind == "binary":
        sim.add(m=0.5, a=0.2, e=rng.uniform(0, 0.5))
        sim.add(m=rng.choice([0.0, 1e-4]), a=1.5, e=rng.uniform(0, 0.3), inc=rng.uniform(0, 3.1),
                f=rng.uniform(0, 6.28))
    elif kind == "flyby":
        sim.add(m=1e-3, a=1.0, e=0.1)
        sim.add(m=rng.choice([0.0, 0.3]), x=-15, y=rng.uniform(0.5, 3), vx=rng.uniform(0.8, 2))
    elif kind == "planets":
        sim.add(m=1e-3, a=1.0, e=rng.uniform(0, 0.4))
        sim.add(m=3e-4, a=2.0, e=rng.uniform(0, 0.4), inc=0.1, f=2)
        sim.add(m=0.0, a=rng.uniform(1.2, 3), e=rng.uniform(0.5, 0.9), inc=rng.uniform(0, 3.1))
    else:
        sim.add(m=1e-3, a=1.0, e=0.3)
        sim.add(m=0.0, a=1.3, e=0.6, inc=3.0, f=rng.uniform(0, 6.28))
    sim.move_to_com()
    sim.integrator = "pfvi"
    sim.integrator.stages = rng.choice([3, 4, 5, 6, 7, 8])
    sim.integrator.epsilon = rng.choice([1e-6, 1e-8, 1e-10])
    if rng.random() < 0.25:
        sim.additional_forces = drag
        sim.force_is_velocity_dependent = 1
    if gr:
        import reboundx
        extras = reboundx.Extras(sim)
        force = extras.load_force("gr")
        extras.add_force(force)
        force.params["c"] = gr
        keep.append(extras)   # (REBOUNDx's forces live as long as their Extras)
    return sim, rng, kind


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seeds", default="0:200", help="first:last (exclusive)")
    parser.add_argument("--gr", type=float, default=0.0, help="add REBOUNDx's gr with this speed of light")
    args = parser.parse_args()
    keep = []
    lo, hi = (int(x) for x in args.seeds.split(":"))
    off = 0
    for seed in range(lo, hi):
        many, rng, kind = build(seed, args.gr, keep)
        T = rng.choice([5.0, 10.0, 20.0])
        back = rng.random() < 0.5
        n = rng.choice([3, 10, 40, 100])
        times = sorted(rng.uniform(0, T) for _ in range(n)) + [T]
        if back:
            times += sorted((rng.uniform(0, T) for _ in range(n)), reverse=True) + [0.0]
        one = build(seed, args.gr, keep)[0]
        one.integrate(T)
        if back:
            one.integrate(0.0)
        for t in times:
            many.integrate(t)
        same = (abs(one.t - many.t) <= 1e-12*max(1.0, abs(one.t))
                and all(p.xyz == q.xyz and p.vxyz == q.vxyz for p, q in zip(one.particles, many.particles)))
        steps = (one.integrator.n_steps, many.integrator.n_steps)
        if not same or steps[0] != steps[1]:
            off += 1
            apart = max(math.dist(p.xyz, q.xyz) for p, q in zip(one.particles, many.particles))
            print(f"seed {seed}: {kind}, s = {many.integrator.stages}, epsilon {many.integrator.epsilon:g}, "
                  f"{n} outputs{' and back' if back else ''}, drag {many.force_is_velocity_dependent}: "
                  f"steps {steps[0]} (one call) against {steps[1]}, {apart:.2g} apart")
    print(f"{off} of {hi - lo} runs off the single call")


if __name__ == "__main__":
    main()
