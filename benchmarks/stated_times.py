"""Reruns every command whose run time README.md states, and records each
run beside a fingerprint of the sources that command runs (issue 41).

docs/stated-times.json holds, per command: the command as README.md gives
it, what was run, the wall time, the CPU time of the command and its child
processes, the load average before and after (the machine is shared), the
date, and the SHA-256 of the files it depends on. tests/test_stated_figures.py
fails when README.md states a time that differs from the recorded one, states
a run time no record covers, or when those files have changed since the
recording: rerun this script and copy its phrases into README.md.

    python3 -P benchmarks/stated_times.py                  # every command
    python3 -P benchmarks/stated_times.py --only main,kepler

The wall time is what README.md states (rounded to whole seconds); on a
quiet 2-core machine a command of one process takes about its CPU time, and
compare's two workers about half of it. The install takes the wheels pip
finds where this machine's pip configuration points (a local folder here:
no download), with an empty pip cache.
"""
import argparse
import hashlib
import json
import os
import re
import resource
import shlex
import subprocess
import sys
import tempfile
import time
from datetime import datetime, timezone
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
RECORDS = ROOT / "docs" / "stated-times.json"

#: The package's computing modules and C core: what every command that
#: integrates runs.
CORE = ["rebound_pfvi/csrc/*.c", "rebound_pfvi/csrc/*.h", "rebound_pfvi/__init__.py", "rebound_pfvi/_core.py",
        "rebound_pfvi/integrators.py", "rebound_pfvi/scenes.py", "rebound_pfvi/units.py"]
COMPARE = CORE + ["rebound_pfvi/__main__.py", "rebound_pfvi/compare.py", "rebound_pfvi/runner.py",
                  "rebound_pfvi/runs.py", "rebound_pfvi/report.py", "rebound_pfvi/verdict.py"]
BUILD = ["pyproject.toml", "setup.py", "build_backend/*.py", "rebound_pfvi/csrc/*.c", "rebound_pfvi/csrc/*.h"]

#: Everything the test suite runs.
SUITE = ["rebound_pfvi/*.py", "rebound_pfvi/csrc/*.c", "rebound_pfvi/csrc/*.h", "tests/*.py", "tests/data/*",
         "benchmarks/*.py", "examples/*"]

#: id -> (the command as README.md states it, argv run here ({out}: a
#: throwaway folder; {py}: this Python; {root}: the source tree), the files
#: it runs, the phrases README.md states: {wall} the recorded seconds,
#: {load} the load average over the run, {summary} pytest's counts).
COMMANDS = {
    "main": ("python3 -P -m rebound_pfvi compare --output results",
             "{py} -P -m rebound_pfvi compare --output {out}", COMPARE,
             ["({wall} s on 2 cores at load {load}", "quick sweep: {wall} s at load {load}"]),
    "kepler": ('rebound-pfvi compare --scene kepler --e 0.99 --a "2 AU" --mass "0.8 Msun" --m "1 Mjup"',
               '{py} -P -m rebound_pfvi compare --scene kepler --e 0.99 --a "2 AU" --mass "0.8 Msun" --m "1 Mjup" '
               "--output {out}", COMPARE, ['--m "1 Mjup" # {wall} s at load {load}']),
    "comet-full": ("rebound-pfvi compare --scene comet --full --budget 60 --output docs/results",
                   "{py} -P -m rebound_pfvi compare --scene comet --full --budget 60 --output {out}", COMPARE,
                   ["--output docs/results # {wall} s at load {load}"]),
    "oscillator": ('rebound-pfvi compare --scene oscillator --omega "1 1/day" --integrators pfvi,ias15',
                   '{py} -P -m rebound_pfvi compare --scene oscillator --omega "1 1/day" --integrators pfvi,ias15 '
                   "--output {out}", COMPARE, ["--integrators pfvi,ias15 # {wall} s at load {load}"]),
    "stability-two": ("rebound-pfvi stability --cases radial-infall,pythagorean --budget 10",
                      "{py} -P -m rebound_pfvi stability --cases radial-infall,pythagorean --budget 10 --output {out}",
                      CORE + ["rebound_pfvi/__main__.py", "rebound_pfvi/stability.py", "rebound_pfvi/runs.py",
                              "rebound_pfvi/report.py", "rebound_pfvi/verdict.py"],
                      ["--budget 10 # {wall} s at load {load}"]),
    "install": ('python3 -m pip install ".[plot]"  (a new venv, an empty pip cache)',
                "{py} -m venv {out}/venv && PIP_NO_CACHE_DIR=1 {out}/venv/bin/python -m pip install -q "
                "{root}[plot]", BUILD, ["after an install of about {wall} s at load {load}"]),
    "tests": ('python3 -m pip install ".[test]" && python3 -P -m pytest tests',
              # The two checks of these records cannot pass before the run they check (its phrase and
              # fingerprint do not exist yet): deselected while the suite is timed.
              "cd {root} && {py} -P -m pytest -q -p no:cacheprovider tests --deselect "
              "tests/test_stated_figures.py::test_every_run_time_readme_states_is_a_recorded_run --deselect "
              "tests/test_stated_figures.py::test_no_stated_time_outlives_a_change_of_the_code_it_measured", SUITE,
              ["(about {wall} s on 2 cores at load {load}: {summary})"]),
}


def fingerprint(patterns):
    """SHA-256 over the files the patterns name (relative path and contents, sorted)."""
    digest = hashlib.sha256()
    files = sorted({p for pattern in patterns for p in ROOT.glob(pattern) if p.is_file()})
    for path in files:
        digest.update(str(path.relative_to(ROOT)).encode() + b"\0" + path.read_bytes() + b"\0")
    return digest.hexdigest()


def record(name):
    stated, argv, sources, phrases = COMMANDS[name]
    with tempfile.TemporaryDirectory(prefix=f"stated-{name}-") as out:
        command = argv.format(py=shlex.quote(sys.executable), out=out, root=shlex.quote(str(ROOT)))
        load_before = os.getloadavg()[0]
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        tick = time.perf_counter()
        done = subprocess.run(command, shell=True, cwd=out, capture_output=True, text=True)
        wall = time.perf_counter() - tick
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if done.returncode != 0:
        raise SystemExit(f"{name}: {command} failed:\n{done.stderr[-2000:]}")
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    load = (load_before + os.getloadavg()[0]) / 2
    counts = re.findall(r"(\d+ passed(?:, \d+ \w+)*)", done.stdout)
    summary = counts[-1] if counts else ""
    return {"command": stated, "ran": argv, "wall_s": round(wall, 1), "cpu_s": round(cpu, 1),
            "load_before": round(load_before, 2), "load_after": round(os.getloadavg()[0], 2),
            "cores": os.cpu_count(), "date": datetime.now(timezone.utc).strftime("%Y-%m-%d %H:%M UTC"),
            "sources": sources, "fingerprint": fingerprint(sources),
            "summary": summary,
            "phrases": [p.format(wall=f"{round(wall, 1):.0f}", load=f"{load:.1f}", summary=summary) for p in phrases]}


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--only", default=None, help="comma-separated ids (default: all): " + ", ".join(COMMANDS))
    args = parser.parse_args(argv)
    names = args.only.split(",") if args.only else list(COMMANDS)
    unknown = [n for n in names if n not in COMMANDS]
    if unknown:
        parser.error(f"--only: {', '.join(unknown)} not among {', '.join(COMMANDS)}")
    records = json.loads(RECORDS.read_text()) if RECORDS.exists() else {}
    for name in names:
        records[name] = record(name)
        r = records[name]
        print(f"{name}: {r['wall_s']} s wall, {r['cpu_s']} s CPU, load {r['load_before']} -> {r['load_after']}: "
              f"README.md states {r['phrases']}", flush=True)
        RECORDS.write_text(json.dumps(records, indent=1) + "\n")


if __name__ == "__main__":
    main()
