"""Instructions per run of pfvi on the pages' scenes, at several epsilons,
for this build and another (callgrind inside REBOUND's step, as
benchmarks/step_budget.py counts: load-independent). Where a change moves
the rounds per step but not the steps, the ratio of the runs' instructions
is the change's cost or gain at equal error.

    python -P benchmarks/scene_instructions.py [--scenes kepler,comet,...] [--epsilons 1e-6,1e-9,1e-12]
        [--baseline "PYTHONPATH=<another build> python3"]

Prints, per scene and epsilon: instructions (millions), steps and force
evaluations per step of each build, and the ratio this build / baseline,
with the geometric mean of the ratios (docs/performance.md: the early stop
tried and dropped on 2026-11-27). Needs valgrind. About 3 minutes a
build for the default eight scenes on one core.
"""
import argparse
import math
import os
import shlex
import subprocess
import sys
import tempfile

SCENES = "kepler,comet,triple,jupiter-comet,outer-solar-system,circumbinary,sungrazer,retrograde"

CHILD = r"""
import sys
import rebound, rebound_pfvi
from rebound_pfvi import scenes
scene = scenes.make(sys.argv[1])
sim = scene.build()
sim.integrator = "pfvi"
sim.integrator.epsilon = float(sys.argv[2])
sim.integrate(scene.t_end, exact_finish_time=1)
print("RUN", sim.integrator.n_steps, sim.integrator.n_force_evaluations)
"""


def count(prefix, scene, epsilon, workdir):
    real = subprocess.run(["env"] + prefix + ["-c", "import sys; print(sys.executable)"], capture_output=True,
                          text=True, check=True).stdout.strip()
    out = os.path.join(workdir, "cg.out")
    done = subprocess.run(["env"] + prefix[:-1] + ["valgrind", "--tool=callgrind", f"--callgrind-out-file={out}",
                                                   "--collect-atstart=no", "--toggle-collect=reb_simulation_step",
                                                   real, "-P", "-c", CHILD, scene, repr(epsilon)],
                          capture_output=True, text=True, check=True)
    steps, evaluations = (int(x) for x in done.stdout.split("RUN")[1].split())
    with open(out) as f:
        for line in f:
            if line.startswith("summary:") or line.startswith("totals:"):
                return int(line.split()[1]), steps, evaluations
    raise RuntimeError("no totals in callgrind's output")


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--scenes", default=SCENES)
    parser.add_argument("--epsilons", default="1e-6,1e-9,1e-12")
    parser.add_argument("--baseline", default=None, help="a command prefix running another build of pfvi")
    args = parser.parse_args()
    builds = [[sys.executable]] + ([shlex.split(args.baseline)] if args.baseline else [])
    header = "| scene | epsilon | this build: M instructions, steps, evaluations/step |"
    if args.baseline:
        header += " baseline | ratio |"
    print(header)
    print("|---|---|---|" + ("---|---|" if args.baseline else ""))
    logs = []
    with tempfile.TemporaryDirectory() as workdir:
        for scene in args.scenes.split(","):
            for epsilon in (float(x) for x in args.epsilons.split(",")):
                rows = [count(prefix, scene, epsilon, workdir) for prefix in builds]
                cells = [f"{n / 1e6:.3f}, {steps}, {ev / steps:.1f}" for n, steps, ev in rows]
                line = f"| {scene} | {epsilon:g} | " + " | ".join(cells) + " |"
                if args.baseline:
                    ratio = rows[0][0] / rows[1][0]
                    logs.append(math.log(ratio))
                    line += f" {ratio:.3f} |"
                print(line, flush=True)
    if logs:
        print(f"\ngeometric mean of the ratios: {math.exp(sum(logs) / len(logs)):.3f}")


if __name__ == "__main__":
    main()
