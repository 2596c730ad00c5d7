"""Work at equal error: pfvi, IAS15 and BS on Kepler e = 0.95 (100 orbits,
exact reference) and an Encke-like comet among Venus, Earth, Mars and
Jupiter (20 comet periods, IAS15 reference at epsilon 1e-13), each swept
over its accuracy knob; for each target final relative position error, the
least CPU time any setting of each integrator needs to reach it, and the
ratios. Every run is a child process; the runs of one repeat are
interleaved and the best of --repeats is kept per setting (the machine is
shared: compare ratios within one run).

    python -P benchmarks/equal_error.py [--repeats 3] [--scenes kepler,encke]
                                        [--baseline "PYTHONPATH=... python3"]
                                        [--instructions] [--output docs/equal-error.md]

--baseline adds pfvi as another build runs it (the build before a change),
interleaved with the rest. --instructions also counts the instructions of
each line's fastest run to each target (valgrind's callgrind, inside
REBOUND's step: load-independent), given beside the wall-time ratios.

The error is verdict.relative_position_error: each body's distance from
its reference position relative to particle 0, over its reference
distance from particle 0, the largest over the bodies.
"""
import argparse
import json
import math
import os
import shlex
import subprocess
import sys
import tempfile

TARGETS = (1e-6, 1e-9, 1e-12)
KNOBS = {
    "pfvi": [10.0**(-k / 2) for k in range(8, 30)],      # epsilon 1e-4 ... 3e-15
    "ias15": [10.0**(-k / 2) for k in range(4, 24)],     # epsilon 1e-2 ... 3e-12
    "bs": [10.0**(-k / 2) for k in range(6, 29)],        # epsilon 1e-3 ... 1e-14
}

CHILD = r"""
import json, math, sys, time
sys.path.insert(0, sys.argv[1])
import rebound, rebound_pfvi
from rebound_pfvi import scenes
from rebound_pfvi.verdict import relative_position_error
import outputs
scene_name, integrator, knob, mode = sys.argv[2], sys.argv[3], float(sys.argv[4]), sys.argv[5]
scene = outputs.Encke() if scene_name == "encke" else scenes.make("kepler", e=0.95)
sim = scene.build()
sim.integrator = integrator
if integrator == "bs":
    sim.integrator.eps_abs = knob
    sim.integrator.eps_rel = knob
else:
    sim.integrator.epsilon = knob
if mode == "reference":
    sim.integrate(scene.t_end, exact_finish_time=1)
    print(json.dumps([[p.x, p.y, p.z] for p in sim.particles]))
    sys.exit()
t = time.process_time()
sim.integrate(scene.t_end, exact_finish_time=1)
t = time.process_time() - t
if scene_name == "kepler":
    error = scene.relative_position_error(sim, scene.reference())
else:
    error = relative_position_error([[p.x, p.y, p.z] for p in sim.particles], json.loads(sys.argv[6]))
print(json.dumps({"time": t, "error": error}))
"""


def child(prefix, script, here, scene, integrator, knob, mode="run", extra=()):
    cmd = ["env"] + prefix + ["-P", script, here, scene, integrator, repr(knob), mode] + list(extra)
    out = subprocess.run(cmd, capture_output=True, text=True)
    if out.returncode != 0:
        return None
    return json.loads(out.stdout.strip().splitlines()[-1])


def instructions(prefix, script, here, scene, integrator, knob, extra, workdir):
    real = subprocess.run(["env"] + prefix + ["-c", "import sys; print(sys.executable)"], capture_output=True,
                          text=True, check=True).stdout.strip()
    out = os.path.join(workdir, "cg.out")
    env_words = prefix[:-1]
    subprocess.run(["env"] + env_words + ["valgrind", "--tool=callgrind", f"--callgrind-out-file={out}",
                                          "--collect-atstart=no", "--toggle-collect=reb_simulation_step", real, "-P",
                                          script, here, scene, integrator, repr(knob), "run"] + list(extra),
                   capture_output=True, text=True, check=True)
    with open(out) as f:
        for line in f:
            if line.startswith("summary:") or line.startswith("totals:"):
                return int(line.split()[1])
    return None


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--scenes", default="kepler,encke")
    parser.add_argument("--baseline", default=None)
    parser.add_argument("--instructions", action="store_true")
    parser.add_argument("--output", default=None)
    args = parser.parse_args()
    here = os.path.dirname(os.path.abspath(__file__))
    lines = [f"{'pfvi' if args.baseline is None else 'pfvi (this build)'}", "ias15", "bs"]
    builds = {"pfvi": [sys.executable], "ias15": [sys.executable], "bs": [sys.executable]}
    if args.baseline:
        builds = {"pfvi (this build)": [sys.executable], "pfvi (baseline)": shlex.split(args.baseline),
                  "ias15": [sys.executable], "bs": [sys.executable]}
        lines = list(builds)
    text = []
    with tempfile.TemporaryDirectory() as workdir:
        script = os.path.join(workdir, "child.py")
        with open(script, "w") as f:
            f.write(CHILD)
        for scene in args.scenes.split(","):
            extra = ()
            if scene != "kepler":
                ref = child([sys.executable], script, here, scene, "ias15", 1e-13, mode="reference")
                extra = (json.dumps(ref),)
            best = {}
            for _ in range(args.repeats):
                for line in lines:
                    integrator = "pfvi" if line.startswith("pfvi") else line
                    for knob in KNOBS[integrator]:
                        r = child(builds[line], script, here, scene, integrator, knob, extra=extra)
                        if r is None or not math.isfinite(r["error"]):
                            continue
                        key = (line, knob)
                        old = best.get(key)
                        best[key] = {"time": min(r["time"], old["time"]) if old else r["time"], "error": r["error"]}
            text.append(f"\n### {scene}: least CPU time to a final relative position error\n")
            head = "| target | " + " | ".join(f"{ln}: s (knob)" for ln in lines) + " | pfvi / IAS15 | pfvi / BS |"
            if args.instructions:
                head += " instructions pfvi / IAS15 | pfvi / BS |"
            text.append(head)
            text.append("|" + "---|" * (len(lines) + 3 + (2 if args.instructions else 0)))
            for target in TARGETS:
                cells, times, chosen = [], {}, {}
                for line in lines:
                    ok = [(v["time"], knob) for (ln, knob), v in best.items() if ln == line and v["error"] <= target]
                    if ok:
                        t, knob = min(ok)
                        times[line], chosen[line] = t, knob
                        cells.append(f"{t:.3g} ({knob:.1e})")
                    else:
                        cells.append("not reached")
                first = lines[0]
                ratio = lambda a, b: f"{times[a] / times[b]:.2f}" if a in times and b in times else "-"  # noqa: E731
                row = f"| {target:g} | " + " | ".join(cells) + f" | {ratio(first, 'ias15')} | {ratio(first, 'bs')} |"
                if args.instructions:
                    counts = {}
                    for line in (first, "ias15", "bs"):
                        if line in chosen:
                            integrator = "pfvi" if line.startswith("pfvi") else line
                            counts[line] = instructions(builds[line], script, here, scene, integrator, chosen[line],
                                                        extra, workdir)
                    iratio = lambda a, b: (f"{counts[a] / counts[b]:.2f}"  # noqa: E731
                                           if counts.get(a) and counts.get(b) else "-")
                    row += f" {iratio(first, 'ias15')} | {iratio(first, 'bs')} |"
                text.append(row)
                print(row, file=sys.stderr)
    out = "\n".join(text)
    print(out)
    if args.output:
        with open(args.output, "w") as f:
            f.write(out + "\n")


if __name__ == "__main__":
    main()
