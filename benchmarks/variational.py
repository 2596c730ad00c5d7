"""The figures of docs/megno.md besides the map: the tangent map against
finite differences, MEGNO of a regular and a chaotic system, the Lyapunov
exponent against IAS15's, and what variational particles cost per step.

    python -P benchmarks/variational.py --output docs/megno_checks.md [--workers 2] [--scheduler ADDR]

A. Tangent map against central differences of two real runs (delta 1e-8 on
   the inner planet's vy): star, planet 1e-3 at a = 1 (e = 0.5, 0.9), planet
   1e-3 at a = 4, 10 inner orbits, s = 4 and 8, the default epsilon 1e-6 and
   1e-10; largest difference over all particles and coordinates relative to
   the largest derivative.
B. MEGNO after 1000 inner orbits of a regular pair (REBOUND's test_megno:
   a = 1.5 and 15, e = 0.1) and of a chaotic pair (P = 1 and 1.17, m = 1e-4).
C. The Lyapunov exponent of that chaotic pair, whose finite-time value
   depends on the trajectory followed: the median over an ensemble of 48
   starts (the outer planet's mean anomaly 2pi k/48) to t = 2000,
   pfvi (epsilon 1e-6 and 1e-10) against IAS15 at epsilon 1e-11, with
   IAS15 at 1e-9 for the reference's own spread.
D. Cost: wall time (best of 3) and force evaluations with init_megno()
   over without, on the regular pair to t = 20000, pfvi s = 4 and 8, IAS15.
"""
from __future__ import annotations

import argparse
import math
import os
import platform
import statistics
import sys
import time
from typing import Any, Dict, List, Optional, Sequence, Tuple

import numpy as np

STATE = ("x", "y", "z", "vx", "vy", "vz")
ENSEMBLE = 48
COST_T = 20000.0


def _pfvi(sim, **options):
    import rebound_pfvi  # noqa: F401
    from rebound_pfvi.integrators import configure
    return configure(sim, "pfvi", **options)


def planets(e: float, stages: int, epsilon: float, dvy: float = 0.0):
    import rebound
    sim = rebound.Simulation()
    sim.add(m=1.0)
    sim.add(m=1e-3, a=1.0, e=e)
    sim.add(m=1e-3, a=4.0, e=0.1, inc=0.1, f=1.0, primary=sim.particles[0])
    sim.particles[1].vy += dvy
    return _pfvi(sim, stages=stages, epsilon=epsilon)


def state(particles) -> np.ndarray:
    return np.array([[getattr(p, f) for f in STATE] for p in particles])


def finite_difference_case(e: float, stages: int, epsilon: float) -> Dict[str, Any]:
    t = 20*math.pi
    sim = planets(e, stages, epsilon)
    var = sim.add_variation()
    var.particles[1].vy = 1.0
    sim.integrate(t)
    delta = 1e-8
    ends = []
    for sign in (1.0, -1.0):
        other = planets(e, stages, epsilon, sign*delta)
        other.integrate(t)
        ends.append(state(other.particles))
    fd = (ends[0] - ends[1])/(2*delta)
    return {"e": e, "s": stages, "epsilon": epsilon,
            "relative": float(np.abs(state(var.particles) - fd).max()/np.abs(fd).max()),
            "steps": int(sim.integrator.n_steps)}


def regular(family: str):
    import rebound
    sim = rebound.Simulation()
    sim.add(m=1)
    sim.add(m=1e-3, a=1.5, e=0.1, inc=0.1)
    sim.add(m=1e-3, a=15., e=0.1, inc=0.1)
    if family == "pfvi":
        _pfvi(sim)
    else:
        sim.integrator = family
    return sim


def chaotic(family: str, M: float = 0.0, epsilon: Optional[float] = None):
    import rebound
    sim = rebound.Simulation()
    sim.add(m=1.)
    sim.add(m=1.e-4, P=1.)
    sim.add(m=1.e-4, P=1.17, M=M)
    sim.move_to_com()
    if family == "pfvi":
        _pfvi(sim, **({} if epsilon is None else {"epsilon": epsilon}))
    else:
        sim.integrator = family
        if epsilon is not None:
            sim.integrator.epsilon = epsilon
    return sim


def megno_case(kind: str, family: str) -> Dict[str, Any]:
    sim = regular(family) if kind == "regular" else chaotic(family)
    sim.init_megno(seed=0)
    orbits = 1000
    t_end = orbits*(sim.particles[1].P)
    start = time.perf_counter()
    sim.integrate(t_end)
    return {"kind": kind, "family": family, "orbits": orbits, "megno": float(sim.megno()),
            "lyapunov": float(sim.lyapunov()), "wall_s": time.perf_counter() - start}


def lyapunov_member(family: str, epsilon: float, M: float, t_end: float) -> Dict[str, Any]:
    sim = chaotic(family, M, epsilon)
    sim.init_megno(seed=0)
    start = time.perf_counter()
    refused = None
    try:
        sim.integrate(t_end)
    except RuntimeError as error:  # a near-collision of the point masses (pfvi: a step below t's rounding)
        refused = f"t = {sim.t:.6g}: {error}"
    return {"family": family, "epsilon": epsilon, "M": M, "lyapunov": float(sim.lyapunov()),
            "megno": float(sim.megno()), "wall_s": time.perf_counter() - start, "refused": refused}


def cost_case(family: str, stages: int) -> Dict[str, Any]:
    result: Dict[str, Any] = {"family": family, "s": stages}
    for megno in (False, True):
        walls = []
        for _ in range(3):
            sim = regular(family)
            if family == "pfvi":
                sim.integrator.stages = stages
            if megno:
                sim.init_megno(seed=0)
            start = time.perf_counter()
            sim.integrate(COST_T)
            walls.append(time.perf_counter() - start)
        key = "megno" if megno else "plain"
        result[key + "_wall_s"] = min(walls)
        pfvi = family == "pfvi"
        result[key + "_evaluations"] = int(sim.integrator.n_force_evaluations) if pfvi else None
        result[key + "_steps"] = int(sim.integrator.n_steps) if pfvi else None
        result[key + "_variational_evaluations"] = int(sim.integrator.n_variational_evaluations) if pfvi else None
    return result


def run(workers: int, scheduler: Optional[str]) -> Tuple[Dict[str, List[Dict[str, Any]]], str]:
    from rebound_pfvi import runner
    tasks, keys = [], []
    for e in (0.5, 0.9):
        for stages in (4, 8):
            for epsilon in (1e-6, 1e-10):
                tasks.append(runner.Task(finite_difference_case, (e, stages, epsilon)))
                keys.append("A")
    for kind in ("regular", "chaotic"):
        for family in ("pfvi", "ias15"):
            tasks.append(runner.Task(megno_case, (kind, family)))
            keys.append("B")
    for family, epsilon in (("ias15", 1e-11), ("ias15", 1e-9), ("pfvi", 1e-6), ("pfvi", 1e-10)):
        for k in range(ENSEMBLE):
            tasks.append(runner.Task(lyapunov_member, (family, epsilon, 2*math.pi*k/ENSEMBLE, 2000.0)))
            keys.append("C")
    for family, stages in (("pfvi", 4), ("pfvi", 8), ("ias15", 0)):
        tasks.append(runner.Task(cost_case, (family, stages)))
        keys.append("D")
    if scheduler:
        outcomes, workers, where = runner.run_tasks_dask(tasks, scheduler)
    else:
        outcomes = runner.run_tasks(tasks, workers=workers)
        where = f"{workers} worker processes"
    out: Dict[str, List[Dict[str, Any]]] = {"A": [], "B": [], "C": [], "D": []}
    for key, (status, result) in zip(keys, outcomes):
        if status != "ok":
            raise RuntimeError(f"part {key}: {status}: {result}")
        out[key].append(result)
    return out, where


def markdown(r: Dict[str, List[Dict[str, Any]]], where: str, seconds: float, command: str) -> str:
    import rebound
    out = ["# Variational particles: checks and cost", "",
           f"Generated by `{command}` ({seconds:.0f} s on {where}; REBOUND {rebound.__version__}, "
           f"Python {platform.python_version()}, {platform.machine()}). What each part runs: the script's "
           "docstring; what it means: [megno.md](megno.md).", "",
           "## A. Tangent map against finite differences (10 inner orbits, delta 1e-8)", "",
           "| e | s | epsilon | steps | largest difference / largest derivative |", "|---|---|---|---|---|"]
    for x in r["A"]:
        out.append(f"| {x['e']} | {x['s']} | {x['epsilon']:g} | {x['steps']} | {x['relative']:.1e} |")
    out += ["", "## B. MEGNO after 1000 inner orbits", "",
            "| system | integrator | MEGNO | Lyapunov exponent | wall time [s] |", "|---|---|---|---|---|"]
    for x in r["B"]:
        out.append(f"| {x['kind']} | {x['family']} | {x['megno']:.3f} | {x['lyapunov']:.3g} | {x['wall_s']:.2f} |")
    out += ["", f"## C. Lyapunov exponent of the chaotic pair: ensemble of {ENSEMBLE} starts to t = 2000", "",
            "The median is the figure compared: a start whose planets pass very close can give one run a "
            "Lyapunov exponent many times the others' (its mean then follows that one run).", "",
            "| integrator | epsilon | median | relative to IAS15 1e-11 (median) | mean | standard error | "
            "largest | wall time, sum [s] |", "|---|---|---|---|---|---|---|---|"]
    groups: Dict[Tuple[str, float], List[Dict[str, Any]]] = {}
    # A start that any run did not finish (a near-collision: the point
    # masses pass within 1e-9) is left out of every line, so that each mean
    # is over the same starts.
    refused = {x["M"] for x in r["C"] if x["refused"]}
    for x in r["C"]:
        if x["M"] not in refused:
            groups.setdefault((x["family"], x["epsilon"]), []).append(x)
    reference = statistics.median(x["lyapunov"] for x in groups[("ias15", 1e-11)])
    notes = [f"{x['family']} epsilon {x['epsilon']:g}, start M = {x['M']:.4f}: {x['refused'].split(' (it is')[0]}"
             for x in r["C"] if x["refused"]]
    for (family, epsilon), xs in groups.items():
        values = [x["lyapunov"] for x in xs]
        mean = statistics.mean(values)
        median = statistics.median(values)
        out.append(f"| {family} | {epsilon:g} | {median:.4f} | {median/reference:.3f} | {mean:.4f} | "
                   f"{statistics.stdev(values)/math.sqrt(len(values)):.4f} | {max(values):.3g} | "
                   f"{sum(x['wall_s'] for x in xs):.1f} |")
    out += ["", f"{ENSEMBLE - len(refused)} starts; left out (a run did not finish): " + ("; ".join(notes) or "none")]
    out += ["", f"## D. Cost of init_megno() (regular pair to t = {COST_T:g}, best of 3)", "",
            "| integrator | steps | wall without [s] | with [s] | ratio | force evaluations without | with | "
            "of which for the variational particles alone |", "|---|---|---|---|---|---|---|---|"]
    for x in r["D"]:
        name = f"pfvi s={x['s']}" if x["family"] == "pfvi" else x["family"]
        cells = [x['plain_steps'], x['plain_evaluations'], x['megno_evaluations'], x['megno_variational_evaluations']]
        steps, without, with_, alone = ("" if c is None else c for c in cells)
        out.append(f"| {name} | {steps} | {x['plain_wall_s']:.3f} | {x['megno_wall_s']:.3f} | "
                   f"{x['megno_wall_s']/x['plain_wall_s']:.2f} | {without} | {with_} | {alone} |")
    return "\n".join(out) + "\n"


def main(argv: Optional[Sequence[str]] = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--output", default=None, help="the markdown page (docs/megno_checks.md); default: stdout")
    parser.add_argument("--workers", type=int, default=os.cpu_count() or 1)
    parser.add_argument("--scheduler", default=None, help="a Dask scheduler's address (needs the [dask] extra)")
    args = parser.parse_args(argv)
    start = time.perf_counter()
    results, where = run(args.workers, args.scheduler)
    command = "python -P benchmarks/variational.py" + (f" --output {args.output}" if args.output else "")
    page = markdown(results, where, time.perf_counter() - start, command)
    if args.output:
        with open(args.output, "w") as f:
            f.write(page)
    else:
        sys.stdout.write(page)


if __name__ == "__main__":
    main()
