"""Issue 42's wall-time goal judged interleaved: on each page and position
error, pfvi's fastest line against the fastest other line, retimed in one
process with their runs taking turns.

    python -P benchmarks/cells_interleaved.py [--folder docs/results] [--pages kepler-e0.95,jupiter-comet]
                                              [--targets 1e-6,1e-8,1e-10] [--rounds 7] [--sample 0.05]

The pages (`rebound_pfvi compare --full`) time each setting best of 3 while
the sweep's other runs share the cores; their run-to-run noise is 1.5x at
the 90th percentile (report.TIE_RATIO), too coarse for the issue's 1.2x. So
this rereads the pages' JSON and, for each page and target, takes as
candidates every line whose recorded least time to the target is within
--within (2.0) of the cell's fastest, pfvi's defaults (pfvi s=8) always
among them; of each line, the loosest knob that reached the target and the
knob with the least recorded time. It then reruns them here, as the pages
do (a fresh simulation, sim.integrate(t_end), build and configuration
untimed), in --rounds rounds; in each round every candidate runs in turn
(the order rotated between rounds), each sample as many back-to-back runs
as fill --sample seconds. A candidate's time is its least per-run time over
the rounds; a line's time is its best candidate's. The position error of
each candidate's run is recomputed against the scene's reference: a
candidate that does not reach the target here is dropped (and said so).

Printed: per page and target, pfvi's fastest line and the fastest other
line with their knobs and times, their ratio, and the verdict the issue
asks for: "pfvi first", "tied (within 1.2x)" or "behind". Pages without a
gravitating pair (the oscillator) are left out unless named in --pages.
"""
from __future__ import annotations

import argparse
import json
import math
import sys
import time
from pathlib import Path
from typing import Dict, List, Optional, Tuple

from rebound_pfvi import compare, report, scenes
from rebound_pfvi.runs import Run

sys.path.insert(0, str(Path(__file__).resolve().parent))
from pages_summary import DEFAULT_LINE, NO_GRAVITY, PAGES  # noqa: E402

#: The issue's tie: within this ratio of the fastest other line.
ISSUE_TIE = 1.2
#: Knob families where a larger knob value is the looser (cheaper) run.
LARGER_IS_LOOSER = ("pfvi", "ias15", "bs")


class Candidate:
    """One setting of one line, with what was recorded and what is measured here."""

    def __init__(self, run: Run) -> None:
        self.run = run
        self.setting = compare.Setting(run.family, float(run.value), tuple(sorted(run.options.items())),
                                       line=run.label)
        self.best: float = math.inf
        self.error: Optional[float] = None

    @property
    def name(self) -> str:
        return f"{self.run.label} ({self.run.knob} {self.run.value:g})"


def candidates_of(rows: List[Run], target: float, within: float) -> List[Candidate]:
    best = report.fastest(rows, target)
    if not best:
        return []
    fastest = min(r.wall_s for r in best.values())
    lines = [label for label, r in best.items() if r.wall_s <= within * fastest or label == DEFAULT_LINE]
    others = [r for r in best.values() if r.family != "pfvi"]
    if others:  # the fastest other line, however far behind
        lines.append(min(others, key=lambda r: r.wall_s).label)
    chosen: Dict[Tuple[str, float], Run] = {}
    for label in dict.fromkeys(lines):
        reached = [r for r in rows if r.label == label and r.status == "ok" and r.position_error is not None
                   and r.position_error <= target]
        if not reached:
            continue
        family = reached[0].family
        loosest = (max if family in LARGER_IS_LOOSER else min)(reached, key=lambda r: r.value)
        for r in (loosest, best[label]):
            chosen[(label, r.value)] = r
    return [Candidate(r) for r in chosen.values()]


def one_run(scene: scenes.Scene, setting: compare.Setting) -> Tuple[float, object]:
    sim = scene.build()
    compare.configure(sim, scene, setting)
    tick = time.perf_counter()
    sim.integrate(scene.t_end, exact_finish_time=1)
    return time.perf_counter() - tick, sim


def measure(scene: scenes.Scene, reference: Dict, cands: List[Candidate], target: float, rounds: int,
            sample: float) -> List[str]:
    dropped = []
    for c in cands:  # the error here, and a first time to size the samples
        wall, sim = one_run(scene, c.setting)
        c.error = scene.position_error(sim, reference)
        c.repeat = max(1, int(math.ceil(sample / max(wall, 1e-6))))
    for c in [c for c in cands if not (c.error <= target)]:
        dropped.append(f"{c.name}: {c.error:.2e} AU here (page: {c.run.position_error:.2e})")
        cands.remove(c)
    for k in range(rounds):
        for c in cands[k % len(cands):] + cands[:k % len(cands)] if cands else []:
            total = 0.0
            for _ in range(c.repeat):
                total += one_run(scene, c.setting)[0]
            c.best = min(c.best, total / c.repeat)
    return dropped


def line_times(cands: List[Candidate]) -> Dict[str, Candidate]:
    lines: Dict[str, Candidate] = {}
    for c in cands:
        if c.run.label not in lines or c.best < lines[c.run.label].best:
            lines[c.run.label] = c
    return lines


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--folder", default="docs/results")
    parser.add_argument("--pages", default="", help="page slugs, comma-separated (default: every page with gravity)")
    parser.add_argument("--targets", default="1e-6,1e-8,1e-10")
    parser.add_argument("--rounds", type=int, default=7)
    parser.add_argument("--sample", type=float, default=0.05, help="seconds of back-to-back runs per timed sample")
    parser.add_argument("--within", type=float, default=2.0)
    args = parser.parse_args()
    folder = Path(args.folder)
    wanted = [p for p in args.pages.split(",") if p] or [p for p in PAGES if p not in NO_GRAVITY]
    targets = [float(t) for t in args.targets.split(",")]
    tick = time.perf_counter()
    table = ["| page | error | fastest pfvi line | fastest other line | pfvi / other | verdict |",
             "|---|---|---|---|---|---|"]
    notes = []
    counts = {"pfvi first": 0, f"tied (within {ISSUE_TIE}x)": 0, "behind": 0}
    for slug in wanted:
        path = folder / f"{slug}.json"
        if not path.exists():
            notes.append(f"{slug}: no page in {folder}")
            continue
        page = json.loads(path.read_text())
        rows = [Run.from_dict(r) for r in page["rows"]]
        scene = scenes.make(page["scene"], **page["params"])
        reference = scene.reference()
        for target in targets:
            cands = candidates_of(rows, target, args.within)
            dropped = measure(scene, reference, cands, target, args.rounds, args.sample)
            notes += [f"{slug} {target:.0e}: dropped {d}" for d in dropped]
            lines = line_times(cands)
            pfvi = min((c for c in lines.values() if c.run.family == "pfvi"), key=lambda c: c.best, default=None)
            other = min((c for c in lines.values() if c.run.family != "pfvi"), key=lambda c: c.best, default=None)
            name = PAGES.get(slug, slug)

            def cell(c: Optional[Candidate]) -> str:
                return "none gets there" if c is None else f"{c.name} {c.best * 1e3:.3g} ms"

            if pfvi and other:
                ratio = pfvi.best / other.best
                verdict = ("pfvi first" if ratio <= 1.0 else f"tied (within {ISSUE_TIE}x)" if ratio <= ISSUE_TIE
                           else "behind")
                counts[verdict] += 1
                table.append(f"| {name} | {target:.0e} AU | {cell(pfvi)} | {cell(other)} | {ratio:.2f} | {verdict} |")
            else:
                table.append(f"| {name} | {target:.0e} AU | {cell(pfvi)} | {cell(other)} | - | "
                             f"{'pfvi alone gets there' if pfvi else 'pfvi does not get there'} |")
            print(table[-1], flush=True)
    print("\n" + "\n".join(table))
    print("\n" + ", ".join(f"{k}: {v}" for k, v in counts.items()))
    for n in notes:
        print("-", n)
    print(f"\n{time.perf_counter() - tick:.0f} s; rounds {args.rounds}, samples of {args.sample} s")


if __name__ == "__main__":
    main()
