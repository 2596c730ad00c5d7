"""The table of docs/results.md, "What the pages show", from the pages' JSON
files: for each page and position error (1e-6, 1e-8, 1e-10 AU), pfvi at its
defaults (the line "pfvi s=8") and IAS15, each its least wall time to that
error within the sweep, their ratio, and the fastest line of all with every
line tied with it (within report.TIE_RATIO, the run-to-run noise).
Then, per family, the pages and errors where it is the fastest or tied;
and issue 42's two comparisons: per page and error, pfvi's fastest line
against the fastest line of any other integrator (BS included; the issue
counts within 1.2x as tied, the pages' noise is report.TIE_RATIO), and at
1e-6 AU pfvi's defaults against WHFast with its corrector.

    python3 -P benchmarks/pages_summary.py [docs/results]
"""
from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import Dict, Iterator, List, Tuple

from rebound_pfvi import report
from rebound_pfvi.runs import Run

TARGETS = (1e-6, 1e-8, 1e-10)
DEFAULT_LINE = "pfvi s=8"
WHFAST_CORRECTOR = "WHFast corrector=11 safe_mode=0"
#: Page order and names, as docs/results.md lists them.
PAGES = {"kepler-e0.5": "Kepler e = 0.5", "kepler-e0.9": "Kepler e = 0.9", "kepler-e0.95": "Kepler e = 0.95",
         "kepler-e0.99": "Kepler e = 0.99", "comet-e0.95": "comet", "triple-e0.7": "triple",
         "jupiter-comet": "Jupiter-family comet", "retrograde": "retrograde crosser",
         "sungrazer-e0.999": "sungrazer", "circumbinary": "circumbinary planet",
         "outer-solar-system": "outer solar system", "periodic-box": "periodic box",
         "mercury-gr": "Mercury with \"gr\"", "oscillator": "oscillator"}


#: Pages without a gravitating pair, left out of the ratio to IAS15 that
#: README.md, docs/results.md and the demo state.
NO_GRAVITY = ("oscillator",)


def page_rows(folder: Path) -> Iterator[Tuple[str, str, List[Run]]]:
    """(slug, name, runs) of each page of PAGES that folder holds, in PAGES' order."""
    for slug, name in PAGES.items():
        path = folder / f"{slug}.json"
        if path.exists():
            yield slug, name, [Run.from_dict(r) for r in json.loads(path.read_text())["rows"]]


def ias15_ratio_range(folder: Path) -> Tuple[float, float]:
    """(least, largest) ratio of pfvi's defaults' wall time to IAS15's, at
    each of TARGETS that both reach, over the pages with gravity: the range
    README.md, docs/results.md and rebound_pfvi.demo state (tests/test_docs.py
    checks them against this)."""
    ratios = []
    for slug, _, rows in page_rows(folder):
        if slug in NO_GRAVITY:
            continue
        for target in TARGETS:
            best = report.fastest(rows, target)
            if DEFAULT_LINE in best and "IAS15" in best:
                ratios.append(best[DEFAULT_LINE].wall_s / best["IAS15"].wall_s)
    if not ratios:
        raise ValueError(f"{folder}: no page where both {DEFAULT_LINE} and IAS15 reach {TARGETS}")
    return min(ratios), max(ratios)


def _s(seconds: float) -> str:
    return f"{seconds:.2g} s"


def main() -> None:
    folder = Path(sys.argv[1] if len(sys.argv) > 1 else "docs/results")
    lines = ["| page | error | pfvi defaults / IAS15 (wall time) | fastest, and lines tied with it |",
             "|---|---|---|---|"]
    wins: Dict[str, List[str]] = {}
    for slug, name, rows in page_rows(folder):
        for target in TARGETS:
            best = report.fastest(rows, target)
            if not best:
                lines.append(f"| {name} | {target:.0e} AU | - | no run gets there |")
                continue
            order = sorted(best.values(), key=lambda r: r.wall_s)
            first = [r for r in order if report.tied(order[0], r)]
            pfvi, ias15 = best.get(DEFAULT_LINE), best.get("IAS15")
            if pfvi and ias15:
                ratio = f"{_s(pfvi.wall_s)} / {_s(ias15.wall_s)} = **{pfvi.wall_s / ias15.wall_s:.2f}**"
            elif pfvi:
                ratio = f"{_s(pfvi.wall_s)} / IAS15 does not get there"
            elif ias15:
                ratio = f"pfvi s=8 does not get there / {_s(ias15.wall_s)}"
            else:
                ratio = "neither gets there"
            fastest = ", ".join(f"{r.label} {_s(r.wall_s)}" for r in first)
            if len(first) > 1:
                fastest = "tie: " + fastest
            lines.append(f"| {name} | {target:.0e} AU | {ratio} | {fastest} |")
            for r in first:
                where = f"{name} {target:.0e}"
                if where not in wins.setdefault(r.family, []):
                    wins[r.family].append(where)
    print("\n".join(lines))
    low, high = ias15_ratio_range(folder)
    print(f"\npfvi's defaults at {low:.2f}-{high:.2f} times IAS15's wall time on the pages with gravity.")
    print("\nFastest or tied, per family:")
    for family, where in sorted(wins.items()):
        print(f"- {family}: {len(where)}: {', '.join(where)}")
    print("\n" + "\n".join(against_the_rest(folder)))


def against_the_rest(folder: Path) -> List[str]:
    """Issue 42's table: pfvi's fastest line over the fastest other line,
    and (1e-6 AU) pfvi's defaults over WHFast with its corrector."""
    lines = ["| page | error | fastest pfvi line | fastest other line | ratio | pfvi defaults / WHFast corrector |",
             "|---|---|---|---|---|---|"]
    for slug, name, rows in page_rows(folder):
        for target in TARGETS:
            best = report.fastest(rows, target)
            pfvi = min((r for r in best.values() if r.family == "pfvi"), key=lambda r: r.wall_s, default=None)
            other = min((r for r in best.values() if r.family != "pfvi"), key=lambda r: r.wall_s, default=None)
            ratio = f"{pfvi.wall_s / other.wall_s:.2f}" if pfvi and other else "-"
            whfast = best.get(WHFAST_CORRECTOR)
            default = best.get(DEFAULT_LINE)
            corrector = "-"
            if target == TARGETS[0]:
                corrector = (f"{default.wall_s / whfast.wall_s:.2f}" if default and whfast
                             else "WHFast corrector does not get there" if default else "pfvi s=8 does not get there")
            lines.append(f"| {name} | {target:.0e} AU | "
                         f"{f'{pfvi.label} {_s(pfvi.wall_s)}' if pfvi else 'none gets there'} | "
                         f"{f'{other.label} {_s(other.wall_s)}' if other else 'none gets there'} | {ratio} | {corrector} |")
    return lines


if __name__ == "__main__":
    main()
