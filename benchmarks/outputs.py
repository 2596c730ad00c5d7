"""Outputs that do not change the answer (issue 36, item 1).

Each page's scene (rebound_pfvi/scenes.py) and an Encke-like comet among
Venus, Earth, Mars and Jupiter run at pfvi's defaults to their end time
once with a single integrate() call and once with `for t in times:
sim.integrate(t)` at 10, 100 and 1000 outputs per period and at 300 random
times; the table gives each run's position error at the end (against IAS15
at the scene's reference tolerance) over the single call's, and its steps,
retaken steps and output steps.

    python -P benchmarks/outputs.py                   # every scene (about 1 min on 2 cores)
    python -P benchmarks/outputs.py --scenes kepler,comet --cadences 10,100
    python -P benchmarks/outputs.py --accuracy      # the outputs' own error (about 1 min)
"""
import argparse
import math
import random
import time

import rebound

import rebound_pfvi  # noqa: F401  (registers "pfvi")
from rebound_pfvi import scenes


class Encke(scenes.Scene):
    """An Encke-like comet (a = 2.2 AU, e = 0.85) among Venus, Earth, Mars and
    Jupiter; 20 comet periods."""

    name = "encke"
    periods = 20.0

    def build(self, counter=None):
        sim = scenes.new_simulation()
        sim.add(m=1.0)
        for m, a, e, M in ((2.45e-6, 0.723, 0.007, 1.0), (3.0e-6, 1.0, 0.017, 2.0), (3.2e-7, 1.524, 0.093, 3.0),
                           (9.55e-4, 5.203, 0.048, 4.0)):
            sim.add(m=m, a=a, e=e, M=M)
        sim.add(m=0.0, a=2.2, e=0.85, inc=math.radians(12.0), omega=3.0, M=0.5)
        sim.move_to_com()
        return sim

    @property
    def period(self):
        return 2.0*math.pi*math.sqrt(2.2**3/scenes.rebound_G())


SCENES = ["kepler", "comet", "triple", "jupiter-comet", "retrograde", "sungrazer", "circumbinary",
          "outer-solar-system", "periodic-box", "encke"]


def make(name):
    return Encke() if name == "encke" else scenes.make(name)


def times_of(scene, cadence, seed=1):
    T, P = scene.t_end, scene.period
    if cadence == "random":
        rng = random.Random(seed)
        return sorted(rng.uniform(0.0, T) for _ in range(300)) + [T]
    if cadence == "one":
        return [T]
    n = max(1, int(round(T/P*int(cadence))))
    return [T*(k + 1)/n for k in range(n - 1)] + [T]


def run(scene, times):
    sim = scene.build()
    sim.integrator = "pfvi"
    start = time.perf_counter()
    for t in times:
        sim.integrate(t)
    return sim, time.perf_counter() - start


def accuracy(scene, per_period=10):
    """The outputs' own error: the largest distance of a body from IAS15's
    (epsilon 1e-11) at the output times, over the largest at the run's own
    step ends (the same run sampled with exact_finish_time = 0)."""
    times = times_of(scene, str(per_period))

    def largest(exact):
        sim = scene.build()
        sim.integrator = "pfvi"
        ref = scene.build()
        ref.integrator = "ias15"
        ref.integrator.epsilon = 1e-11
        worst = 0.0
        for t in times:
            sim.integrate(t, exact_finish_time=exact)
            ref.integrate(sim.t, exact_finish_time=1)
            worst = max(worst, max(math.dist((p.x, p.y, p.z), (q.x, q.y, q.z))
                                   for p, q in zip(sim.particles, ref.particles)))
        return worst

    shown, own = largest(1), largest(0)
    return shown, own


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--scenes", default=",".join(SCENES))
    parser.add_argument("--cadences", default="10,100,1000,random", help="outputs per period, or 'random'")
    parser.add_argument("--accuracy", action="store_true",
                        help="instead: each output's error against IAS15 over the run's own at its step ends")
    args = parser.parse_args()
    if args.accuracy:
        print("| scene | outputs (10/period): largest error | the run's step ends: largest error | ratio |")
        print("|---|---|---|---|")
        for name in args.scenes.split(","):
            shown, own = accuracy(make(name))
            print(f"| {name} | {shown:.2g} AU | {own:.2g} AU | {shown/own:.2f} |", flush=True)
        return
    cadences = args.cadences.split(",")
    print("| scene | one call: error, steps | " + " | ".join(f"{c}{'/period' if c != 'random' else ''}: "
                                                           "error ratio, steps, retaken, outputs, wall"
                                                           for c in cadences) + " |")
    print("|---|---|" + "---|"*len(cadences))
    for name in args.scenes.split(","):
        scene = make(name)
        reference = scene.reference()
        one, wall = run(scene, times_of(scene, "one"))
        base = scene.position_error(one, reference)
        cells = [f"{base:.2g} AU, {one.integrator.n_steps} ({wall:.2f} s)"]
        for cadence in cadences:
            sim, wall = run(scene, times_of(scene, cadence))
            ig = sim.integrator
            error = scene.position_error(sim, reference)
            cells.append(f"{error/base:.3g}, {ig.n_steps}, {ig.n_rejected - one.integrator.n_rejected:+d}, "
                         f"{getattr(ig, 'n_outputs', '-')}, {wall:.2f} s")
        print(f"| {name} | " + " | ".join(cells) + " |", flush=True)


if __name__ == "__main__":
    main()
