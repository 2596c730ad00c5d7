"""Whether pfvi's error falls as epsilon does (issue 42, item 3).

Every page of docs/results.md with gravity (its scene and parameters from the
page's JSON; mercury-gr needs REBOUNDx and is run when it is installed) and
the Encke-like comet of benchmarks/outputs.py run at pfvi's defaults (s = 8)
down a ladder of epsilons, a decade apart (1e-4 ... 1e-12), to the page's
t_end. The table gives each run's largest position error against the page's
reference (IAS15 at a tight epsilon, or the exact Kepler orbit), in units of
epsilon a n (a a body's orbit size, n its orbits: the step control's goal is
at most 10), epsilon_effective and the steps per shortest period. A scene is
monotone where every run's error is at most its looser neighbour's; runs
within 100 times the reference's uncertainty (or 1e-12 of the scene's size,
the round-off floor of s = 8) are not judged.

    python3 -P benchmarks/epsilon_monotone.py                 # about 30 s
    python3 -P benchmarks/epsilon_monotone.py --ladder 1e-5,1e-6,1e-7 --scenes kepler-e0.9
"""
import argparse
import json
import math
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from rebound_pfvi import scenes  # noqa: E402
from rebound_pfvi.integrators import configure  # noqa: E402

import outputs  # noqa: E402  (the Encke-like comet)

ROOT = Path(__file__).resolve().parent.parent
LADDER = [10.0 ** -k for k in range(4, 13)]


def pages():
    """(slug, scene) for each page of docs/results with gravity, and the Encke-like comet."""
    out = []
    for path in sorted((ROOT / "docs" / "results").glob("*.json")):
        page = json.loads(path.read_text())
        if page["scene"] == "oscillator":
            continue
        if page["scene"] == "mercury-gr":
            try:
                import reboundx  # noqa: F401
            except ImportError:
                continue
        out.append((path.stem, scenes.make(page["scene"], **page["params"])))
    out.append(("encke", outputs.Encke()))
    return out


def ladder_of(scene, ladder):
    """[(epsilon, epsilon_effective, error, goal ratio, steps)] down the ladder."""
    reference = scene.reference()
    scales = scenes.orbit_scales(scene.build(), scene.t_end)
    rows = []
    for eps in ladder:
        sim = scene.build()
        configure(sim, "pfvi", epsilon=eps)
        sim.integrate(scene.t_end, exact_finish_time=1)
        error = scene.position_error(sim, reference)
        goal = error / (eps * min(a * n for a, n in scales))
        rows.append((eps, sim.integrator.epsilon_effective, error, goal, sim.integrator.n_steps))
    size = max(a for a, _ in scales)
    floor = max(100.0 * reference.get("uncertainty", 0.0), 1e-12 * size)
    return rows, floor


def breaks(rows, floor):
    """Where a run's error exceeds its looser neighbour's (above the floor):
    [(looser epsilon, its error, epsilon, error)]."""
    out = []
    for (e0, _, err0, _, _), (e1, _, err1, _, _) in zip(rows, rows[1:]):
        if err1 > floor and err1 > err0:
            out.append((e0, err0, e1, err1))
    return out


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--ladder", default=None, help="epsilons, comma-separated (default 1e-4 ... 1e-12)")
    parser.add_argument("--scenes", default=None, help="page slugs, comma-separated (default: all)")
    args = parser.parse_args(argv)
    ladder = [float(x) for x in args.ladder.split(",")] if args.ladder else LADDER
    chosen = set(args.scenes.split(",")) if args.scenes else None
    start = time.perf_counter()
    total = 0
    for slug, scene in pages():
        if chosen and slug not in chosen:
            continue
        rows, floor = ladder_of(scene, ladder)
        period = scene.period
        cells = "; ".join(f"{eps:.0e}: {err:.1e} ({goal:.2g}, {steps * period / scene.t_end:.1f}/P)"
                          for eps, _, err, goal, steps in rows)
        found = breaks(rows, floor)
        total += len(found)
        verdict = "monotone" if not found else "NOT monotone at " + ", ".join(
            f"{e0:.0e} {r0:.1e} -> {e1:.0e} {r1:.1e}" for e0, r0, e1, r1 in found)
        print(f"{slug}: {verdict} (floor {floor:.0e})\n    {cells}", flush=True)
    print(f"{total} breaks; {time.perf_counter() - start:.0f} s")


if __name__ == "__main__":
    main()
