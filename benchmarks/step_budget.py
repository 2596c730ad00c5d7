"""Where a step goes, in instructions: pfvi, IAS15 and BS on the same systems,
counted by valgrind's callgrind inside REBOUND's step (load-independent), by
category.

    python -P benchmarks/step_budget.py [--sizes 2,3,11,101,1001] [--integrators pfvi,ias15,bs]
                                        [--baseline "PYTHONPATH=... python3"] [--output docs/step-budget.md]
    python -P benchmarks/step_budget.py --phases [--sizes 2,3,11]
    python -P benchmarks/step_budget.py --megno [--sizes 2,3,11] [--integrators pfvi,ias15] [--wall R ...]

Each (system, integrator) runs in a child process under
`valgrind --tool=callgrind --collect-atstart=no --toggle-collect=reb_simulation_step`,
which counts every instruction executed inside REBOUND's step (the
integrator, REBOUND's gravity, libm, REBOUND's bookkeeping) and nothing of
Python's. The child builds the system and takes a fixed number of steps
with sim.steps(n) at the integrator's defaults (REBOUND's default sim.dt);
the figures are the totals over the steps taken. The first step's setup is
among them (under 1% at these step counts).

Systems (G = 1, COM frame):
  N = 2     Kepler e = 0.5, m = 1 and 1e-3, a = 1
  N = 3     Sun, Jupiter, Saturn (masses in Msun, a in AU, t in yr/2pi)
  N = 11+   a star and N - 1 planets of 1e-6 at a = 1 + 0.05 k, e = 0.05
            (benchmarks/solve.py's timing systems)

Categories, by the function that executed the instruction (its own cost,
not what it calls):
  gravity          REBOUND's gravity routine (gravity.c, boundary.c's ghost boxes)
  force interface  stage positions into REBOUND's particles, the call, the
                   accelerations back (pfvi_update_acceleration, stage_forces,
                   REBOUND's reb_simulation_update_acceleration)
  solve / method   pfvi: the stage equations, rounds and Newton corrections
                   (pfvi_solve.c, pfvi_stages.c, pfvi_fitting.c); IAS15/BS:
                   their whole integrator file (predictor and control included)
  predictor        pfvi's first iterate (two-body drift, the rest's
                   extrapolation, stage_predict; libm's sin/cos)
  control          step control and time scales (pfvi_control.c,
                   pfvi_timescales.c, pfvi_osculating.c, pfvi_centre.c; libm's
                   pow/exp/log)
  contact, output  pfvi_contact.c, pfvi_output.c
  bookkeeping      everything else (pfvi_integrator.c, pfvi_step.c,
                   pfvi_state.c, REBOUND's step, memcpy, ...)
"own / gravity" is everything but gravity over gravity.

A --baseline command (e.g. another build on PYTHONPATH) adds its rows for
pfvi, counted the same way in the same run.

--phases: pfvi's step by the phases of its algorithm instead, each the
inclusive count of the function that runs it (what it calls included), per
step: the work of the solve's rounds (forces: stage positions, the gravity
pass and back; the Newton correction; the rounds' stage equations; the
change measured) against the work done once a step (the two-body
predictor; the Newton factorisation; the step control outside the trial
step: time scales and the resolution check; the rest of the trial and of
the solve; what lies outside the control). It says what a cheaper round
can buy at most.

--megno: every system with sim.init_megno(seed=1), N variational particles
beside the N real ones (with --wall too).

--wall R: instead of counting, times pfvi's steps on the same systems (CPU
time of sim.steps, no valgrind) for this build and the --baseline build,
interleaved, best of R each, and prints the ratio: the wall-time judge of a
change (instruction counts can fall while time does not). Steps:
WALL_STEPS below.
"""
import argparse
import os
import re
import shlex
import shutil
import subprocess
import sys
import tempfile

CHILD = r"""
import sys, rebound
import rebound_pfvi  # noqa: F401
n, integrator, steps = int(sys.argv[1]), sys.argv[2], int(sys.argv[3])
sim = rebound.Simulation()
if n == 2:
    sim.add(m=1.0)
    sim.add(m=1e-3, a=1.0, e=0.5)
elif n == 3:
    sim.add(m=1.0)
    sim.add(m=9.547919e-4, a=5.2026, e=0.0485, inc=0.0228, Omega=1.7536, omega=4.7805, f=0.6)
    sim.add(m=2.858860e-4, a=9.5549, e=0.0555, inc=0.0434, Omega=1.9838, omega=5.9237, f=2.4)
else:
    sim.add(m=1.0)
    for k in range(n - 1):
        sim.add(m=1e-6, a=1.0 + 0.05 * k, e=0.05, inc=0.01 * (k % 7), f=2.1 * k)
sim.move_to_com()
if "megno" in sys.argv[4:]:
    sim.init_megno(seed=1)   # (N variational particles beside the N real ones)
sim.integrator = integrator
if "time" in sys.argv[4:]:   # timing: one step first (setup), then the steps timed
    import time
    sim.steps(1)
    t = time.process_time()
    sim.steps(steps)
    print("NS", (time.process_time() - t) / steps * 1e9)
else:
    sim.steps(steps)
print("STEPS", steps, sim.t)
"""

STEPS = {2: 3000, 3: 3000, 11: 1000, 101: 60, 1001: 3}
WALL_STEPS = {2: 30000, 3: 20000, 11: 4000, 101: 200, 1001: 4}

CATEGORIES = ("gravity", "force interface", "solve / method", "predictor", "control", "contact", "output",
              "bookkeeping")

FORCE_INTERFACE = {"pfvi_update_acceleration", "force_model_unchanged", "written_keep", "written_changed",
                   "stage_forces", "stage_solve_forces", "reb_simulation_update_acceleration",
                   "stage_forces_own", "stage_forces_own_variational", "stage_points"}
PREDICTOR = {"pfvi_solve_predict", "predict_body", "kepler_start", "kepler_drift", "kepler_pull", "stumpff",
             "rest_weights_of", "rest_integral", "stage_predict", "pfvi_lagrange_at", "centre_start"}
LIBM_PREDICTOR = ("sin", "cos", "sincos")
LIBM_CONTROL = ("pow", "exp", "log")


def category(file, function):
    base = os.path.basename(file)
    name = function.split(".")[0].split("'")[0]
    if base in ("gravity.c", "boundary.c", "pfvi_gravity.c"):
        return "gravity"
    if name in FORCE_INTERFACE:
        return "force interface"
    if name in PREDICTOR:
        return "predictor"
    if base.startswith("integrator_"):
        return "solve / method"
    if base in ("pfvi_solve.c", "pfvi_stages.c", "pfvi_fitting.c", "pfvi_two_point.c", "pfvi_lobatto.c"):
        return "solve / method"
    if base in ("pfvi_control.c", "pfvi_timescales.c", "pfvi_osculating.c", "pfvi_centre.c"):
        return "control"
    if base == "pfvi_contact.c":
        return "contact"
    if base == "pfvi_output.c":
        return "output"
    libm = re.sub(r"^__|(_fma|_avx2|_sse2|_finite)+$|@.*$", "", name).replace("ieee754_", "")
    if libm in LIBM_PREDICTOR or libm.startswith("sincos") or name.startswith("__sin") or name.startswith("__cos"):
        return "predictor"
    if libm in LIBM_CONTROL:
        return "control"
    return "bookkeeping"


LINE = re.compile(r"^\s*([\d,]+)\s+(?:\([^)]*\)\s+)?(\S.*?):(\S+)(?:\s+\[.*\])?\s*$")


def count(prefix, n, integrator, steps, workdir, flags=()):
    out = os.path.join(workdir, f"cg.{n}.{integrator}.{abs(hash(tuple(prefix))) % 10**6}")
    script = os.path.join(workdir, "child.py")
    with open(script, "w") as f:
        f.write(CHILD)
    python = prefix[-1]
    env_words = prefix[:-1]
    # valgrind must see the real interpreter (a shim script would exec it untraced).
    real = subprocess.run(["env"] + env_words + [python, "-c", "import sys; print(sys.executable)"],
                          capture_output=True, text=True, check=True).stdout.strip()
    cmd = ["env"] + env_words + ["valgrind", "--tool=callgrind", f"--callgrind-out-file={out}",
                                 "--collect-atstart=no", "--toggle-collect=reb_simulation_step",
                                 real, "-P", script, str(n), integrator, str(steps), *flags]
    run = subprocess.run(cmd, capture_output=True, text=True)
    if run.returncode != 0 or "STEPS" not in run.stdout:
        raise RuntimeError(f"child failed ({n}, {integrator}): {run.stderr[-2000:]}")
    annotate = subprocess.run(["callgrind_annotate", "--threshold=100", out], capture_output=True, text=True,
                              check=True).stdout
    totals = dict.fromkeys(CATEGORIES, 0)
    seen_header = False
    for line in annotate.splitlines():
        if "file:function" in line:
            seen_header = True
            continue
        if not seen_header:
            continue
        m = LINE.match(line)
        if m:
            totals[category(m.group(2), m.group(3))] += int(m.group(1).replace(",", ""))
    os.remove(out)
    return {k: v / steps for k, v in totals.items()}


# (label, functions whose inclusive counts add, functions whose inclusive counts are taken off)
PHASES = (
    ("rounds: forces", ("stage_solve_forces",), ()),
    ("rounds: Newton correction", ("newton_correct_unit",), ()),
    ("rounds: stage equations", ("stage_rounds",), ()),
    ("rounds: change", ("pfvi_solve_change",), ()),
    ("step: predictor", ("pfvi_solve_predict",), ()),
    ("step: Newton factorisation", ("pfvi_newton_prepare",), ()),
    ("step: control", ("pfvi_controlled_step",), ("pfvi_trial_step",)),
    ("step: rest of the trial", ("pfvi_trial_step",), ("stage_solve_forces", "newton_correct_unit", "stage_rounds",
                                                       "pfvi_solve_change", "pfvi_solve_predict",
                                                       "pfvi_newton_prepare")),
    ("step: outside the control", ("reb_simulation_step",), ("pfvi_controlled_step",)),
)


def phases(prefix, n, steps, workdir):
    out = os.path.join(workdir, f"cgp.{n}")
    script = os.path.join(workdir, "child.py")
    with open(script, "w") as f:
        f.write(CHILD)
    real = subprocess.run(["env"] + prefix[:-1] + [prefix[-1], "-c", "import sys; print(sys.executable)"],
                          capture_output=True, text=True, check=True).stdout.strip()
    cmd = ["env"] + prefix[:-1] + ["valgrind", "--tool=callgrind", f"--callgrind-out-file={out}",
                                   "--collect-atstart=no", "--toggle-collect=reb_simulation_step",
                                   real, "-P", script, str(n), "pfvi", str(steps)]
    run = subprocess.run(cmd, capture_output=True, text=True)
    if run.returncode != 0 or "STEPS" not in run.stdout:
        raise RuntimeError(f"child failed ({n}): {run.stderr[-2000:]}")
    annotate = subprocess.run(["callgrind_annotate", "--inclusive=yes", "--auto=no", "--threshold=100", out],
                              capture_output=True, text=True, check=True).stdout
    os.remove(out)
    inclusive = {}
    for line in annotate.splitlines():
        m = LINE.match(line)
        if m:
            # (a target clone, .avx2, or GCC's .constprop copy counts as its
            # function; a function listed under two spellings of its file, as an
            # in-place build's debug information can give, is counted once)
            name = m.group(3).split(".")[0]
            key = (name, os.path.basename(m.group(2)), m.group(3))
            inclusive.setdefault(name, {})[key] = int(m.group(1).replace(",", ""))
    inclusive = {name: sum(parts.values()) for name, parts in inclusive.items()}
    row = {label: (sum(inclusive.get(f, 0) for f in plus) - sum(inclusive.get(f, 0) for f in minus)) / steps
           for label, plus, minus in PHASES}
    row["step"] = inclusive.get("reb_simulation_step", 0) / steps
    return row


def phase_table(rows):
    labels = [label for label, _, _ in PHASES]
    lines = ["| N | instructions/step | " + " | ".join(labels) + " | once a step |",
             "|" + "---|" * (3 + len(labels))]
    for n, row in rows:
        once = sum(row[label] for label in labels if label.startswith("step:"))
        cells = " | ".join(f"{row[label] / 1e3:,.1f}k" for label in labels)
        lines.append(f"| {n} | {row['step'] / 1e3:,.1f}k | {cells} | {100 * once / row['step']:.0f}% |")
    return "\n".join(lines)


def wall(prefixes, n, repeats, workdir, flags=()):
    script = os.path.join(workdir, "child.py")
    with open(script, "w") as f:
        f.write(CHILD)
    best = [float("inf")] * len(prefixes)
    for _ in range(repeats):
        for k, prefix in enumerate(prefixes):
            out = subprocess.run(["env"] + prefix + ["-P", script, str(n), "pfvi", str(WALL_STEPS[n]), "time",
                                                      *flags],
                                 capture_output=True, text=True, check=True).stdout
            ns = float(out.split("NS")[1].split()[0])
            best[k] = min(best[k], ns)
    return best


def table(rows):
    head = ("| N | integrator | instructions/step | " + " | ".join(CATEGORIES) + " | own / gravity |")
    lines = [head, "|" + "---|" * (4 + len(CATEGORIES))]
    for n, label, c in rows:
        total = sum(c.values())
        shares = " | ".join(f"{100 * c[k] / total:.0f}%" if c[k] else "-" for k in CATEGORIES)
        own = (total - c["gravity"]) / c["gravity"] if c["gravity"] else float("nan")
        lines.append(f"| {n} | {label} | {total / 1e3:,.1f}k | {shares} | {own:.2f} |")
    return "\n".join(lines)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--sizes", default="2,3,11,101,1001")
    parser.add_argument("--integrators", default="pfvi,ias15,bs")
    parser.add_argument("--baseline", default=None, help="a command prefix running another build of pfvi")
    parser.add_argument("--output", default=None, help="write the markdown table here too")
    parser.add_argument("--wall", type=int, default=0, metavar="R",
                        help="time pfvi against --baseline instead (interleaved, best of R)")
    parser.add_argument("--phases", action="store_true", help="pfvi's step by the phases of its algorithm")
    parser.add_argument("--megno", action="store_true",
                        help="each system with init_megno(): N variational particles beside the N real ones")
    args = parser.parse_args()
    flags = ("megno",) if args.megno else ()
    if args.phases:
        if shutil.which("valgrind") is None:
            sys.exit("step_budget: needs valgrind (apt-get install valgrind)")
        with tempfile.TemporaryDirectory() as workdir:
            rows = [(n, phases([sys.executable], n, STEPS[n], workdir)) for n in
                    [int(x) for x in args.sizes.split(",")]]
        print(phase_table(rows))
        return
    if args.wall:
        if not args.baseline:
            sys.exit("step_budget: --wall needs --baseline")
        lines = ["| N | this build: ns/step | baseline: ns/step | ratio |", "|---|---|---|---|"]
        with tempfile.TemporaryDirectory() as workdir:
            for n in [int(x) for x in args.sizes.split(",")]:
                this, base = wall([[sys.executable], shlex.split(args.baseline)], n, args.wall, workdir, flags)
                lines.append(f"| {n} | {this:,.0f} | {base:,.0f} | {this / base:.2f} |")
                print(lines[-1], file=sys.stderr)
        print("\n".join(lines))
        return
    if shutil.which("valgrind") is None:
        sys.exit("step_budget: needs valgrind (apt-get install valgrind)")
    sizes = [int(x) for x in args.sizes.split(",")]
    rows = []
    with tempfile.TemporaryDirectory() as workdir:
        for n in sizes:
            for integrator in args.integrators.split(","):
                rows.append((n, integrator, count([sys.executable], n, integrator, STEPS[n], workdir, flags)))
                print(f"N = {n} {integrator}: {sum(rows[-1][2].values()) / 1e3:,.1f}k", file=sys.stderr)
                if args.baseline and integrator == "pfvi":
                    rows.append((n, "pfvi (baseline)", count(shlex.split(args.baseline), n, "pfvi", STEPS[n],
                                                              workdir, flags)))
                    print(f"N = {n} baseline: {sum(rows[-1][2].values()) / 1e3:,.1f}k", file=sys.stderr)
    text = table(rows)
    print(text)
    if args.output:
        with open(args.output, "w") as f:
            f.write(text + "\n")


if __name__ == "__main__":
    main()
