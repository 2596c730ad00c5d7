"""A MEGNO map with pfvi, IAS15 and WHFast: wall time per map, agreement of
the regular/chaotic verdicts with IAS15 at a tight epsilon, the maps side by side.

    python -P benchmarks/megno_map.py --output docs/megno.md [--grid 20] [--workers 2]
                                      [--scheduler tcp://host:8786] [--quick]

REBOUND's classic MEGNO example (its Megno.ipynb): the Sun, Jupiter (m =
9.54e-4, a = 5.204, e = 0.048) and a Saturn-mass planet (m = 2.85e-4) whose
a (7 ... 10) and e (0 ... 0.6) span the grid, G = 1 (time unit yr/2pi),
integrated to t = 500 * 2pi (42 Jupiter orbits) with init_megno(seed=0),
exit_max_distance = 20 (an escape counts as MEGNO 10) and MEGNO clipped at 10.
Each map's verdicts (regular: MEGNO < 2.5) are compared point by point with
the reference map (IAS15, epsilon 1e-11), over the whole grid and over its
eccentric half (e >= 0.3). Its wall time is the sum of its points' wall
times (each timed in its worker, so the number of workers does not change it).

Runs go through rebound_pfvi.runner: worker processes here (--workers), or a
Dask scheduler (--scheduler). Writes the page (--output), beside it a PNG of
the maps (needs matplotlib: the [plot] extra) and a JSON of every point.
--quick: a 6 x 6 grid to t = 50 * 2pi, a smoke test of the script.
"""
from __future__ import annotations

import argparse
import json
import math
import os
import platform
import statistics
import sys
import time
from typing import Any, Dict, List, Optional, Sequence, Tuple

#: (label, family, options): the reference first. Options are the
#: integrator's fields (rebound_pfvi.integrators.configure), dt is sim.dt.
CONFIGS: Tuple[Tuple[str, str, Dict[str, Any]], ...] = (
    ("IAS15 epsilon 1e-11 (reference)", "ias15", {"epsilon": 1e-11}),
    ("IAS15 epsilon 1e-9 (default)", "ias15", {}),
    ("pfvi s=8 epsilon 1e-6 (default)", "pfvi", {}),
    ("pfvi s=8 epsilon 1e-9", "pfvi", {"epsilon": 1e-9}),
    ("WHFast dt 5 (REBOUND's example)", "whfast", {"dt": 5.0}),
    ("WHFast dt 1", "whfast", {"dt": 1.0}),
    ("WHFast dt 0.4", "whfast", {"dt": 0.4}),
)
A_RANGE = (7.0, 10.0)
E_RANGE = (0.0, 0.6)
MEGNO_MAX = 10.0
REGULAR_BELOW = 2.5
ECCENTRIC_FROM = 0.3


def megno_point(family: str, options: Dict[str, Any], a: float, e: float, t_end: float) -> Dict[str, Any]:
    """One grid point: its MEGNO (10 on an escape, clipped at 10), Lyapunov
    exponent, wall time of the integration, and steps where the integrator counts them."""
    import rebound

    import rebound_pfvi  # noqa: F401  (registers "pfvi" in this worker)
    from rebound_pfvi.integrators import configure

    sim = rebound.Simulation()
    sim.add(m=1.0)
    sim.add(m=0.000954, a=5.204, M=0.600, omega=0.257, e=0.048)
    sim.add(m=0.000285, a=a, M=0.871, omega=1.616, e=e)
    sim.move_to_com()
    opts = dict(options)
    configure(sim, family, dt=opts.pop("dt", None), **opts)
    sim.init_megno(seed=0)
    sim.exit_max_distance = 20.0
    start = time.perf_counter()
    escaped = False
    try:
        sim.integrate(t_end, exact_finish_time=0)
    except rebound.Escape:
        escaped = True
    wall = time.perf_counter() - start
    megno = MEGNO_MAX if escaped else min(sim.megno(), MEGNO_MAX)
    steps = int(sim.integrator.n_steps) if family == "pfvi" else None
    return {"megno": float(megno), "lyapunov": float(sim.lyapunov()), "wall_s": wall, "escaped": escaped, "t": float(sim.t),
            "steps": steps}


def grid(n: int) -> Tuple[List[float], List[float]]:
    a = [A_RANGE[0] + (A_RANGE[1] - A_RANGE[0])*k/(n - 1) for k in range(n)]
    e = [E_RANGE[0] + (E_RANGE[1] - E_RANGE[0])*k/(n - 1) for k in range(n)]
    return a, e


def run_maps(n: int, t_end: float, workers: int, scheduler: Optional[str]) -> Tuple[Dict[str, Any], str, int]:
    """Every configuration's map: {label: [[point for each a] for each e]}."""
    from rebound_pfvi import runner

    a_values, e_values = grid(n)
    tasks, keys = [], []
    for label, family, options in CONFIGS:
        for i, e in enumerate(e_values):
            for j, a in enumerate(a_values):
                tasks.append(runner.Task(megno_point, (family, options, a, e, t_end)))
                keys.append((label, i, j))
    finished = [0]

    def done(index: int, outcome: Any) -> None:
        finished[0] += 1
        if finished[0] % 100 == 0 or finished[0] == len(tasks):
            print(f"  {finished[0]} of {len(tasks)} points", file=sys.stderr, flush=True)

    if scheduler:
        outcomes, workers, where = runner.run_tasks_dask(tasks, scheduler, done=done)
    else:
        outcomes = runner.run_tasks(tasks, workers=workers, done=done)
        where = f"{workers} worker processes"
    maps: Dict[str, Any] = {label: [[None]*n for _ in range(n)] for label, _, _ in CONFIGS}
    for (label, i, j), (status, result) in zip(keys, outcomes):
        if status != "ok":
            raise RuntimeError(f"{label} at a = {a_values[j]:.3f}, e = {e_values[i]:.3f}: {status}: {result}")
        maps[label][i][j] = result
    return maps, where, workers


def summary(maps: Dict[str, Any], n: int) -> List[Dict[str, Any]]:
    """Per map: wall time, steps, and verdict agreement with the reference (all points, e >= 0.3)."""
    _, e_values = grid(n)
    reference = maps[CONFIGS[0][0]]
    rows = []
    for label, family, _ in CONFIGS:
        m = maps[label]
        agree = agree_ecc = n_ecc = 0
        deviations = []  # |MEGNO - reference's| where the reference is regular, eccentric points
        for i in range(n):
            for j in range(n):
                same = (m[i][j]["megno"] < REGULAR_BELOW) == (reference[i][j]["megno"] < REGULAR_BELOW)
                agree += same
                if e_values[i] >= ECCENTRIC_FROM - 1e-12:
                    n_ecc += 1
                    agree_ecc += same
                    if reference[i][j]["megno"] < REGULAR_BELOW:
                        deviations.append(abs(m[i][j]["megno"] - reference[i][j]["megno"]))
        wall = sum(p["wall_s"] for row in m for p in row)
        steps = sum(p["steps"] for row in m for p in row) if family == "pfvi" else None
        rows.append({"label": label, "family": family, "wall_s": wall, "agree": agree/(n*n),
                     "agree_eccentric": agree_ecc/n_ecc, "n_eccentric": n_ecc, "steps": steps,
                     "n_eccentric_regular": len(deviations),
                     "deviation_median": statistics.median(deviations) if deviations else math.nan,
                     "deviation_max": max(deviations) if deviations else math.nan,
                     "regular": sum(p["megno"] < REGULAR_BELOW for row in m for p in row)})
    return rows


def plot(maps: Dict[str, Any], n: int, path: str) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    a_values, e_values = grid(n)
    da, de = (a_values[1] - a_values[0])/2, (e_values[1] - e_values[0])/2
    extent = [a_values[0] - da, a_values[-1] + da, e_values[0] - de, e_values[-1] + de]
    fig, axes = plt.subplots(2, 4, figsize=(16, 7.5), sharex=True, sharey=True)
    for ax, (label, _, _) in zip(axes.flat, CONFIGS):
        values = [[p["megno"] for p in row] for row in maps[label]]
        image = ax.imshow(values, origin="lower", extent=extent, aspect="auto", vmin=1.9, vmax=4.0,
                          cmap="RdYlGn_r", interpolation="nearest")
        ax.set_title(label, fontsize=9)
    for ax in axes[-1]:
        ax.set_xlabel("a [AU]")
    for ax in axes[:, 0]:
        ax.set_ylabel("e")
    for ax in list(axes.flat)[len(CONFIGS):]:
        ax.set_visible(False)
    fig.colorbar(image, ax=axes, label="MEGNO (clipped)", shrink=0.8)
    fig.savefig(path, dpi=90)
    plt.close(fig)


def markdown(rows: List[Dict[str, Any]], n: int, t_end: float, where: str, seconds: float, png: str,
             command: str) -> str:
    import rebound

    ref = rows[0]
    ias15_default = rows[1]
    out = [
        "# MEGNO maps: pfvi, IAS15 and WHFast", "",
        f"Generated by `{command}` ({seconds:.0f} s on {where}; REBOUND {rebound.__version__}, "
        f"Python {platform.python_version()}, {platform.machine()}).", "",
        f"REBOUND's classic MEGNO example: Sun, Jupiter (a = 5.204, e = 0.048), a Saturn-mass planet on a "
        f"{n} x {n} grid in a = {A_RANGE[0]:g} ... {A_RANGE[1]:g} and e = {E_RANGE[0]:g} ... {E_RANGE[1]:g}, "
        f"integrated to t = {t_end/(2*math.pi):g} x 2pi ({t_end/(2*math.pi*5.204**1.5):.0f} Jupiter orbits), "
        f"init_megno(seed=0), an escape beyond 20 AU counted as MEGNO {MEGNO_MAX:g}, MEGNO clipped at "
        f"{MEGNO_MAX:g}. Verdict: regular if MEGNO < {REGULAR_BELOW}. Agreement: the fraction of grid points "
        f"whose verdict is the reference's ({ref['label']}); eccentric: the {ref['n_eccentric']} points with "
        f"e >= {ECCENTRIC_FROM}. Wall time: the sum over the map's points of each integration's wall time "
        f"(one core each).", "",
        f"MEGNO error: |MEGNO - the reference's| over the {ref['n_eccentric_regular']} eccentric points the "
        f"reference finds regular (chaotic points' values depend on the trajectory followed).", "",
        "| map | wall time [s] | IAS15 default's time / this | agreement | eccentric agreement | "
        "eccentric MEGNO error, median | largest | regular points | pfvi steps |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        out.append(f"| {r['label']} | {r['wall_s']:.2f} | {ias15_default['wall_s']/r['wall_s']:.1f} | "
                   f"{100*r['agree']:.1f}% | {100*r['agree_eccentric']:.1f}% | {r['deviation_median']:.1e} | "
                   f"{r['deviation_max']:.1e} | {r['regular']} | {r['steps'] if r['steps'] is not None else ''} |")
    out += ["", f"![MEGNO maps]({os.path.basename(png)})", ""]
    return "\n".join(out) + "\n"


def main(argv: Optional[Sequence[str]] = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--output", default=None, help="the markdown page (docs/megno_map.md); default: stdout")
    parser.add_argument("--grid", type=int, default=20, help="points per axis (default 20)")
    parser.add_argument("--orbits", type=float, default=500.0, help="t_end / 2pi (default 500)")
    parser.add_argument("--workers", type=int, default=os.cpu_count() or 1)
    parser.add_argument("--scheduler", default=None, help="a Dask scheduler's address (needs the [dask] extra)")
    parser.add_argument("--quick", action="store_true", help="6 x 6 points to t = 50 x 2pi (a smoke test)")
    args = parser.parse_args(argv)
    if args.quick:
        args.grid, args.orbits = 6, 50.0
    t_end = args.orbits*2*math.pi
    start = time.perf_counter()
    maps, where, _ = run_maps(args.grid, t_end, args.workers, args.scheduler)
    seconds = time.perf_counter() - start
    rows = summary(maps, args.grid)
    base = os.path.splitext(args.output)[0] if args.output else "megno_map"
    png = base + ".png"
    try:
        plot(maps, args.grid, png)
    except ImportError:
        print("matplotlib is not installed: no PNG (pip install 'rebound_pfvi[plot]')", file=sys.stderr)
    command = "python -P benchmarks/megno_map.py" + (f" --output {args.output}" if args.output else "") + \
        (" --quick" if args.quick else "")
    page = markdown(rows, args.grid, t_end, where, seconds, png, command)
    compact = {label: [[{k: (float(f"{v:.6g}") if isinstance(v, float) else v) for k, v in p.items()} for p in row]
                        for row in m] for label, m in maps.items()}
    with open(base + ".json", "w") as f:
        json.dump({"grid": args.grid, "t_end": t_end, "summary": rows, "maps": compact}, f, separators=(",", ":"))
    if args.output:
        with open(args.output, "w") as f:
            f.write(page)
    else:
        sys.stdout.write(page)


if __name__ == "__main__":
    main()
