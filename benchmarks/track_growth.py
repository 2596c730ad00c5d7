"""How far the varying step track carries a small difference (docs/solve.md,
"What breaks those reversals"): two runs of the compact five-planet system
(stability.compact_planets) whose second planet's x differs by 1e-13
(relative), stepped one step at a time; the relative difference of their
grid times t_n at steps 50, half-way and the last, its growth per step from
step 50 on, the asymmetric steps and whether the track was held at the end.
IAS15's two states over the same time are given first, for the dynamics'
own part.

    python -P benchmarks/track_growth.py [--kappas 0.8,0.9,1.0] [--steps 400]

kappa is set through epsilon = C_8 kappa^14 (s = 8). The installed build caps
kappa at PFVI_KAPPA_MAX (pfvi.h, 1.0): for kappa above it, run this under a
build with a higher cap; for the track without the steady hold, under one
with PFVI_STEADY_WINDOW raised beyond the run's steps (both debug builds,
PYTHONPATH=<build> python3 -P benchmarks/track_growth.py).
"""
import argparse
import math

import rebound_pfvi  # noqa: F401  (registers "pfvi")
from rebound_pfvi import stability

C_8 = 1.2e-7   # PFVI_SYMMETRIC_CONSTANTS[8]
SHIFT = 1e-13


def grid(kappa, steps, shift):
    sim = stability.compact_planets()
    sim.particles[1].x *= 1.0 + shift
    sim.integrator = "pfvi"
    sim.integrator.epsilon = C_8 * kappa ** 14
    times = []
    for _ in range(steps):
        sim.steps(1)
        times.append(sim.t)
    return times, int(sim.integrator.n_asymmetric), int(sim.integrator.steady_hold), float(sim.integrator.epsilon_effective)


def ias15_divergence(t_end):
    a, b = stability.compact_planets(), stability.compact_planets()
    b.particles[1].x *= 1.0 + SHIFT
    for sim in (a, b):
        sim.integrator = "ias15"
        sim.integrate(t_end)
    scale = max(math.dist(p.xyz, a.particles[0].xyz) for p in a.particles[1:])
    return max(math.dist(p.xyz, q.xyz) for p, q in zip(a.particles, b.particles)) / scale


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--kappas", default="0.8,0.9,1.0")
    parser.add_argument("--steps", type=int, default=400)
    args = parser.parse_args(argv)
    steps = args.steps
    for kappa in (float(k) for k in args.kappas.split(",")):
        (a, asymmetric, held, used), (b, asymmetric2, _, _) = grid(kappa, steps, 0.0), grid(kappa, steps, SHIFT)
        if kappa == float(args.kappas.split(",")[0]):
            print(f"IAS15, the same shift: states {ias15_divergence(a[-1]):.1e} apart (relative) at t = {a[-1]:.3g}")
        d = [abs(x - y) / abs(x) for x, y in zip(a, b)]
        growth = (max(d[-1], 1e-300) / max(d[49], 1e-300)) ** (1.0 / (steps - 50))
        print(f"kappa {kappa:.3f} (epsilon_effective {used:.2g}): |t_n - t_n'|/t_n at step 50 {d[49]:.1e}, "
              f"{steps // 2} {d[steps // 2 - 1]:.1e}, {steps} {d[-1]:.1e}; growth per step {growth:.4f}; "
              f"asymmetric steps {asymmetric}/{asymmetric2}; held at the end {held}")


if __name__ == "__main__":
    main()
