"""Inclined and retrograde bodies beside Jupiter against IAS15 (issue 40, item 6).

    python -P benchmarks/retrograde_sweep.py                      # s = 8 and 6, epsilon 1e-6 and 1e-10 (480 runs)
    python -P benchmarks/retrograde_sweep.py --stages 2 4 6 8 --epsilon 1e-6 1e-9 1e-12

The Sun, Jupiter (a = 5.203 AU, e = 0.048) and a body (a test particle or
1e-5 Msun) at a = 2 or 3 AU (inside Jupiter's orbit; their conjunctions are
1.5-3 AU apart, no close encounter) or 8 AU (outside), e = 0 or 0.3, at
inclinations 0, pi/4, pi/2, 2.5 and pi, from two phases (f = 0 and 2), over
300 yr. pfvi at the given s and epsilon; the reference is IAS15 at epsilon
1e-11. Per run: the body's and Jupiter's largest position error at the end in
units of epsilon_effective a n (a the body's semi-major axis, n its orbits
over the run); the step control's goal is at most 10 (docs/step-control.md).
Prints, per s and epsilon, the worst run, how many exceed the goal, the steps
and the steps not time-symmetric.
"""
import argparse
import math
from concurrent.futures import ProcessPoolExecutor

T = 300.0
INCLINATIONS = (0.0, math.pi / 4, math.pi / 2, 2.5, math.pi)
PHASES = (0.0, 2.0)
AXES = (2.0, 3.0, 8.0)
ECCENTRICITIES = (0.0, 0.3)
MASSES = (0.0, 1e-5)


def build(inc, m, a, e, f):
    import rebound

    import rebound_pfvi  # noqa: F401  (registers "pfvi")
    sim = rebound.Simulation()
    sim.units = ("AU", "yr", "Msun")
    sim.add(m=1.0)
    sim.add(m=9.55e-4, a=5.203, e=0.048, f=1.0, inc=0.02)
    sim.add(m=m, a=a, e=e, f=f, inc=inc, Omega=0.5, omega=0.5)
    sim.move_to_com()
    return sim


def reference(task):
    inc, m, a, e, f = task
    ref = build(inc, m, a, e, f)
    ref.integrator = "ias15"
    ref.integrator.epsilon = 1e-11
    ref.integrate(T)
    return [p.xyz for p in ref.particles]


def run(task):
    (inc, m, a, e, f), s, eps, ref = task
    sim = build(inc, m, a, e, f)
    sim.integrator = "pfvi"
    sim.integrator.stages = s
    sim.integrator.epsilon = eps
    sim.integrate(T)
    error = max(math.dist(p.xyz, q) for p, q in zip(sim.particles[1:], ref[1:]))
    orbits = T / math.sqrt(a**3 / (1.0 + m))
    goal = error / (sim.integrator.epsilon_effective * a * orbits)
    return (inc, m, a, e, f), s, eps, goal, int(sim.integrator.n_steps), int(sim.integrator.n_asymmetric)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--stages", type=int, nargs="+", default=[8, 6])
    parser.add_argument("--epsilon", type=float, nargs="+", default=[1e-6, 1e-10])
    args = parser.parse_args(argv)
    systems = [(inc, m, a, e, f) for inc in INCLINATIONS for m in MASSES for a in AXES
               for e in ECCENTRICITIES for f in PHASES]
    with ProcessPoolExecutor(2) as pool:
        refs = list(pool.map(reference, systems, chunksize=4))
        tasks = [(sys_, s, eps, ref) for s in args.stages for eps in args.epsilon for sys_, ref in zip(systems, refs)]
        rows = list(pool.map(run, tasks, chunksize=4))
    print("| s | epsilon | runs | worst (epsilon a n) | where (inc, m, a, e, f) | over 10 | steps | not time-symmetric |")
    print("|---|---|---|---|---|---|---|---|")
    for s in args.stages:
        for eps in args.epsilon:
            part = [r for r in rows if r[1] == s and r[2] == eps]
            worst = max(part, key=lambda r: r[3])
            inc, m, a, e, f = worst[0]
            print(f"| {s} | {eps:g} | {len(part)} | {worst[3]:.3g} | {inc:.2f}, {m:g}, {a:g}, {e:g}, {f:g} | "
                  f"{sum(1 for r in part if r[3] > 10)} | {sum(r[4] for r in part)} | {sum(r[5] for r in part)} |")


if __name__ == "__main__":
    main()
