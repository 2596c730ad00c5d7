"""Adaptive steps (seed section 4): long-term energy, monotonicity, reversibility.

    python -P benchmarks/adaptive.py longterm [--e 0.95] [--orbits 10000] [--epsilon 1e-6] [--stages 2]
    python -P benchmarks/adaptive.py monotone [--e 0.9]
    python -P benchmarks/adaptive.py roundtrip [--e 0.9] [--orbits 10]

Two bodies (m = 1 and 1e-3, a = 1, COM frame, starting at pericentre), G = 1.
`longterm` integrates both step controls and both fittings and reports the
largest relative energy error over the first and over the last tenth of the
run, checked after every step. Wall times are single runs on a shared machine: compare them within
one run only.
"""
import argparse
import math
import time

import rebound

import rebound_pfvi  # noqa: F401  (registers "pfvi")


def pair(e, frame="seed"):
    """The seed's problem (frame 'seed'): a massless body about a unit mass at
    rest, G = 1. Frame 'com': m = 1e-3 about m = 1 in the centre-of-mass frame."""
    sim = rebound.Simulation()
    sim.add(m=1.0)
    sim.add(m=0.0 if frame == "seed" else 1e-3, a=1.0, e=e)
    if frame == "com":
        sim.move_to_com()
    return sim


def energy(sim):
    """Total energy, or the orbiter's specific energy if it is massless."""
    if sim.particles[1].m > 0:
        return sim.energy()
    d = sim.particles[1] - sim.particles[0]
    return 0.5 * (d.vx**2 + d.vy**2 + d.vz**2) - sim.G * sim.particles[0].m / math.sqrt(d.x**2 + d.y**2 + d.z**2)


def configure(sim, epsilon, step_control, fitting, stages):
    sim.integrator = "pfvi"
    sim.integrator.epsilon = epsilon
    sim.integrator.step_control = step_control
    sim.integrator.fitting = fitting
    sim.integrator.stages = stages


def longterm(e, orbits, epsilon, stages, frame):
    print(f"e = {e}, frame {frame}, {orbits} orbits, epsilon = {epsilon:g}, stages = {stages}")
    print("| step_control | fitting | steps/orbit | trial steps/step | max energy error, first tenth |"
          " last tenth | ratio last/first | wall [s] |")
    print("|---|---|---|---|---|---|---|---|")
    rows = []
    for step_control in ("seed", "reversible"):
        for fitting in ("phase", "none"):
            sim = pair(e, frame)
            period = sim.particles[1].P
            E0 = energy(sim)
            configure(sim, epsilon, step_control, fitting, stages)
            first = last = 0.0
            tick = time.perf_counter()
            # Every step is checked: the error peaks at pericentre, which lasts
            # about (1 - e)^1.5 of a period.
            while sim.t < 0.1 * orbits * period:
                sim.steps(1)
                first = max(first, abs(energy(sim) / E0 - 1))
            while sim.t < 0.9 * orbits * period:
                sim.steps(100)
            while sim.t < orbits * period:
                sim.steps(1)
                last = max(last, abs(energy(sim) / E0 - 1))
            wall = time.perf_counter() - tick
            it = sim.integrator
            row = dict(step_control=step_control, fitting=fitting, steps_per_orbit=it.n_steps / orbits,
                       attempts=it.n_attempts / it.n_steps, first=first, last=last, wall=wall)
            rows.append(row)
            print(f"| {step_control} | {fitting} | {row['steps_per_orbit']:.0f} | {row['attempts']:.2f} |"
                  f" {first:.2e} | {last:.2e} | {last / first:.1f} | {wall:.1f} |", flush=True)
    return rows


def energy_error_after(e, orbits, epsilon, step_control="seed", fitting="phase", stages=2):
    sim = pair(e)
    period = sim.particles[1].P
    E0 = energy(sim)
    configure(sim, epsilon, step_control, fitting, stages)
    sim.integrate(orbits * period)
    return abs(energy(sim) / E0 - 1), sim.integrator.n_steps


def monotone(e):
    print(f"e = {e}, one orbit: final relative energy error against epsilon")
    print("| step_control | fitting | stages | " + " | ".join(f"{10.0**-k:.0e}" for k in range(4, 12)) + " |")
    print("|---" * 11 + "|")
    for step_control in ("seed", "reversible"):
        for fitting in ("phase", "none"):
            for stages in (2, 4):
                errs = [energy_error_after(e, 1, 10.0**-k, step_control, fitting, stages)[0] for k in range(4, 12)]
                print(f"| {step_control} | {fitting} | {stages} | " + " | ".join(f"{x:.1e}" for x in errs) + " |")


def roundtrip(e, orbits):
    print(f"e = {e}, {orbits} orbits forward, then back to the first step point (reversible, exact_finish_time = 0)")
    print("| fitting | stages | epsilon | steps | position error after the round trip | relative energy error |")
    print("|---|---|---|---|---|---|")
    for fitting in ("phase", "none"):
        for stages in (2, 4):
            for epsilon in (1e-6, 1e-9):
                sim = pair(e)
                period = sim.particles[1].P
                configure(sim, epsilon, "reversible", fitting, stages)
                sim.dt = period  # the cap; the step equation chooses
                start = [(p.x, p.y, p.z) for p in sim.particles]
                E0 = energy(sim)
                sim.integrate(orbits * period, exact_finish_time=0)
                first = sim.integrator.dt_reversible if False else None
                steps = sim.integrator.n_steps
                sim.dt = -sim.dt
                sim.integrate(0.0, exact_finish_time=0)
                back = [(p.x, p.y, p.z) for p in sim.particles]
                err = max(math.dist(a, b) for a, b in zip(start, back))
                print(f"| {fitting} | {stages} | {epsilon:g} | {steps} | {err:.1e} | {abs(energy(sim) / E0 - 1):.1e} | t = {sim.t:.3g}")


def local(u):
    """Why fitting gains less as e grows: the one-step position error at
    pericentre, fitted vs classical, and the share of the force that the
    harmonic model -omega^2 q explains there."""
    print(f"one step from pericentre with u = omega h = {u} (seed problem), error against IAS15 (epsilon 1e-12)")
    print("| e | position error, phase | none | ratio phase/none | omega^2 r / |a| at pericentre |")
    print("|---|---|---|---|---|")
    for e in (0.0, 0.5, 0.9, 0.95, 0.99):
        ref = pair(e)
        ref.integrator = "ias15"
        ref.integrator.epsilon = 1e-12
        p = ref.particles[1]
        r = math.hypot(p.x, p.y)
        a = ref.particles[0].m / r**2
        omega = math.hypot(p.vx, p.vy) / (r * (1 + e))  # v / R, R = r_p (1 + e) at pericentre
        h = u / omega
        ref.integrate(h)
        errors = {}
        for fitting in ("phase", "none"):
            sim = pair(e)
            configure(sim, 0.0, "seed", fitting, 2)
            sim.dt = h
            sim.integrate(h)
            errors[fitting] = math.hypot(sim.particles[1].x - ref.particles[1].x, sim.particles[1].y - ref.particles[1].y)
        print(f"| {e} | {errors['phase']:.2e} | {errors['none']:.2e} | {errors['phase'] / errors['none']:.3f} |"
              f" {omega**2 * r / a:.3f} |")


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = parser.add_subparsers(dest="command", required=True)
    p = sub.add_parser("longterm")
    p.add_argument("--e", type=float, default=0.95)
    p.add_argument("--orbits", type=int, default=10000)
    p.add_argument("--epsilon", type=float, default=1e-6)
    p.add_argument("--stages", type=int, default=2)
    p.add_argument("--frame", choices=("seed", "com"), default="seed")
    p = sub.add_parser("monotone")
    p.add_argument("--e", type=float, default=0.9)
    p = sub.add_parser("local")
    p.add_argument("--u", type=float, default=0.05)
    p = sub.add_parser("roundtrip")
    p.add_argument("--e", type=float, default=0.9)
    p.add_argument("--orbits", type=int, default=10)
    args = parser.parse_args(argv)
    if args.command == "longterm":
        longterm(args.e, args.orbits, args.epsilon, args.stages, args.frame)
    elif args.command == "local":
        local(args.u)
    elif args.command == "monotone":
        monotone(args.e)
    else:
        roundtrip(args.e, args.orbits)


if __name__ == "__main__":
    main()
