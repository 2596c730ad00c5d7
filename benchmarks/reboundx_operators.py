"""REBOUNDx operators, ODEs, forces and recorders with pfvi against IAS15
(issue 40, item 2), with and without outputs.

Each effect is added as a REBOUND user adds it (`rx.add_operator(op)`,
`rx.add_force(force)`, `rx.initialize_spin_ode(force)`) and run once with a
single integrate() call and with `for t in times: sim.integrate(t)` at 40
and 700 evenly spaced outputs, with pfvi at its defaults and IAS15 at its
defaults. The table gives the measured quantity, its exact value where one
is known, and each run's relative difference from the exact value (or from
IAS15's single call where none is known).

    python -P benchmarks/reboundx_operators.py             # about 30 s
    python -P benchmarks/reboundx_operators.py --markdown  # the table of docs/reboundx.md
"""
import argparse
import math

import rebound
import reboundx

import rebound_pfvi  # noqa: F401  (registers "pfvi"; makes rx.add_operator place operators for it)

T_END = 500.0
TAU = -1e3  # the migration and mass-loss e-folding times
TAU_SPIN = 0.1  # tides_spin's time lag


def _sun_jupiter(integrator):
    sim = rebound.Simulation()
    sim.integrator = integrator
    sim.add(m=1.0)
    sim.add(m=1e-3, a=1.0)
    sim.move_to_com()
    return sim


def migration(integrator):
    """modify_orbits_direct, tau_a = -1e3 on a Jupiter at a = 1: a = exp(-t/|tau|)."""
    sim = _sun_jupiter(integrator)
    rx = reboundx.Extras(sim)
    op = rx.load_operator("modify_orbits_direct")
    rx.add_operator(op)
    sim.particles[1].params["tau_a"] = TAU
    return sim, (lambda s: s.particles[1].a), math.exp(T_END / TAU)


def mass_loss(integrator):
    """modify_mass, tau_mass = -1e3 on the star: m = exp(-t/|tau|)."""
    sim = _sun_jupiter(integrator)
    rx = reboundx.Extras(sim)
    op = rx.load_operator("modify_mass")
    rx.add_operator(op)
    sim.particles[0].params["tau_mass"] = TAU
    return sim, (lambda s: s.particles[0].m), math.exp(T_END / TAU)


def tides_spin(integrator):
    """tides_spin (an ODE for the spins): a hot Jupiter's spin Omega_z after
    T_END/10 (it spins down towards synchronous rotation)."""
    sim = rebound.Simulation()
    sim.integrator = integrator
    sim.add(m=1.0, r=0.005)
    sim.add(m=1e-3, a=0.05, e=0.1, r=5e-4)
    sim.move_to_com()
    rx = reboundx.Extras(sim)
    force = rx.load_force("tides_spin")
    rx.add_force(force)
    p = sim.particles[1]
    p.params["k2"] = 0.3
    p.params["tau"] = TAU_SPIN
    p.params["I"] = 0.25 * p.m * p.r**2
    n = p.n
    p.params["Omega"] = rebound.spherical_to_xyz(magnitude=3.0 * n, theta=0.0, phi=0.0)
    rx.initialize_spin_ode(force)
    return sim, (lambda s: s.particles[1].params["Omega"][2]), None


def gr_potential(integrator):
    """gr_potential (a force): Mercury's x at the end."""
    sim = rebound.Simulation()
    sim.integrator = integrator
    sim.add(m=1.0)
    sim.add(m=1.66e-7, a=0.387, e=0.206)
    sim.move_to_com()
    rx = reboundx.Extras(sim)
    force = rx.load_force("gr_potential")
    rx.add_force(force)
    force.params["c"] = 1e2  # strong, so that the precession shows in T_END
    return sim, (lambda s: s.particles[1].x - s.particles[0].x), None


def track_min_distance(integrator):
    """track_min_distance (a recorder): a comet e = 0.8 crossing Jupiter's
    orbit, its closest approach to the star (particle 0, the default), as
    sampled at the step ends the recorder sees."""
    sim = rebound.Simulation()
    sim.integrator = integrator
    sim.add(m=1.0)
    sim.add(m=1e-3, a=1.0, name="jupiter")
    sim.add(m=0.0, a=1.5, e=0.8, inc=0.05, omega=1.0, f=2.0)
    sim.move_to_com()
    rx = reboundx.Extras(sim)
    op = rx.load_operator("track_min_distance")
    rx.add_operator(op)
    sim.particles[2].params["min_distance"] = 10.0
    return sim, (lambda s: s.particles[2].params["min_distance"]), None


EFFECTS = {"migration (modify_orbits_direct)": migration, "mass loss (modify_mass)": mass_loss,
           "tides_spin (ODE)": tides_spin, "gr_potential (force)": gr_potential,
           "track_min_distance (recorder)": track_min_distance}
OUTPUTS = (1, 40, 700)


def run(build, integrator, outputs):
    """The measured value (None if the integrator refused the run), the exact
    one, and the steps taken."""
    sim, measure, exact = build(integrator)
    t_end = T_END / 10.0 if build is tides_spin else T_END
    try:
        for k in range(outputs):
            sim.integrate(t_end * (k + 1) / outputs)
    except RuntimeError as error:
        print(f"  ({integrator}, {outputs} outputs, refused at t = {sim.t:.6g}: {str(error)[:120]})")
        return None, exact, sim.steps_done
    steps = sim.integrator.n_steps if integrator == "pfvi" else sim.steps_done
    return measure(sim), exact, steps


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--markdown", action="store_true", help="print the docs table")
    args = parser.parse_args(argv)
    rows = []
    for label, build in EFFECTS.items():
        ias15_single, exact, _ = run(build, "ias15", 1)
        reference = exact if exact is not None else ias15_single
        cells = []
        for integrator in ("ias15", "pfvi"):
            for outputs in OUTPUTS:
                value, _, steps = run(build, integrator, outputs)
                rel = math.nan if value is None else abs(value - reference) / abs(reference)
                cells.append((integrator, outputs, value, rel, steps))
        rows.append((label, exact, ias15_single, cells))
    if args.markdown:
        head = " | ".join(f"{i} {o} out." for i in ("IAS15", "pfvi") for o in OUTPUTS)
        print(f"| effect | exact | {head} |")
        print("|---|---|" + "---|" * (2 * len(OUTPUTS)))
        for label, exact, ias15_single, cells in rows:
            ex = f"{exact:.6g}" if exact is not None else f"(IAS15: {ias15_single:.6g})"
            print(f"| {label} | {ex} | " + " | ".join(("refused" if c[2] is None else f"{c[3]:.1e}") + f" ({c[4]})" for c in cells) + " |")
        return
    for label, exact, ias15_single, cells in rows:
        print(label, "exact" if exact is not None else "reference IAS15 single call",
              exact if exact is not None else ias15_single)
        for integrator, outputs, value, rel, steps in cells:
            shown = "refused" if value is None else f"{value:.12g}"
            print(f"  {integrator:6s} {outputs:4d} outputs: {shown}  relative difference {rel:.2e}  steps {steps}")


if __name__ == "__main__":
    main()
