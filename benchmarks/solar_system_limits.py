"""What limits the solar system's agreement with DE421: each body's largest
distance from DE421 over the outputs, for the model with and without GR and
with the Earth's J2, each integrated by pfvi (its defaults) and IAS15 (its
default epsilon).

    python3 -P benchmarks/solar_system_limits.py [--epoch 2000-01-01] [--years 10] [--every 10] [--interleave 3]

Needs the ephemeris extra (pip install ".[ephemeris]") and, for GR and J2,
the reboundx extra. The models:

- Newtonian: scenes.solar_system(gr=False), point masses with DE421's GM;
- GR: REBOUNDx's gr_full (scenes.solar_system's default where REBOUNDx is);
- GR + Earth J2: also REBOUNDx's gravitational_harmonics on the Earth,
  J2 = 1.0826e-3 and R_eq = 6378.137 km (IERS values; DE421 models the
  Earth's figure through its J2 too), about the z axis of DE421's frame
  (ICRF, the Earth's pole at J2000, so precession of 50"/yr is left out).

What no model here has: the asteroids (DE421 integrates 343 of them and
Ceres, Pallas and Vesta with their own GM, GMAST1-3 in its constants, but
gives none of their states), the Moon's figure and librations, and the
Earth's tides on the Moon; the asteroids' momentum shows as the drift of the
11 bodies' barycentre from DE421's origin, printed first.

--interleave N then times pfvi's defaults and IAS15's with GR, as the
model is integrated with outputs, alternately N times each in this one
process (so that both see the same load), and prints each one's best and
median wall time and their ratio.
"""
import argparse
import time

from rebound_pfvi import scenes

EARTH_J2 = 1.0826e-3
EARTH_R_EQ_KM = 6378.137
MODELS = ("Newtonian", "GR", "GR + Earth J2")


def build(epoch, model):
    sim = scenes.solar_system(epoch, gr=model != "Newtonian")
    if model == "GR + Earth J2":
        rebx = sim._extras_ref
        harmonics = rebx.load_force("gravitational_harmonics")
        rebx.add_force(harmonics)
        earth = sim.particles["Earth"]
        earth.params["J2"] = EARTH_J2
        earth.params["R_eq"] = EARTH_R_EQ_KM / scenes.AU_KM
    return sim


def run(scene, model, integrator):
    """(wall time with the outputs, {body: largest km from DE421}, {body: km from IAS15 at 1e-11})."""
    import rebound_pfvi  # noqa: F401

    states = {}
    for name, epsilon in (("run", None), ("tight", scenes.REFERENCE_EPSILON)):
        sim = build(scene.epoch, model)
        sim.integrator = integrator if epsilon is None else "ias15"
        if epsilon is not None:
            sim.integrator.epsilon = epsilon
        out = []
        tick = time.perf_counter()
        for t in scene.output_times():
            sim.integrate(t, exact_finish_time=1)
            out.append([(p.x, p.y, p.z) for p in sim.particles])
        states[name] = (time.perf_counter() - tick, out)
    wall, out = states["run"]
    reference = {"de421": scenes.de421_states(scene.epoch, [t * 365.25 for t in scene.output_times()])[0].tolist(),
                 "outputs": states["tight"][1]}
    errors = scene.output_errors(out, reference)
    return wall, errors["DE421"], errors["IAS15"]


def interleaved(scene, repeats):
    """Best and median wall times of pfvi and IAS15 (GR, their defaults), run alternately."""
    import statistics

    import rebound_pfvi  # noqa: F401

    walls = {"pfvi": [], "ias15": []}
    for _ in range(repeats):
        for integrator in walls:
            sim = build(scene.epoch, "GR")
            sim.integrator = integrator
            tick = time.perf_counter()
            for t in scene.output_times():
                sim.integrate(t, exact_finish_time=1)
                [(p.x, p.y, p.z) for p in sim.particles]
            walls[integrator].append(time.perf_counter() - tick)
    print(f"\nWall time with the outputs, GR, each integrator at its defaults, run alternately {repeats} times:\n")
    print("| integrator | best [s] | median [s] |\n|---|---|---|")
    for integrator, w in walls.items():
        print(f"| {integrator} | {min(w):.3g} | {statistics.median(w):.3g} |")
    print(f"\npfvi / IAS15: {min(walls['pfvi']) / min(walls['ias15']):.2f} (best), "
          f"{statistics.median(walls['pfvi']) / statistics.median(walls['ias15']):.2f} (median)")


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--epoch", default="2000-01-01", help="ISO date (TDB) or Julian date (default 2000-01-01)")
    parser.add_argument("--years", type=float, default=10.0)
    parser.add_argument("--every", type=float, default=10.0, help="days between outputs")
    parser.add_argument("--interleave", type=int, default=0, help="time pfvi and IAS15 alternately N times each")
    args = parser.parse_args()
    scene = scenes.SolarSystem(epoch=args.epoch, years=args.years, every=args.every, gr=False)
    bodies = scenes.DE421_BODIES
    print(f"{scene.describe().replace(', Newtonian (no GR)', '')}.\n")
    # DE421's origin is the barycentre with the asteroids; the model's is without them.
    com = scenes.solar_system(scene.epoch, gr=False).com()
    print(f"The 11 bodies' barycentre at the epoch: {(com.x**2 + com.y**2 + com.z**2) ** 0.5 * scenes.AU_KM:.3g} km "
          f"from DE421's, moving from it at {(com.vx**2 + com.vy**2 + com.vz**2) ** 0.5 * scenes.AU_KM:.3g} km/yr.\n")
    print("Each body's largest distance from DE421 over the outputs [km]; the last column: the largest distance of "
          "any body from IAS15 at epsilon 1e-11 with the same model [km].\n")
    print("| model | integrator | wall [s] | " + " | ".join(bodies) + " | from IAS15 |")
    print("|---|---|---|" + "---|" * len(bodies) + "---|")
    for model in MODELS:
        for integrator in ("pfvi", "ias15"):
            wall, de421, ias15 = run(scene, model, integrator)
            print(f"| {model} | {integrator} | {wall:.3g} | " + " | ".join(f"{de421[b]:.3g}" for b in bodies)
                  + f" | {max(ias15.values()):.2g} |", flush=True)
    if args.interleave:
        interleaved(scene, args.interleave)


if __name__ == "__main__":
    main()
