"""The steady track (docs/step-control.md) over a dense grid of three-body
systems at pfvi's defaults: the Sun, Jupiter (a = 5.203 AU, e = 0.048) and an
inner body at a = 1 AU (an Earth-mass planet, or a test particle) with e =
0 ... 0.30 every 0.01 from four starting phases (pericentre, apocentre, f =
2 and 4), 300 yr each.

    python -P benchmarks/steady_sweep.py        # 248 runs, about 30 s on 2 cores

Per run: the largest position error against IAS15 at epsilon 1e-11 in units
of epsilon_effective a n t (the inner orbit's; the step control's goal is at
most 10), the steps not time-symmetric, whether the track is held after 1500
steps, and a flip there (sim.dt = -sim.dt, 1500 steps back): how far from
t = 0 (relative) and from the start (AU) it ends.
"""
import math
from concurrent.futures import ProcessPoolExecutor

PHASES = (0.0, math.pi, 2.0, 4.0)


def build(e, f, m):
    import rebound

    import rebound_pfvi  # noqa: F401  (registers "pfvi")
    sim = rebound.Simulation()
    sim.units = ("AU", "yr", "Msun")
    sim.add(m=1.0)
    sim.add(m=m, a=1.0, e=e, f=f)
    sim.add(m=9.55e-4, a=5.203, e=0.048, f=1.0, inc=0.02)
    sim.move_to_com()
    return sim


def run(task, T=300.0, flip_steps=1500):
    e, f, m = task
    ref = build(e, f, m)
    ref.integrator = "ias15"
    ref.integrator.epsilon = 1e-11
    ref.integrate(T)
    sim = build(e, f, m)
    sim.integrator = "pfvi"
    sim.integrate(T)
    error = max(math.dist(a.xyz, b.xyz) for a, b in zip(sim.particles, ref.particles))
    goal = error / (sim.integrator.epsilon_effective * 2.0 * math.pi * T)
    flip = build(e, f, m)
    flip.integrator = "pfvi"
    start = [p.xyz for p in flip.particles]
    flip.steps(flip_steps)
    t_turn, held = flip.t, int(flip.integrator.steady_hold)
    flip.dt = -flip.dt
    flip.steps(flip_steps)
    miss = max(math.dist(a, p.xyz) for a, p in zip(start, flip.particles))
    return e, f, m, goal, int(sim.integrator.n_asymmetric), held, abs(flip.t) / t_turn, miss


def main():
    tasks = [(round(0.01 * k, 2), f, m) for k in range(31) for f in PHASES for m in (3e-6, 0.0)]
    with ProcessPoolExecutor(2) as pool:
        rows = list(pool.map(run, tasks, chunksize=4))
    worst = max(rows, key=lambda r: r[3])
    print(f"runs: {len(rows)}; worst error: {worst[3]:.3g} epsilon a n t (e = {worst[0]}, f = {worst[1]:.2f}, "
          f"m = {worst[2]:g})")
    print(f"held at the flip: {sum(r[5] for r in rows)}; most steps not time-symmetric: {max(r[4] for r in rows)}")
    print(f"flips off t = 0 by more than 1e-10 or the start by more than 1e-8 AU: "
          f"{sum(1 for r in rows if r[6] > 1e-10 or r[7] > 1e-8)}; "
          f"largest: {max(r[6] for r in rows):.2g} in t, {max(r[7] for r in rows):.2g} AU")


if __name__ == "__main__":
    main()
