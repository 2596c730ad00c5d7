"""Kepler pairs whose orbit takes a whole number of the track's steps: the
error over 100 orbits against the exact two-body solution, beside its
neighbours in e (docs/step-control.md, "Steps per orbit near a whole
number"). A hostile trial found it (2026-11-27).

    python -P benchmarks/commensurate_steps.py            # the table of cases
    python -P benchmarks/commensurate_steps.py --sweep    # e = 0.1 ... 0.95, 8 phases

--sweep runs e = 0.10 ... 0.95 every 0.01 from 8 starting mean anomalies at
epsilon 1e-6 (the default), 1e-7, 3e-8, 1e-8, 1e-9 and 1e-10 (4128 runs,
about 30 s), and gives per epsilon the error per orbit in units of epsilon
a (largest, 99th percentile, median, runs above 1 and 3.4) and the mean
steps per orbit. Run it with another build's PYTHONPATH to compare.
"""
import argparse
import math

import rebound

import rebound_pfvi  # noqa: F401

ORBITS = 100.37
CASES = ((1e-6, (0.70, 0.71, 0.715, 0.717, 0.72, 0.73)), (1e-8, (0.80, 0.81, 0.82)),
         (1.19e-7, (0.60, 0.61, 0.62)), (1e-10, (0.72, 0.73, 0.74)))


def pair(e, M=4.0):
    sim = rebound.Simulation()
    sim.add(m=1.0)
    sim.add(m=1e-3, a=1.0, e=e, M=M)
    sim.move_to_com()
    return sim


def relative(sim):
    p = sim.particles
    return (p[1].x - p[0].x, p[1].y - p[0].y, p[1].z - p[0].z)


def exact(e, t):
    o = pair(e).particles[1].orbit(primary=pair(e).particles[0])
    sim = rebound.Simulation()
    sim.add(m=1.0)
    sim.add(m=1e-3, a=o.a, e=o.e, omega=o.omega, M=o.M + o.n * t)
    return relative(sim), o.P


SWEEP_EPSILONS = (1e-6, 1e-7, 3e-8, 1e-8, 1e-9, 1e-10)


def sweep():
    print("| epsilon | runs | largest | 99th percentile | median | above 1 | above 3.4 | steps per orbit |")
    print("|---|---|---|---|---|---|---|---|")
    for epsilon in SWEEP_EPSILONS:
        errors, steps = [], 0.0
        for k in range(10, 96):
            e = k / 100
            for j in range(8):
                sim = pair(e, M=2 * math.pi * j / 8)
                orbit = sim.particles[1].orbit(primary=sim.particles[0])
                t_end = ORBITS * orbit.P
                reference = rebound.Simulation()
                reference.add(m=1.0)
                reference.add(m=1e-3, a=orbit.a, e=orbit.e, omega=orbit.omega, M=orbit.M + orbit.n * t_end)
                sim.integrator = "pfvi"
                sim.integrator.epsilon = epsilon
                sim.integrate(t_end)
                errors.append(math.dist(relative(sim), relative(reference)) / (epsilon * ORBITS))
                steps += sim.integrator.n_steps / ORBITS
        errors.sort()
        n = len(errors)
        print(f"| {epsilon:.0e} | {n} | {errors[-1]:.3g} | {errors[int(0.99 * n)]:.3g} | {errors[n // 2]:.3g} | "
              f"{sum(x > 1 for x in errors)} | {sum(x > 3.4 for x in errors)} | {steps / n:.3f} |")


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--sweep", action="store_true")
    if parser.parse_args().sweep:
        sweep()
        return
    print("| epsilon | e | steps per orbit | error (epsilon_effective a n) | error (epsilon a n) | IAS15 (1e-11) |")
    print("|---|---|---|---|---|---|")
    for epsilon, es in CASES:
        for e in es:
            period = exact(e, 0.0)[1]
            t_end = ORBITS * period
            reference = exact(e, t_end)[0]
            sim = pair(e)
            sim.integrator = "pfvi"
            sim.integrator.epsilon = epsilon
            sim.integrate(t_end)
            error = math.dist(relative(sim), reference)
            ias15 = pair(e)
            ias15.integrator = "ias15"
            ias15.integrator.epsilon = 1e-11
            ias15.integrate(t_end)
            scale = sim.integrator.epsilon_effective * ORBITS
            print(f"| {epsilon:.3g} | {e:.3g} | {sim.integrator.n_steps / ORBITS:.3f} | {error / scale:.2g} | "
                  f"{error / (epsilon * ORBITS):.2g} | {math.dist(relative(ias15), reference):.1e} |")


if __name__ == "__main__":
    main()
