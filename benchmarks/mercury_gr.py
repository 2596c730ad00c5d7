"""Mercury's perihelion advance with REBOUNDx's "gr" force: pfvi against IAS15.

    python3 -P benchmarks/mercury_gr.py [--periods 415] [--repeats 3]

Needs the reboundx extra (pip install ".[reboundx]"). For each integrator
setting: the advance of the perihelion longitude over the run (scene
`mercury-gr`, 415 orbits = 99.95 yr by default), its difference from IAS15's,
the advance the same setting gives with the force off (the integrator's own
precession), and the best of `repeats` wall times of ``sim.integrate``. The
secular rate is also fitted to IAS15's perihelion longitude sampled 2000
times, free of the short-period terms that the end point carries.
"""
import argparse
import math
import time

from rebound_pfvi import scenes

SETTINGS = [("ias15", 1e-9, {}), ("ias15", 1e-7, {})] + [
    ("pfvi", eps, {"stages": 4, "fitting": fitting}) for fitting in ("phase", "none")
    for eps in (1e-6, 1e-7, 1e-8, 1e-9)] + [("whfast", 100, {}), ("whfast", 1000, {})]
ARCSEC = math.pi / 180.0 / 3600.0


def newtonian(scene):
    sim = scenes.new_simulation()
    sim.add(m=1.0)
    sim.add(m=scene.MASS, a=scene.A, e=scene.E)
    sim.move_to_com()
    return sim


def run(scene, family, knob, options, gr=True):
    sim = scene.build() if gr else newtonian(scene)
    sim.integrator = family
    if family == "whfast":
        sim.dt = scene.period / knob
    else:
        sim.integrator.epsilon = knob
        sim.dt = scene.period / (10.0 if family == "pfvi" else 100.0)
    for name, value in options.items():
        setattr(sim.integrator, name, value)
    start = scene.perihelion_longitude(sim)
    tick = time.perf_counter()
    sim.integrate(scene.t_end)
    wall = time.perf_counter() - tick
    return math.remainder(scene.perihelion_longitude(sim) - start, 2.0 * math.pi), wall


def fitted_rate(scene, samples=2000):
    import numpy as np

    sim = scene.build()
    sim.integrator = "ias15"
    times = np.linspace(0.0, scene.t_end, samples)
    angles = []
    for t in times:
        sim.integrate(t)
        angles.append(scene.perihelion_longitude(sim))
    return np.polyfit(times, np.unwrap(angles), 1)[0]


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--periods", type=float, default=415.0, help="Mercury orbits (default 415: 99.95 yr)")
    parser.add_argument("--repeats", type=int, default=3, help="timed runs, best kept (default 3)")
    args = parser.parse_args()
    scene = scenes.MercuryGR(periods=args.periods)
    century = 100.0 / scene.t_end
    a, e = scene.A, scene.E
    c = scenes.SPEED_OF_LIGHT_AU_YR
    textbook = 6 * math.pi * scenes.rebound_G() / (c * c * a * (1 - e * e)) / scene.period
    print(f"{scene.describe()}")
    print(f"textbook secular rate 6 pi GM / (c^2 a (1 - e^2)) per orbit: {textbook * 100 / ARCSEC:.3f} arcsec/century")
    print(f"IAS15, fitted to 2000 samples: {fitted_rate(scene) * 100 / ARCSEC:.3f} arcsec/century\n")
    print("| integrator | knob | advance [rad] | [arcsec/century] | minus IAS15 1e-9 [rad] | force off [rad] "
          "| gr part minus IAS15's [rad] | wall [s] |")
    print("|---|---|---|---|---|---|---|---|")
    reference = None
    for family, knob, options in SETTINGS:
        walls, advance = [], None
        for _ in range(args.repeats):
            advance, wall = run(scene, family, knob, options)
            walls.append(wall)
        own, _ = run(scene, family, knob, options, gr=False)
        if reference is None:
            reference = advance
        label = family + "".join(f" {k}={v}" for k, v in options.items())
        print(f"| {label} | {knob:g} | {advance:.10e} | {advance * century / ARCSEC:.4f} | {advance - reference:.2e} "
              f"| {own:.2e} | {advance - own - reference:.2e} | {min(walls):.3f} |", flush=True)


if __name__ == "__main__":
    main()
