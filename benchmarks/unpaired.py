"""Runs without pairs (no density to track: gravity off, or no massive body):
pfvi against IAS15 and BS on test particles in potentials given by
additional_forces and on a user's own gravity (docs/adaptive.md, "Without
pairs"). Each run's error is its largest position difference from IAS15 at
epsilon 1e-11 after 30 time units; CPU time best of --repeats.

    python -P benchmarks/unpaired.py [--repeats 3] [--workflows] [--stages] [--edges]

--workflows instead runs each scene as users do: epsilon 1e-6, 1e-8 and
1e-10, one integrate() call and 37 outputs (errors against IAS15), a round
trip to 30 and back at 1e-9; and a dense sweep of a test particle in the
Kepler potential at the defaults from REBOUND's first sim.dt (e = 0 ...
0.99 every 0.01, four starting phases and inclinations up to retrograde,
10 outputs over 3 orbits, then back to 0 with sim.dt flipped).

--stages compares each scheme s = 2 ... 8 without pairs and with them: a
test particle 3 orbits from pericentre and from apocentre (e = 0 ... 0.999;
0.99 at s = 2, whose paired runs take millions of steps beyond) in the
Kepler potential from additional_forces and about a massive body, at
epsilon 1e-6, 1e-9 and 1e-12 (1e-6 at s = 2). The error is the distance
from the exact start, in epsilon per orbit (a = 1).

--edges sends one body through a slab that pushes it across its path,
2 (1 - q^2)^p (p = 1, 2, 3) or the C-infinity bump 2 exp(-1/(1 - q^2)), in
12 variants each (width, position and speed a little apart, so that the
steps meet the edges at different places), at s = 4, 5, 6, 8 and epsilon
1e-6, 1e-9, 1e-12 (576 runs, about 3 minutes): how many are refused (the
steps crept onto an edge until t's rounding) and the largest error of the
rest against the exact push.
"""
import argparse
import math
import time

import rebound

import rebound_pfvi  # noqa: F401

T_END = 30.0


def kepler_potential(simp):
    for p in simp.contents.particles:
        r = math.sqrt(p.x * p.x + p.y * p.y + p.z * p.z)
        f = -1.0 / r**3
        p.ax += f * p.x
        p.ay += f * p.y
        p.az += f * p.z


def own_gravity(simp):
    ps, n = simp.contents.particles, simp.contents.N
    for i in range(n):
        for j in range(i + 1, n):
            dx, dy, dz = ps[j].x - ps[i].x, ps[j].y - ps[i].y, ps[j].z - ps[i].z
            r3 = (dx * dx + dy * dy + dz * dz) ** 1.5
            ps[i].ax += ps[j].m * dx / r3
            ps[i].ay += ps[j].m * dy / r3
            ps[i].az += ps[j].m * dz / r3
            ps[j].ax -= ps[i].m * dx / r3
            ps[j].ay -= ps[i].m * dy / r3
            ps[j].az -= ps[i].m * dz / r3


def log_halo(simp):
    for p in simp.contents.particles:
        R2 = p.x * p.x + p.y * p.y + p.z * p.z / 0.64 + 0.01
        p.ax -= p.x / R2
        p.ay -= p.y / R2
        p.az -= p.z / 0.64 / R2


def plummer_drag(simp):
    for p in simp.contents.particles:
        r2 = p.x * p.x + p.y * p.y + p.z * p.z + 0.01
        f = -1.0 / r2**1.5
        p.ax += f * p.x - 0.01 * p.vx
        p.ay += f * p.y - 0.01 * p.vy
        p.az += f * p.z - 0.01 * p.vz


def build(scene):
    sim = rebound.Simulation()
    if scene == "Kepler potential, e = 0.9":
        sim.add(m=1.0)
        sim.add(m=0.0, a=1.0, e=0.9)
        sim.add(m=0.0, a=3.0, e=0.5, omega=1.0, inc=2.5)
        sim.remove(0)
        force = kepler_potential
    elif scene == "own gravity, gravity off":
        sim.add(m=1.0)
        sim.add(m=1e-3, a=1.0, e=0.6)
        sim.add(m=1e-3, a=1.6, e=0.3, inc=0.4, f=2.0)
        sim.move_to_com()
        sim.gravity = "none"
        force = own_gravity
    elif scene == "flattened logarithmic halo":
        sim.add(m=0.0, x=1.0, vy=0.9, vz=0.2)
        sim.add(m=0.0, x=0.2, vy=0.1, vz=0.05)
        sim.add(m=0.0, x=-3.0, vy=-0.3)
        force = log_halo
    else:
        sim.add(m=0.0, x=1.0, vy=0.6)
        sim.add(m=0.0, x=0.05, vy=1.5, vz=0.3)
        sim.force_is_velocity_dependent = 1
        force = plummer_drag
    sim.additional_forces = force
    return sim, force


SCENES = ("Kepler potential, e = 0.9", "own gravity, gravity off", "flattened logarithmic halo",
          "Plummer sphere with drag")
RUNS = (("ias15", None), ("pfvi", None), ("pfvi", 1e-10), ("bs", None))


def run(scene, integrator, epsilon):
    sim, force = build(scene)
    sim.integrator = integrator
    if epsilon is not None:
        sim.integrator.epsilon = epsilon
    start = time.process_time()
    sim.integrate(T_END)
    return sim, time.process_time() - start, force


def off(sim, reference):
    return max(math.dist((p.x, p.y, p.z), (q.x, q.y, q.z)) for p, q in zip(sim.particles, reference.particles))


def pfvi_run(scene, epsilon, outputs):
    sim, force = build(scene)
    sim.integrator = "pfvi"
    sim.integrator.epsilon = epsilon
    for k in range(1, outputs + 1):
        sim.integrate(T_END * k / outputs)
    return sim, force


def workflows():
    print("| scene | epsilon | error, one call | error, 37 outputs | round trip at 1e-9 |")
    print("|---|---|---|---|---|")
    for scene in SCENES:
        reference, _, _ = run(scene, "ias15", 1e-11)
        sim, _ = pfvi_run(scene, 1e-9, 1)
        sim.integrate(0.0)
        back = off(sim, build(scene)[0])
        for epsilon in (1e-6, 1e-8, 1e-10):
            one, _ = pfvi_run(scene, epsilon, 1)
            many, _ = pfvi_run(scene, epsilon, 37)
            print(f"| {scene} | {epsilon:g} | {off(one, reference):.1e} | {off(many, reference):.1e} | {back:.1e} |")
    worst, worst_back, runs = 0.0, 0.0, 0
    for i in range(100):
        e = i / 100.0
        for f, inc in ((0.0, 0.0), (math.pi / 2, 1.0), (math.pi, 2.5), (4.0, math.pi)):
            sims = []
            for integrator in ("ias15", "pfvi"):
                sim = rebound.Simulation()
                sim.add(m=1.0)
                sim.add(m=0.0, a=1.0, e=e, f=f, inc=inc)
                sim.remove(0)
                sim.additional_forces = kepler_potential
                sim.integrator = integrator
                if integrator == "ias15":
                    sim.integrator.epsilon = 1e-11
                for k in range(1, 11):
                    sim.integrate(6 * math.pi * k / 10)
                sims.append(sim)
            reference, sim = sims
            scale = sim.integrator.epsilon_effective * 3   # epsilon_effective a n, 3 orbits
            worst = max(worst, off(sim, reference) / scale)
            begin = rebound.Simulation()
            begin.add(m=1.0)
            begin.add(m=0.0, a=1.0, e=e, f=f, inc=inc)
            begin.remove(0)
            sim.dt = -sim.dt
            sim.integrate(0.0)
            worst_back = max(worst_back, off(sim, begin))
            runs += 1
    print(f"\nDense sweep at the defaults: {runs} runs, largest error {worst:.2g} epsilon_effective a n, "
          f"largest round trip {worst_back:.1e}")


def orbit_from(e, pericentre, paired, s, epsilon):
    q, big_q = 1.0 - e, 1.0 + e
    x, vy = (q, math.sqrt(big_q / q)) if pericentre else (-big_q, -math.sqrt(q / big_q))
    sim = rebound.Simulation()
    if paired:
        sim.add(m=1.0)
    else:
        sim.gravity = "none"
        sim.additional_forces = kepler_potential
    sim.add(m=0.0, x=x, vy=vy)
    sim.integrator = "pfvi"
    sim.integrator.stages = s
    sim.integrator.epsilon = epsilon
    sim.dt = 0.1
    orbits = 3
    sim.integrate(orbits * 2 * math.pi)
    p = sim.particles[-1]
    return math.hypot(p.x - x, p.y, p.z) / (epsilon * orbits), sim.integrator.n_steps


def stages():
    print("| s | epsilon | without pairs: worst (e, start) | e = 0.99 | e = 0.999 | steps "
          "| with a pair: worst | e = 0.99 | e = 0.999 | steps |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for s in range(2, 9):
        eccentricities = (0.0, 0.5, 0.9, 0.99) + ((0.999,) if s > 2 else ())
        for epsilon in ((1e-6,) if s == 2 else (1e-6, 1e-9, 1e-12)):
            cells = []
            for paired in (False, True):
                worst, steps, at = (0.0, ""), 0, {}
                for e in eccentricities:
                    for pericentre in ((True,) if e == 0.0 else (True, False)):
                        ratio, n = orbit_from(e, pericentre, paired, s, epsilon)
                        steps += n
                        at[e] = max(at.get(e, 0.0), ratio)
                        if ratio > worst[0]:
                            worst = (ratio, f"{e}, {'pericentre' if pericentre else 'apocentre'}")
                cells.append(f"{worst[0]:.2g} ({worst[1]}) | {at[0.99]:.2g} | "
                             f"{at[0.999]:.2g} | {steps}" if 0.999 in at else
                             f"{worst[0]:.2g} ({worst[1]}) | {at[0.99]:.2g} | - | {steps}")
            print(f"| {s} | {epsilon:g} | " + " | ".join(cells) + " |", flush=True)


def slab_edge_run(power, stages, epsilon, k):
    """One body through slab variant k; (error against the exact push, steps), or None if refused."""
    width, centre, speed = 0.2 * (1 + 0.013 * k), 10.0 + 0.037 * k, 1.0 + 0.011 * k

    def push(simp):
        for p in simp.contents.particles:
            q = (p.x - centre) / width
            if abs(q) < 1.0:
                p.ay += 2.0 * (math.exp(-1.0 / (1.0 - q * q)) if power is None else (1.0 - q * q) ** power)

    sim = rebound.Simulation()
    sim.gravity = "none"
    sim.add(m=0.0, x=0.0, vx=speed)
    sim.additional_forces = push
    sim.dt = 0.5
    sim.integrator = "pfvi"
    sim.integrator.stages = stages
    sim.integrator.epsilon = epsilon
    try:
        sim.integrate(20.0)
    except RuntimeError:
        return None
    if power is None:
        import numpy as np
        q, w = np.polynomial.legendre.leggauss(200)
        integral = float(sum(wk * math.exp(-1.0 / (1.0 - qk * qk)) for qk, wk in zip(q, w)))
    else:
        integral = {1: 4.0 / 3.0, 2: 16.0 / 15.0, 3: 32.0 / 35.0}[power]   # of (1 - q^2)^p over (-1, 1)
    return abs(sim.particles[0].vy - 2.0 * width * integral / speed), sim.integrator.n_steps


def edges():
    import warnings
    print("| profile | s | epsilon | refused (of 12) | largest error of the rest | steps |")
    print("|---|---|---|---|---|---|")
    refused_all = 0
    for power in (1, 2, 3, None):
        for stages in (4, 5, 6, 8):
            for epsilon in (1e-6, 1e-9, 1e-12):
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    runs = [slab_edge_run(power, stages, epsilon, k) for k in range(12)]
                done = [r for r in runs if r is not None]
                refused_all += len(runs) - len(done)
                name = "bump" if power is None else f"(1 - q^2)^{power}"
                worst = max((r[0] for r in done), default=float("nan"))
                print(f"| {name} | {stages} | {epsilon:g} | {len(runs) - len(done)} | {worst:.1e} | "
                      f"{sum(r[1] for r in done)} |", flush=True)
    print(f"\nRefused: {refused_all} of 576 runs")


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--workflows", action="store_true")
    parser.add_argument("--stages", action="store_true")
    parser.add_argument("--edges", action="store_true")
    args = parser.parse_args(argv)
    if args.edges:
        edges()
        return
    if args.workflows:
        workflows()
        return
    if args.stages:
        stages()
        return
    print("| scene | integrator | epsilon | error | steps | CPU time (ms) |")
    print("|---|---|---|---|---|---|")
    for scene in SCENES:
        reference, _, _ = run(scene, "ias15", 1e-11)
        best = {}
        for _ in range(args.repeats):
            for integrator, epsilon in RUNS:
                sim, seconds, _ = run(scene, integrator, epsilon)
                key = (integrator, epsilon)
                if key not in best or seconds < best[key][1]:
                    best[key] = (sim, seconds)
        for integrator, epsilon in RUNS:
            sim, seconds = best[integrator, epsilon]
            error = max(math.dist((p.x, p.y, p.z), (q.x, q.y, q.z)) for p, q in zip(sim.particles, reference.particles))
            steps = sim.integrator.n_steps if integrator == "pfvi" else sim.steps_done
            shown = "default" if epsilon is None else f"{epsilon:g}"
            print(f"| {scene} | {integrator} | {shown} | {error:.1e} | {steps} | {1e3 * seconds:.0f} |")


if __name__ == "__main__":
    main()
