"""Adaptive steps (seed section 4): long-term energy, monotonicity, reversibility.

    python -P benchmarks/adaptive.py longterm [--e 0.95] [--orbits 10000] [--epsilon 1e-6] [--stages 2] [--frame seed|com]
    python -P benchmarks/adaptive.py monotone [--e 0.9]
    python -P benchmarks/adaptive.py roundtrip [--e 0.9] [--orbits 10] [--epsilon 1e-8]
    python -P benchmarks/adaptive.py retrace [--e 0.9] [--steps 400] [--epsilon 1e-6]
    python -P benchmarks/adaptive.py order
    python -P benchmarks/adaptive.py local [--u 0.05]
    python -P benchmarks/adaptive.py defaults [--orbits 1000]
    python -P benchmarks/adaptive.py symmetric [--long 100000]

`symmetric`: the symmetric step control (the default) on m = 1e-3 about
m = 1 in the COM frame: steps per orbit against epsilon for s = 2, 4, 6 at
e = 0.95 (slope against the predicted 1/(2s - 2)); the largest relative
position error per orbit over 5 orbits against epsilon for e = 0 ... 0.99;
the largest energy error in the first and last tenth over 2000 orbits at
e = 0.95 and over --long periods of the seed's problem at e = 0.95 (Figure
2's run at the default settings), both sampled 10 times per orbit (the
energy error oscillates within an orbit, and the phase drifts: sampled once
per period, the sample slides along that oscillation and looks like a
drift); forward and back over 10 orbits at e = 0.9.

Two bodies, a = 1, G = 1, from pericentre: the seed's problem (a massless body
about a unit mass at rest) or m = 1e-3 about m = 1 in the COM frame.
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
from rebound_pfvi.integrators import configure as configure_integrator


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
    configure_integrator(sim, "pfvi", epsilon=epsilon, step_control=step_control, fitting=fitting, stages=stages)


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
            sim.integrate(0.9 * orbits * period, exact_finish_time=0)  # ends within one step
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
    it = sim.integrator
    return abs(energy(sim) / E0 - 1), it.n_steps, it.n_attempts / it.n_steps, it.n_asymmetric


def monotone(e):
    print(f"e = {e}, one orbit: final relative energy error against epsilon")
    print("| step_control | fitting | stages | " + " | ".join(f"{10.0**-k:.0e}" for k in range(4, 12)) + " |")
    print("|---" * 11 + "|")
    costs = []
    for step_control in ("seed", "reversible"):
        for fitting in ("phase", "none"):
            for stages in (2, 4):
                runs = [energy_error_after(e, 1, 10.0**-k, step_control, fitting, stages) for k in range(4, 12)]
                label = f"| {step_control} | {fitting} | {stages} | "
                print(label + " | ".join(f"{run[0]:.1e}" for run in runs) + " |")
                costs.append(label + " | ".join(f"{run[2]:.2f} ({run[3]})" for run in runs) + " |")
    print("\ntrial steps per step (n_asymmetric), same runs")
    print("| step_control | fitting | stages | " + " | ".join(f"{10.0**-k:.0e}" for k in range(4, 12)) + " |")
    print("|---" * 11 + "|")
    print("\n".join(costs))


def roundtrip(e, orbits, epsilon):
    """Forward `orbits` periods and back to t = 0 with exact_finish_time (the
    protocol of tests/test_adaptive.py), COM frame, both controllers."""
    print(f"e = {e}, COM frame, {orbits} orbits forward and back to t = 0, epsilon = {epsilon:g}")
    print("| step_control | stages | fitting | steps forward | largest position error at t = 0 |")
    print("|---|---|---|---|---|")
    for step_control in ("seed", "reversible"):
        for stages in (2, 4):
            for fitting in ("phase", "none"):
                sim = pair(e, "com")
                configure(sim, epsilon, step_control, fitting, stages)
                start = [(p.x, p.y, p.z) for p in sim.particles]
                sim.integrate(orbits * sim.particles[1].P)
                steps = sim.integrator.n_steps
                sim.integrate(0.0)
                err = max(math.dist(a, (p.x, p.y, p.z)) for a, p in zip(start, sim.particles))
                print(f"| {step_control} | {stages} | {fitting} | {steps} | {err:.1e} |")


def retrace(e, steps, epsilon):
    """Where the backward steps of 'reversible' stop retracing the forward ones:
    `steps` steps forward from f = 2, then as many back, step by step."""
    sim = rebound.Simulation()
    sim.add(m=1.0)
    sim.add(m=1e-3, a=1.0, e=e, f=2.0)
    sim.move_to_com()
    configure(sim, epsilon, "reversible", "none", 2)
    sim.dt = sim.particles[1].P
    forward, times = [], []
    for _ in range(steps):
        times.append(sim.t)
        sim.steps(1)
        forward.append(sim.dt_last_done)
    sim.dt = -sim.dt
    backward = []
    for _ in range(steps):
        sim.steps(1)
        backward.append(-sim.dt_last_done)
    backward.reverse()
    print(f"e = {e}, epsilon = {epsilon:g}, fitting none, s = 2: relative difference of the backward "
          "step from the forward step it should retrace")
    print("| step | t | forward step | relative difference |")
    print("|---|---|---|---|")
    for k in range(0, steps, max(1, steps // 40)):
        print(f"| {k} | {times[k]:.4f} | {forward[k]:.6e} | {(backward[k] - forward[k]) / forward[k]:.1e} |")
    print(f"back at t = {sim.t:.3e} (0 if every step were retraced)")


def order():
    """Order in h of the osculating-circle estimate: one step of h, h/2, ... from
    several points of the orbit (fitting none, epsilon large so it is accepted)."""
    print("| e | mean anomaly | estimate for h = 1e-2 ... 6.25e-4 | slopes (log2 of successive ratios) |")
    print("|---|---|---|---|")
    for e in (0.5, 0.9):
        for M in (0.0, 0.02, 0.3, math.pi):
            row = []
            for h in (1e-2, 5e-3, 2.5e-3, 1.25e-3, 6.25e-4):
                sim = rebound.Simulation()
                sim.add(m=1.0)
                sim.add(m=0.0, a=1.0, e=e, M=M)
                configure(sim, 1e10, "seed", "none", 2)
                sim.integrator.u_max = 1.5
                sim.dt = h
                sim.steps(1)
                row.append(sim.integrator.error_estimate)
            slopes = [math.log2(a / b) if b > 0 else math.nan for a, b in zip(row, row[1:])]
            print(f"| {e} | {M:.3g} | " + ", ".join(f"{x:.2e}" for x in row) + " | "
                  + ", ".join(f"{x:.2f}" for x in slopes) + " |")


def defaults(orbits):
    """Default settings (only stages varied), m = 1e-3 about m = 1, COM frame."""
    print(f"| e | stages | outcome | steps/orbit | trial steps/step | energy error | wall [s] | star's distance from the COM |")
    print("|---|---|---|---|---|---|---|---|")
    for e in (0.0, 0.5, 0.9):
        for stages in (2, 4):
            sim = pair(e, "com")
            E0 = sim.energy()
            configure_integrator(sim, "pfvi", stages=stages)
            tick = time.perf_counter()
            try:
                sim.integrate(orbits * sim.particles[1].P)
                outcome = "finished"
            except RuntimeError as error:
                outcome = f"refused at t = {sim.t:.0f}: {str(error)[:40]}..."
            wall = time.perf_counter() - tick
            it = sim.integrator
            star = math.hypot(sim.particles[0].x, sim.particles[0].y)
            print(f"| {e} | {stages} | {outcome} | {it.n_steps / orbits:.0f} | {it.n_attempts / it.n_steps:.2f} |"
                  f" {abs(sim.energy() / E0 - 1):.1e} | {wall:.2f} | {star:.2e} |")


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


def symmetric(long_periods):
    from rebound_pfvi.scenes import Kepler

    def kepler(e, s, epsilon, orbits):
        scene = Kepler(e=e, periods=orbits)
        sim = scene.build()
        configure_integrator(sim, "pfvi", dt=scene.period / 10, stages=s, epsilon=epsilon)
        return scene, sim

    print("Steps per orbit, e = 0.95 (2 orbits), and their slope against 1/(2s - 2):\n")
    epsilons = [10.0**-k for k in range(4, 13, 2)]
    print("| s | " + " | ".join(f"{x:.0e}" for x in epsilons) + " | slope | predicted |")
    print("|---|" + "---|" * (len(epsilons) + 2))
    for s in (2, 4, 6, 8):
        counts = []
        for x in epsilons:
            scene, sim = kepler(0.95, s, x, 2)
            if s == 2 and x < 1e-8:
                counts.append(None)
                continue
            sim.integrate(scene.t_end, exact_finish_time=0)
            counts.append(sim.integrator.n_steps / 2)
        known = [(x, n) for x, n in zip(epsilons, counts) if n]
        slope = math.log(known[-1][1] / known[0][1]) / math.log(known[0][0] / known[-1][0])
        print(f"| {s} | " + " | ".join(f"{n:.0f}" if n else "-" for n in counts)
              + f" | {slope:.3f} | {1 / (2 * s - 2):.3f} |")
    print("\nLargest relative position error per orbit over 5 orbits, in units of epsilon:\n")
    eccentricities = (0.0, 0.3, 0.5, 0.7, 0.9, 0.95, 0.99)
    print("| s | epsilon | " + " | ".join(f"e = {e:g}" for e in eccentricities) + " |")
    print("|---|---|" + "---|" * len(eccentricities))
    for s, x in ((2, 1e-5), (3, 1e-7), (4, 1e-8), (5, 1e-9), (6, 1e-10), (7, 1e-10), (8, 1e-10)):
        cells = []
        for e in eccentricities:
            scene, sim = kepler(e, s, x, 5)
            reference = scene.reference()
            worst = 0.0
            for k in range(1, 21):
                sim.integrate(k * scene.period / 4, exact_finish_time=0)
                worst = max(worst, scene.position_error(sim, reference))
            cells.append(f"{worst / scene.a / 5 / x:.2g}")
        print(f"| {s} | {x:.0e} | " + " | ".join(cells) + " |")
    print("\nLong-term energy at the default settings (symmetric steps, s = 8, epsilon 1e-6), e = 0.95:\n")
    print("| run | steps/orbit | max energy error, first tenth | last tenth | last/first | seconds |")
    print("|---|---|---|---|---|---|")
    for label, frame, orbits, samples in (("m = 1e-3, COM frame, 2000 orbits", "com", 2000, 10),
                                          (f"seed's problem, {long_periods} periods", "seed", long_periods, 10)):
        sim = pair(0.95, frame)
        sim.integrator = "pfvi"
        period = sim.particles[1].P
        sim.dt = period / 100
        E0 = energy(sim)
        errors = []
        start = time.perf_counter()
        for k in range(1, orbits * samples + 1):
            sim.integrate(k * period / samples, exact_finish_time=0)
            errors.append(abs(energy(sim) / E0 - 1))
        tenth = len(errors) // 10
        first, last = max(errors[:tenth]), max(errors[-tenth:])
        print(f"| {label} | {sim.integrator.n_steps / orbits:.0f} | {first:.2e} | {last:.2e} | {last / first:.2f} |"
              f" {time.perf_counter() - start:.0f} |")
    print("\nForward 10 orbits at e = 0.9, then as many steps back: largest difference from the start:\n")
    print("| s | epsilon | steps | difference |")
    print("|---|---|---|---|")
    for s, x in ((4, 1e-8), (6, 1e-10), (8, 1e-10)):
        scene, sim = kepler(0.9, s, x, 10)
        start_state = [(p.x, p.y, p.vx, p.vy) for p in sim.particles]
        sim.integrate(scene.t_end, exact_finish_time=0)
        n = sim.integrator.n_steps
        sim.dt = -sim.dt
        sim.steps(n)
        diff = max(abs(a - b) for p, q in zip(sim.particles, start_state) for a, b in zip((p.x, p.y, p.vx, p.vy), q))
        print(f"| {s} | {x:.0e} | {n} | {diff:.1e} |")


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
    p.add_argument("--epsilon", type=float, default=1e-8)
    p = sub.add_parser("retrace")
    p.add_argument("--e", type=float, default=0.9)
    p.add_argument("--steps", type=int, default=400)
    p.add_argument("--epsilon", type=float, default=1e-6)
    sub.add_parser("order")
    p = sub.add_parser("defaults")
    p.add_argument("--orbits", type=int, default=1000)
    p = sub.add_parser("symmetric")
    p.add_argument("--long", type=int, default=100000)
    args = parser.parse_args(argv)
    if args.command == "longterm":
        longterm(args.e, args.orbits, args.epsilon, args.stages, args.frame)
    elif args.command == "local":
        local(args.u)
    elif args.command == "monotone":
        monotone(args.e)
    elif args.command == "roundtrip":
        roundtrip(args.e, args.orbits, args.epsilon)
    elif args.command == "retrace":
        retrace(args.e, args.steps, args.epsilon)
    elif args.command == "order":
        order()
    elif args.command == "symmetric":
        symmetric(args.long)
    else:
        defaults(args.orbits)


if __name__ == "__main__":
    main()
