"""Error against run time for an eccentric orbit: pfvi beside REBOUND's integrators.

A starting point for your own comparisons. Run it with

    python3 examples/compare_eccentric.py

It builds a Kepler scene with astropy units, sweeps every integrator's
accuracy knob (pfvi's and IAS15's epsilon, BS's tolerance, the steps per
period of WHFast, LEAPFROG, TRACE and MERCURIUS), prints an astropy table and writes the
markdown page, the JSON/CSV data and the work-precision PNG to
./compare-example/ (the same files as `rebound-pfvi compare`).
"""
import astropy.units as u

from rebound_pfvi import compare, report, scenes


def main():
    # A Jupiter-mass planet on an e = 0.9 orbit at 2 AU around a 0.8 Msun star.
    scene = scenes.Kepler(e=0.9, a=2 * u.AU, mass=0.8 * u.Msun, m=1 * u.Mjup, periods=20)
    print(f"{scene.describe()} - period {scene.period_quantity().to(u.day):.1f}")

    # The default sweep, and settings of your own beside it: an option not
    # named is pfvi's default (rebound_pfvi.DEFAULTS), e.g. s = 6 at epsilon
    # 1e-9, which the quick sweep does not run (its s = 6 line has 1e-8 and 1e-10):
    settings = compare.default_settings(scene, "quick")
    settings.append(compare.Setting("pfvi", 1e-9, (("stages", 6),)))

    results = compare.run(scene, settings, repeats=3)  # a local process pool; Ctrl-C keeps finished runs
    table = results.table()  # astropy QTable: wall_time in s, position_error in AU (and km)
    table.sort("wall_time")
    shown = table["line", "knob", "value", "steps", "wall_time", "energy_error_max", "position_error_km"]
    for name, spec in (("value", ".0e"), ("wall_time", ".3g"), ("energy_error_max", ".1e"),
                       ("position_error_km", ".2e")):
        shown[name].info.format = spec
    shown.pprint(max_lines=-1, max_width=-1)  # every row and column: nothing hidden behind "..."

    paths = report.write(results, "compare-example", command="python3 examples/compare_eccentric.py")
    print("wrote", ", ".join(paths.values()))

    # Your own REBOUND simulation with pfvi, as with any integrator (rebound_pfvi is
    # imported above, which registers "pfvi"):
    sim = scene.build()
    sim.integrator = "pfvi"             # its defaults: s = 8, symmetric steps
    sim.integrator.epsilon = 1e-8
    sim.integrate(scene.t_end)
    print("pfvi: steps", sim.integrator.n_steps, "trial steps", sim.integrator.n_attempts)


# The guard matters: the sweep's worker processes are started with "spawn" and
# import this file; without it each would rerun the sweep.
if __name__ == "__main__":
    main()
