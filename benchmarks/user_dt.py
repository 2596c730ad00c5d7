"""A sim.dt the user sets by hand (docs/outputs.md): does it cap exactly the
next step, whatever the output times, and do copies, loads and archives
judge it as the run they copy?

    python -P benchmarks/user_dt.py [--seeds 0:200] [--baseline "PYTHONPATH=<other build> python3"]   # about 5 s

Systems (G = 1): two planets of 1e-3 (a = 1, e = 0.3; a = 1.7, e = 0.1);
Kepler e = 0.6; a planet with a retrograde test particle (N_active = 2);
a binary (0.5, a = 0.2, e = 0.5) with a planet at a = 1.5.
  cap once        integrate(1), sim.dt = u (0.01, 0.1, 0.3: below, at and
                  above the output spacing), then outputs every 0.1 to t = 4
                  against one call to 4: runs off (bits or step count)
  copy or load    random call sequences (integrate to times inside and on
                  steps, steps(n), sim.dt edits, backwards times), a copy
                  and a save/load at a random point, then the same edit and
                  calls on all three: runs whose copy or load ends off
  archive         sim.dt = u at an output, save_to_file(interval), outputs;
                  every snapshot restarted through the outputs still to
                  come: snapshots off
  dense e sweep   e = 0, 0.01, ..., 0.99 from pericentre, apocentre and
                  f = 2, with an outer planet and a retrograde test
                  particle; outputs every 0.37 to t = 20, epsilon set to
                  1e-7 at t = 5 and sim.dt to 0.05 at t = 10, at the
                  defaults otherwise: runs off the same run with calls
                  only at the edits, and the largest error of any body
                  against IAS15 (epsilon 1e-12) over a n (a its orbit's
                  size, n its orbits, at least 1)
Each line: this build, then --baseline's (child processes).
"""
import argparse
import json
import shlex
import subprocess
import sys

CHILD = r"""
import json, math, os, random, sys, tempfile
import numpy as np
import rebound
import rebound_pfvi  # noqa: F401

def two_planets():
    sim = rebound.Simulation()
    sim.add(m=1.0); sim.add(m=1e-3, a=1.0, e=0.3); sim.add(m=1e-3, a=1.7, e=0.1)
    return sim

def kepler():
    sim = rebound.Simulation()
    sim.add(m=1.0); sim.add(m=1e-3, a=1.0, e=0.6)
    return sim

def retrograde_test_particle():
    sim = rebound.Simulation()
    sim.add(m=1.0); sim.add(m=1e-3, a=1.0, e=0.05); sim.add(m=0.0, a=1.4, e=0.4, inc=math.pi - 0.2)
    sim.N_active = 2
    return sim

def binary_planet():
    sim = rebound.Simulation()
    sim.add(m=1.0); sim.add(m=0.5, a=0.2, e=0.5); sim.add(m=1e-4, a=1.5, e=0.05)
    return sim

SYSTEMS = {"two planets": two_planets, "Kepler e = 0.6": kepler, "retrograde test particle": retrograde_test_particle,
           "binary with a planet": binary_planet}

def build(name):
    sim = SYSTEMS[name]()
    sim.move_to_com()
    sim.integrator = "pfvi"
    return sim

def state(sim):
    return (sim.t, np.array([[p.x, p.y, p.z, p.vx, p.vy, p.vz] for p in sim.particles]).tobytes())

lo, hi = json.loads(sys.argv[1])
rows = {}
for name in SYSTEMS:
    off = n = 0
    for u in (0.01, 0.1, 0.3):
        runs = []
        for times in ([4.0], [1.0 + 0.1*k for k in range(1, 31)]):
            sim = build(name)
            sim.integrate(1.0)
            sim.dt = u
            for t in times:
                sim.integrate(t)
            runs.append((state(sim), sim.integrator.n_steps))
        n += 1
        off += runs[0] != runs[1]
    rows[f"cap once: {name}"] = [n, off, "runs off"]

def sequence(rng):
    ops, t = [], 0.0
    for _ in range(rng.randint(3, 9)):
        r = rng.random()
        if r < 0.25:
            ops.append(("dt", rng.choice([0.01, 0.05, 0.1, 0.3, -0.1, rng.uniform(1e-3, 0.5)])))
        elif r < 0.4:
            ops.append(("steps", rng.randint(1, 3)))
        else:
            t += rng.choice([rng.uniform(0.001, 0.05), rng.uniform(0.05, 1.0)])*(-1 if rng.random() < 0.1 else 1)
            ops.append(("integrate", t))
    return ops

def apply(sim, op):
    if op[0] == "dt":
        sim.dt = op[1]
    elif op[0] == "steps":
        sim.steps(op[1])
    else:
        sim.integrate(op[1])

off = n = 0
folder = tempfile.mkdtemp()
for seed in range(lo, hi):
    rng = random.Random(seed)
    name = list(SYSTEMS)[seed % len(SYSTEMS)]
    ops = sequence(rng)
    k = rng.randint(1, len(ops))
    sim = build(name)
    for op in ops[:k]:
        apply(sim, op)
    copy = sim.copy()
    path = os.path.join(folder, f"{seed}.bin")
    sim.save_to_file(path, delete_file=True)
    loaded = rebound.Simulation(path)
    later = [("dt", rng.choice([0.01, 0.1, 0.3, -0.05]))] + ops[k:] + [("integrate", 5.0)]
    ends = []
    for s in (sim, copy, loaded):
        for op in later:
            apply(s, op)
        ends.append(state(s))
    n += 1
    off += not (ends[0] == ends[1] == ends[2])
rows["copy or load"] = [n, off, "runs off"]

off = n = 0
for name in SYSTEMS:
    for u in (0.01, 0.29):
        path = os.path.join(folder, "archive.bin")
        sim = build(name)
        sim.integrate(1.0)
        sim.integrate(1.5)
        sim.dt = u
        sim.save_to_file(path, interval=0.37, delete_file=True)
        times = [1.5 + 0.3*k for k in range(1, 12)]
        for t in times:
            sim.integrate(t)
        end = state(sim)
        archive = rebound.Simulationarchive(path)
        for j in range(len(archive)):
            again = archive[j]
            for t in times:
                if t > again.t:
                    again.integrate(t)
            n += 1
            off += state(again) != end
rows["archive"] = [n, off, "snapshots off"]

# The way users run it, densely: e every 0.01 from pericentre, apocentre and
# f = 2 (with an outer planet and a retrograde test particle), outputs every
# 0.37 to t = 20, epsilon set to 1e-7 at t = 5 and sim.dt to 0.05 at t = 10.
def swept(e, f, integrator):
    sim = rebound.Simulation()
    sim.add(m=1.0); sim.add(m=1e-3, a=1.0, e=e, f=f); sim.add(m=1e-3, a=3.0, e=0.05, f=1.0)
    sim.add(m=0.0, a=1.8, e=0.3, inc=math.pi - 0.3, f=2.0)
    sim.N_active = 3
    sim.move_to_com()
    sim.integrator = integrator
    return sim

def edited_run(e, f, times):
    sim = swept(e, f, "pfvi")
    for t in times:
        sim.integrate(t)
        if t == 5.0:
            sim.integrator.epsilon = 1e-7
        if t == 10.0:
            sim.dt = 0.05
    return sim

outputs = sorted(set([0.37*k for k in range(1, 55)] + [5.0, 10.0, 20.0]))
off = n = 0
worst = 0.0
for e in np.round(np.arange(0.0, 1.0, 0.01), 2):
    for f in (0.0, math.pi, 2.0):
        many, few = edited_run(e, f, outputs), edited_run(e, f, [5.0, 10.0, 20.0])
        n += 1
        off += (state(many), many.integrator.n_steps) != (state(few), few.integrator.n_steps)
        ref = swept(e, f, "ias15")
        ref.integrator.epsilon = 1e-12
        ref.integrate(20.0)
        for i, a in ((1, 1.0), (2, 3.0), (3, 1.8)):
            orbits = max(1.0, 20.0/(2*math.pi*a**1.5))
            worst = max(worst, math.dist(many.particles[i].xyz, ref.particles[i].xyz)/(a*orbits))
rows["dense e sweep, edits at outputs"] = [n, off, "runs off"]
rows["  its largest error against IAS15 / (a n)"] = [None, f"{worst:.1e}", ""]
print(json.dumps(rows))
"""


def measure(command, seeds):
    out = subprocess.run(shlex.split(command) + ["-P", "-c", CHILD, json.dumps(seeds)], capture_output=True,
                         text=True, check=False)
    if out.returncode != 0:
        raise SystemExit(f"{command}: failed\n{out.stderr[-2000:]}")
    return json.loads(out.stdout.strip().splitlines()[-1])


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seeds", default="0:200", help="first:last (exclusive) of the copy-or-load sequences")
    parser.add_argument("--baseline", help='another build, e.g. "PYTHONPATH=/path/to/build python3"')
    args = parser.parse_args(argv)
    seeds = [int(x) for x in args.seeds.split(":")]
    builds = [("this build", sys.executable)] + ([("baseline", f"env {args.baseline}")] if args.baseline else [])
    results = [(label, measure(command, seeds)) for label, command in builds]
    print("| case | " + " | ".join(label for label, _ in results) + " |")
    print("|---|" + "---|"*len(results))
    for case in results[0][1]:
        cells = [f"{r[case][1]} of {r[case][0]} {r[case][2]}" if r[case][0] is not None else r[case][1]
                 for _, r in results]
        print(f"| {case} | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    main()
