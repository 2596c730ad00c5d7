"""Is the round-off biased? Ensembles of Kepler pairs whose semi-major axes
differ by k 2^-40 (far below what the truncation error feels, far enough
apart that their round-off is independent), relative energy error at 10
times (no step shortened to reach them); for each case the ensemble mean's
largest excursion over the 10 samples in standard errors, signed (unbiased
round-off stays within about 2-3 of zero), the spread at the end, and the
force evaluations per step. A stop rule that keeps the same small error
in every step biases the energy (docs/roundoff.md); the circular case
("circ") is the one that showed it for the early stop tried on 2026-11-27
(docs/performance.md, "Tried and dropped: the stage solve's early stop"),
which the eccentric cases did not.

    python -P benchmarks/roundoff_bias.py [--cases fix201,fix50,...] [--members 8]
        [--set a=0.7,per_orbit=50] [--baseline "PYTHONPATH=<another build> python3"]
        [--integrator ias15|whfast]

Each case runs in a child process of the interpreter given (default: this
one), so --baseline puts another build's column beside this one's. About 5
minutes for the first seven cases on one core (the default: all eleven).
"""
import argparse
import json
import math
import shlex
import subprocess
import sys

CASES = {
    "fix201": ("fixed steps P/201, e = 0.5", dict(e=0.5, orbits=1000, per_orbit=201)),
    "fix50": ("fixed steps P/50, e = 0.5", dict(e=0.5, orbits=1000, per_orbit=50)),
    "s4e12": ("s = 4, epsilon 1e-12, e = 0.9", dict(e=0.9, orbits=1000, stages=4, epsilon=1e-12)),
    "s5e10": ("s = 5, epsilon 1e-10, e = 0.9", dict(e=0.9, orbits=1000, stages=5, epsilon=1e-10)),
    "s6e11": ("s = 6, epsilon 1e-11, e = 0.9", dict(e=0.9, orbits=1000, stages=6, epsilon=1e-11)),
    "e99": ("s = 8, epsilon 1e-12, e = 0.99", dict(e=0.99, orbits=1000, stages=8, epsilon=1e-12)),
    "circ": ("s = 8, epsilon 1e-11, e = 0, 10^4 orbits, 16 members at phases 0.3 k",
             dict(e=0.0, orbits=10000, stages=8, epsilon=1e-11, members=16)),
    "circ-long": ("s = 8, epsilon 1e-11, e = 0, 3*10^4 orbits, 16 members at phases 0.3 k",
                  dict(e=0.0, orbits=30000, stages=8, epsilon=1e-11, members=16)),
    "circ-fixed": ("fixed steps P/25, e = 0, 3*10^4 orbits, 16 members at phases 0.3 k",
                   dict(e=0.0, orbits=30000, per_orbit=25, members=16)),
    "circ-fixed-s6": ("as circ-fixed at s = 6",
                      dict(e=0.0, orbits=30000, per_orbit=25, members=16, stages=6)),
    "circ-fixed-m6": ("as circ-fixed with m = 1e-6",
                      dict(e=0.0, orbits=30000, per_orbit=25, members=16, m=1e-6)),
}

CHILD = r"""
import json, math, sys
import rebound, rebound_pfvi
case = json.loads(sys.argv[1])
members = case.get("members", int(sys.argv[2]))
integrator = sys.argv[3]
runs, evaluations, steps = [], 0, 0
for k in range(members):
    sim = rebound.Simulation()
    sim.add(m=1.0)
    # (on a circular orbit each member starts at its own phase too: from one
    # phase the members' roundings stay alike and the mean's standard error
    # comes out too small)
    sim.add(m=case.get("m", 1e-3), a=case.get("a", 1.0) * (1.0 + k * 2.0**-40), e=case["e"],
            f=(0.3 * k if case["e"] == 0.0 else 0.0))
    sim.move_to_com()
    sim.integrator = integrator
    period, energy0 = sim.particles[1].P, sim.energy()
    if integrator == "whfast":
        sim.dt = period / case.get("per_orbit", 25)
    elif integrator != "pfvi":
        pass   # (IAS15 and the like at their defaults)
    elif "per_orbit" in case:
        sim.integrator.epsilon = 0.0
        sim.integrator.stages = case.get("stages", 8)
        sim.dt = period / case["per_orbit"]
    else:
        sim.integrator.stages = case["stages"]
        sim.integrator.epsilon = case["epsilon"]
    errors = []
    for j in range(1, 11):
        sim.integrate(case["orbits"] * period * j / 10, exact_finish_time=0)
        errors.append(sim.energy() / energy0 - 1.0)
    runs.append(errors)
    steps += sim.integrator.n_steps if integrator == "pfvi" else sim.steps_done
    evaluations += sim.integrator.n_force_evaluations if integrator == "pfvi" else 0
means = [sum(r[j] for r in runs) / members for j in range(10)]
spreads = [math.sqrt(sum((r[j] - means[j])**2 for r in runs) / (members - 1)) for j in range(10)]
# (signed: the sample farthest from zero in standard errors)
bias = max((m / (sd / math.sqrt(members)) for m, sd in zip(means, spreads)), key=abs)
print(json.dumps({"bias": bias, "spread": spreads[-1], "evaluations": evaluations / steps}))
"""


def run(prefix, case, members, integrator):
    out = subprocess.run(["env"] + prefix + ["-P", "-c", CHILD, json.dumps(case), str(members), integrator],
                         capture_output=True, text=True, check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--cases", default=",".join(CASES))
    parser.add_argument("--members", type=int, default=8, help="members of each ensemble (circ: 16)")
    parser.add_argument("--baseline", default=None, help="a command prefix running another build of pfvi")
    parser.add_argument("--set", default="", metavar="KEY=VALUE,...",
                        help="override every case's parameters, e.g. a=0.7,per_orbit=50 (m, a, e, orbits, "
                             "per_orbit, stages, epsilon, members)")
    parser.add_argument("--integrator", default="pfvi",
                        help="pfvi (default), or REBOUND's ias15 (its defaults) or whfast (P/25) for comparison")
    args = parser.parse_args()
    builds = [("this build", [sys.executable])]
    if args.baseline:
        builds.append(("baseline", shlex.split(args.baseline)))
    print("| run | " + " | ".join(f"{name}: bias (SE), spread, evaluations/step" for name, _ in builds) + " |")
    print("|---|" + "---|" * len(builds))
    for key in args.cases.split(","):
        label, case = CASES[key]
        if args.set:
            case = dict(case)
            for item in args.set.split(","):
                name, value = item.split("=")
                case[name] = int(value) if name in ("members", "stages") else float(value)
            label += f" ({args.set})"
        cells = []
        for _, prefix in builds:
            r = run(prefix, case, args.members, args.integrator)
            cells.append(f"{r['bias']:.1f}, {r['spread']:.1e}, {r['evaluations']:.1f}")
        print(f"| {label} | " + " | ".join(cells) + " |", flush=True)


if __name__ == "__main__":
    main()
