"""What a new simulation costs before its steps: `sim.integrator = name`
and the first call's first step, for pfvi, IAS15 and BS (and pfvi of
another build, --baseline), in child processes taking turns.

    python -P benchmarks/setup_cost.py [--baseline "PYTHONPATH=<other build> python3"] [--rounds 5]

Each child makes 2000 simulations (Sun, Jupiter and a massless comet of
e = 0.9, the Jupiter-family comet page's), then times, per simulation:
  integrator   sim.integrator = name (the state's creation);
  first step   sim.integrate(t) to a t inside the first step (a new
               simulation's first call: the scratch, the stage rule, the
               time scales, one step);
  a step       the same simulation's sim.steps(100), per step, for scale.
Printed: the least over --rounds of each, in microseconds.
"""
import argparse
import shlex
import subprocess
import sys

CHILD = r"""
import sys, time
import rebound, rebound_pfvi
name, n = sys.argv[1], 2000

def build():
    sim = rebound.Simulation()
    sim.add(m=1.0)
    sim.add(m=9.547919e-4, a=5.2026, e=0.0485, M=3.5)
    sim.add(m=0.0, a=3.0, e=0.9, inc=0.087, M=3.14159)
    sim.move_to_com()
    return sim

sims = [build() for _ in range(n)]
tick = time.perf_counter()
for sim in sims:
    sim.integrator = name
create = (time.perf_counter() - tick)/n
tick = time.perf_counter()
for sim in sims:
    sim.integrate(1e-6)
first = (time.perf_counter() - tick)/n
sim = sims[0]
tick = time.perf_counter()
sim.steps(100)
step = (time.perf_counter() - tick)/100
print("RESULT", create*1e6, first*1e6, step*1e6)
"""


def child(command, name):
    out = subprocess.run(shlex.split(command) + ["-P", "-c", CHILD, name], capture_output=True, text=True)
    for line in out.stdout.splitlines():
        if line.startswith("RESULT"):
            return [float(x) for x in line.split()[1:]]
    raise RuntimeError(f"{command} {name}: {out.stderr[-2000:]}")


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--baseline", default="")
    parser.add_argument("--rounds", type=int, default=5)
    args = parser.parse_args()
    runs = [("pfvi", sys.executable, "pfvi")]
    if args.baseline:
        runs.append(("pfvi (baseline)", args.baseline, "pfvi"))
    runs += [("ias15", sys.executable, "ias15"), ("bs", sys.executable, "bs")]
    best = {label: [float("inf")] * 3 for label, _, _ in runs}
    for _ in range(args.rounds):
        for label, command, name in runs:
            best[label] = [min(a, b) for a, b in zip(best[label], child(command, name))]
    print("| integrator | sim.integrator = ... (us) | first call, one step (us) | a step after (us) |")
    print("|---|---|---|---|")
    for label, _, _ in runs:
        create, first, step = best[label]
        print(f"| {label} | {create:.2f} | {first:.2f} | {step:.2f} |")


if __name__ == "__main__":
    main()
