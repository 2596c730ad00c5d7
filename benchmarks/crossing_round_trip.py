"""Round trips on crossing orbits (issue 40, item 7).

    python -P benchmarks/crossing_round_trip.py      # 16 runs, about 20 s on 2 cores

The Sun, Jupiter, Saturn and a massless comet (e = 0.8, inclination 0.1)
crossing Jupiter's orbit: a = 4 AU from f = 0 and 2, a = 3.5 from f = 1, a =
6 from f = 3. pfvi at epsilon 1e-6 (the default), 1e-8, 1e-10 and 1e-12:
integrate(200 yr), then integrate(0). Per run: the largest distance of any
body from its start (AU), the steps not time-symmetric on the way out
(n_asymmetric) and in all, and on the way out what made them: retakes (the
resolution check, the density jump, the stage solve), lambda falling back
after a retake, the track's drift correction, the steady hold's jumps.
"""
import math
from concurrent.futures import ProcessPoolExecutor

COMETS = ((4.0, 0.0), (4.0, 2.0), (3.5, 1.0), (6.0, 3.0))
EPSILONS = (1e-6, 1e-8, 1e-10, 1e-12)
T = 200.0


def build(a, f):
    import rebound

    import rebound_pfvi  # noqa: F401  (registers "pfvi")
    sim = rebound.Simulation()
    sim.units = ("AU", "yr", "Msun")
    sim.add(m=1.0)
    sim.add(m=9.547919e-4, a=5.2026, e=0.0485, inc=0.0228)
    sim.add(m=2.858e-4, a=9.5549, e=0.0555, inc=0.0434, f=2.0)
    sim.add(m=0.0, a=a, e=0.8, f=f, inc=0.1, Omega=1.0)
    sim.move_to_com()
    return sim


def causes(a, f, eps):
    """What made the way out's asymmetric steps, one step at a time."""
    sim = build(a, f)
    sim.integrator = "pfvi"
    sim.integrator.epsilon = eps
    counts = {"retake": 0, "lambda falls back": 0, "drift correction": 0, "hold": 0}
    while sim.t < T:
        i = sim.integrator
        before = (i.n_asymmetric, i.n_rejected, i.density_scale, i.steady_hold)
        sim.steps(1)
        if i.n_asymmetric > before[0]:
            if i.n_rejected > before[1]:
                counts["retake"] += 1
            elif i.density_scale < before[2]:
                counts["lambda falls back"] += 1
            elif i.steady_hold != before[3]:
                counts["hold"] += 1
            else:
                counts["drift correction"] += 1
    return counts


def run(task):
    a, f, eps = task
    sim = build(a, f)
    sim.integrator = "pfvi"
    sim.integrator.epsilon = eps
    start = [p.xyz for p in sim.particles]
    sim.integrate(T)
    out = int(sim.integrator.n_asymmetric)
    sim.integrate(0.0)
    miss = max(math.dist(s, p.xyz) for s, p in zip(start, sim.particles))
    return a, f, eps, miss, out, int(sim.integrator.n_asymmetric), causes(a, f, eps)


def main():
    tasks = [(a, f, eps) for eps in EPSILONS for a, f in COMETS]
    with ProcessPoolExecutor(2) as pool:
        rows = list(pool.map(run, tasks))
    print("| comet (a, f) | epsilon | back at the start (AU) | not time-symmetric: out, in all | out: retakes, lambda back, drift, hold |")
    print("|---|---|---|---|---|")
    for a, f, eps, miss, out, total, c in rows:
        print(f"| {a:g}, {f:g} | {eps:g} | {miss:.2g} | {out}, {total} | {c['retake']}, {c['lambda falls back']}, "
              f"{c['drift correction']}, {c['hold']} |")


if __name__ == "__main__":
    main()
