"""Run-to-run noise of compare's wall times: the quick sweep of a scene run
`--sweeps` times (default 3) one after another; for each setting the ratio
of its slowest to its fastest best-of-repeats wall time across the sweeps.

    python3 -P benchmarks/noise.py                       # the main job's scene (comet), 3 sweeps
    python3 -P benchmarks/noise.py --scene kepler --sweeps 5

It prints the ratios' quantiles overall and by wall time. The pages call two
lines a tie when their times differ by less than report.TIE_RATIO, the 90th
percentile measured here, rounded up over the scenes measured (docs/results.md, "Ties")."""
from __future__ import annotations

import argparse
import statistics
from typing import Dict, List, Tuple


def measure(scene_name: str, sweeps: int, repeats: int) -> List[Tuple[str, float, float]]:
    """(setting, median wall time, slowest/fastest) for each setting of the quick sweep."""
    from rebound_pfvi import compare, scenes

    scene = scenes.make(scene_name)
    settings = compare.default_settings(scene, "quick")
    walls: Dict[str, List[float]] = {}
    for k in range(sweeps):
        results = compare.run(scene, settings, repeats=repeats)
        for row in results.rows:
            if row.wall_s is not None:
                walls.setdefault(row.name, []).append(row.wall_s)
        print(f"sweep {k + 1} of {sweeps}: {results.wall_s:.1f} s", flush=True)
    return [(name, statistics.median(w), max(w) / min(w)) for name, w in walls.items() if len(w) == sweeps]


def quantile(values: List[float], q: float) -> float:
    ordered = sorted(values)
    return ordered[min(len(ordered) - 1, int(q * len(ordered)))]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scene", default="comet")
    parser.add_argument("--sweeps", type=int, default=3)
    parser.add_argument("--repeats", type=int, default=3, help="compare's timed repeats, best kept (default 3)")
    args = parser.parse_args()
    rows = measure(args.scene, args.sweeps, args.repeats)
    ratios = [r for _, _, r in rows]
    print(f"\n{len(rows)} settings, {args.sweeps} quick sweeps of {args.scene}, best of {args.repeats} each")
    print(f"slowest/fastest across sweeps: median {statistics.median(ratios):.3f}, "
          f"90th percentile {quantile(ratios, 0.9):.3f}, largest {max(ratios):.3f}")
    for low, high in ((0.0, 1e-3), (1e-3, 1e-2), (1e-2, 1e-1), (1e-1, 1e9)):
        band = [r for _, wall, r in rows if low <= wall < high]
        if band:
            print(f"  wall {low:g} to {high:g} s: {len(band)} settings, median {statistics.median(band):.3f}, "
                  f"90th percentile {quantile(band, 0.9):.3f}")


if __name__ == "__main__":
    main()
