"""Outputs exactly on the run's step ends, and the sim.dt REBOUND restores
after integrate() there (docs/outputs.md): how many runs a requested time on
a step end changes, against the same run in one call, and whether a sim.dt
the user sets still caps the next step.

    python -P benchmarks/step_end_outputs.py [--baseline "PYTHONPATH=<other build> python3"]   # about 1 s

Kepler e = 0.5 and 0.9 (m = 1e-3, G = 1); step ends read with sim.steps(1):
  one output      integrate(E_k), integrate(T) for 40 step ends E_k: runs off
  two, then in    integrate(E_k), integrate(E_k+1), a time 0.1 into the next
                  step, integrate(T): runs off
  copy            integrate(E_k), sim.copy(), integrate(E_k+1), integrate(T)
  archive         save_to_file(step=1), integrate(E_k); the snapshot at E_k-1
                  restarted with integrate(E_k), integrate(T)
  user dt         sim.dt = 0.01 before each of 40 integrate() to times inside
                  steps: calls whose first step is capped (heartbeat; rebound
                  5.2.2 and later)
  steps after     steps(1), integrate(E_k), steps(3) against steps(k + 4)
Each line: this build, then --baseline's (child processes).
"""
import argparse
import json
import shlex
import subprocess
import sys

CHILD = r"""
import json, os, sys, tempfile
import numpy as np
import rebound
import rebound_pfvi  # noqa: F401

def kepler(e, eps):
    sim = rebound.Simulation()
    sim.add(m=1.0)
    sim.add(m=1e-3, a=1.0, e=e)
    sim.move_to_com()
    sim.integrator = "pfvi"
    sim.integrator.epsilon = eps
    return sim

def state(sim):
    return np.array([[p.x, p.y, p.z, p.vx, p.vy, p.vz] for p in sim.particles]).tobytes()

def ends_of(build, T):
    sim, ends = build(), []
    while sim.t < T:
        sim.steps(1)
        ends.append(sim.t)
    return ends[:-1]

def run(build, times):
    sim = build()
    for t in times:
        sim.integrate(t)
    return sim

out = {}
for e, eps, T in ((0.5, 1e-7, 30.0), (0.9, 1e-6, 30.0)):
    build = lambda: kepler(e, eps)
    ends = ends_of(build, T)
    one = state(run(build, [T]))
    ks = np.linspace(1, len(ends) - 3, 40).astype(int)
    rows = {}
    rows["one output"] = len(ks), sum(state(run(build, [ends[k], T])) != one for k in ks)
    rows["two, then in"] = len(ks), sum(state(run(build, [ends[k], ends[k + 1], ends[k + 1] + 0.1*(ends[k + 2] - ends[k + 1]), T])) != one
                               for k in ks)
    off = 0
    for k in ks:
        sim = run(build, [ends[k]])
        c = sim.copy()
        c.integrate(ends[k + 1])
        c.integrate(T)
        off += state(c) != one
    rows["copy"] = len(ks), off
    off = n = 0
    d = tempfile.mkdtemp()
    for k in ks[::4]:
        path = os.path.join(d, f"{k}.bin")
        sim = build()
        sim.save_to_file(path, step=1)
        sim.integrate(ends[k])
        sim.integrate(T)
        archive = rebound.Simulationarchive(path)
        for i in range(len(archive)):
            snap = archive[i]
            if snap.t == ends[k - 1]:
                snap.integrate(ends[k])
                snap.integrate(T)
                off += state(snap) != state(sim)
                n += 1
    rows["archive"] = n, off
    try:
        sim = build()
        capped = 0
        for j in range(1, 41):
            times = []
            sim.dt = 0.01
            sim.heartbeat = lambda p: times.append(p.contents.t)
            t0 = sim.t
            sim.integrate(0.37*j)
            sim.heartbeat = 0
            capped += abs(times[1] - t0) <= 0.01*(1 + 1e-12)
        rows["user dt"] = 40, capped
    except AttributeError:
        rows["user dt"] = 40, None   # rebound before 5.2.2 cannot set a heartbeat from Python
    off = 0
    for k in ks:
        a = build()
        a.steps(1)
        a.integrate(ends[k])
        a.steps(3)
        b = build()
        b.steps(int(k) + 4)
        off += state(a) != state(b)
    rows["steps after"] = len(ks), off
    out[f"e = {e}, epsilon {eps:g}"] = {key: (int(n), None if v is None else int(v)) for key, (n, v) in rows.items()}
print(json.dumps(out))
"""




def measure(prefix):
    words = shlex.split(prefix) if prefix else [sys.executable]
    run = subprocess.run(["env"] + words + ["-P", "-c", CHILD], capture_output=True, text=True)
    if run.returncode != 0:
        raise SystemExit(f"child failed: {run.stderr[-2000:]}")
    return json.loads(run.stdout)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--baseline", default=None, help="a command prefix running another build")
    args = parser.parse_args(argv)
    mine = measure(None)
    other = measure(args.baseline) if args.baseline else None
    print("| case | scene | this build | baseline |" if other else "| case | scene | this build |")
    print("|---|---|---|---|" if other else "|---|---|---|")
    def cell(case, entry):
        total, value = entry
        return "-" if value is None else f"{value} of {total} {'capped' if case == 'user dt' else 'off'}"
    for scene, rows in mine.items():
        for case, entry in rows.items():
            tail = f" {cell(case, other[scene][case])} |" if other else ""
            print(f"| {case} | {scene} | {cell(case, entry)} |{tail}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
