"""Cost per step of the fixed-step check (issue 36, item 4): wall time per
fixed step with this build against a build without the check, interleaved
in one run (each repeat runs both, in their own processes, so that both see
the same load), on well-resolved fixed steps, where every step pays the
check and none warns.

    python -P benchmarks/fixed_step_check.py --baseline PYTHON_OF_A_BUILD_WITHOUT_IT

(a build without the check: e.g. `git archive a7bd4da | tar -x -C /tmp/base`
and a venv with `pip install /tmp/base`.)
"""
import argparse
import statistics
import subprocess
import sys

CASE = r"""
import math, sys, time, rebound, rebound_pfvi
s, n_bodies, steps = int(sys.argv[1]), int(sys.argv[2]), int(sys.argv[3])
sim = rebound.Simulation()
sim.add(m=1.0)
for k in range(n_bodies - 1):
    sim.add(m=1e-5, a=1.0 + 0.3 * k, e=0.05, theta=k)
sim.move_to_com()
sim.integrator = "pfvi"
sim.integrator.epsilon = 0.0
sim.integrator.stages = s
sim.dt = 2 * math.pi / 100
t0 = time.perf_counter()
sim.steps(steps)
print((time.perf_counter() - t0) / steps)
"""


def per_step(python, s, n, steps):
    out = subprocess.run([python, "-P", "-c", CASE, str(s), str(n), str(steps)], check=True,
                         capture_output=True, text=True).stdout
    return float(out)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--baseline", required=True, help="python of a build without the check")
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()
    print("| s | N | steps | with the check [us/step] | without [us/step] | ratio |")
    print("|---|---|---|---|---|---|")
    for s, n, steps in [(2, 2, 200000), (2, 50, 4000), (8, 2, 20000), (8, 50, 400)]:
        new, old = [], []
        for _ in range(args.repeats):
            new.append(per_step(sys.executable, s, n, steps))
            old.append(per_step(args.baseline, s, n, steps))
        a, b = statistics.median(new), statistics.median(old)
        print(f"| {s} | {n} | {steps} | {a * 1e6:.3g} | {b * 1e6:.3g} | {a / b:.3f} |")


if __name__ == "__main__":
    main()
