"""A fixed set of pfvi runs, one per step mode, reduced to a digest of every
particle's doubles and t at the end: the record that a refactoring of the core
must reproduce to the bit (tests/test_trajectory_record.py).

    python -P tests/trajectory_record.py    # rewrite tests/data/trajectories.json

Rewrite it only for a change that is meant to change trajectories, and say
which runs changed and why in the commit.
"""
import hashlib
import json
import os
import struct

import rebound

import rebound_pfvi  # noqa: F401  (registers "pfvi")

RECORD = os.path.join(os.path.dirname(os.path.abspath(__file__)), "data", "trajectories.json")


def system():
    sim = rebound.Simulation()
    sim.add(m=1.0)
    sim.add(m=1e-3, a=1.0, e=0.3, inc=0.1)
    sim.add(m=1e-4, a=1.8, e=0.1, inc=0.3, Omega=1.0, f=2.0)
    sim.move_to_com()
    return sim


def drag(simp):
    p = simp.contents.particles[1]
    p.ax -= 0.01 * p.vx
    p.ay -= 0.01 * p.vy
    p.az -= 0.01 * p.vz


# The seed's scheme as the record was taken with it (the defaults then):
# pinned, so that the record keeps testing it whatever the defaults become.
SEED = {"fitting": "phase", "frequency": "curvature", "centre": "origin"}
# The fitting of issue 14, each frequency about its partner.
EXACT = {"fitting": "exact", "centre": "partner"}


def runs():
    """name -> (fields, steps, dt, velocity_dependent)"""
    table = {}
    for s in range(2, 7):
        for fitting in ("phase", "phase-literal", "none"):
            table[f"fixed-s{s}-{fitting}"] = ({**SEED, "stages": s, "fitting": fitting, "epsilon": 0.0}, 60, 0.01,
                                              False)
    for s in (2, 4):
        table[f"fixed-s{s}-omega"] = ({**SEED, "stages": s, "frequency": "fixed", "omega": 2.0, "epsilon": 0.0}, 60,
                                      0.01, False)
        for control in ("seed", "reversible"):
            for fitting in ("phase", "none"):
                table[f"{control}-s{s}-{fitting}"] = ({**SEED, "stages": s, "fitting": fitting, "epsilon": 1e-7,
                                                      "step_control": control}, 40, 0.01, False)
    for s in (2, 3):
        table[f"drag-s{s}"] = ({**SEED, "stages": s, "epsilon": 0.0}, 60, 0.01, True)
    table["backward-s4"] = ({**SEED, "stages": 4, "epsilon": 1e-7, "step_control": "reversible"}, 40, -0.01, False)
    # Added with fitting 'exact' (issue 14).
    for s in (2, 3, 4, 6):
        for frequency in ("curvature", "radial", "mean-motion"):
            table[f"fixed-s{s}-exact-{frequency}"] = ({**EXACT, "stages": s, "frequency": frequency, "epsilon": 0.0},
                                                     60, 0.01, False)
    table["fixed-s4-exact-barycentre"] = ({**EXACT, "stages": 4, "frequency": "radial", "centre": "barycentre",
                                           "epsilon": 0.0}, 60, 0.01, False)
    for s in (2, 4):
        table[f"reversible-s{s}-exact"] = ({**EXACT, "stages": s, "frequency": "radial", "epsilon": 1e-7,
                                            "step_control": "reversible"}, 40, 0.01, False)
        table[f"drag-s{s}-exact"] = ({**EXACT, "stages": s, "frequency": "radial", "epsilon": 0.0}, 60, 0.01, True)
    return table


def digest(name):
    fields, steps, dt, velocity_dependent = runs()[name]
    sim = system()
    sim.integrator = "pfvi"
    for key, value in fields.items():
        setattr(sim.integrator, key, value)
    sim.dt = dt
    if velocity_dependent:
        sim.additional_forces = drag
        sim.force_is_velocity_dependent = 1
    sim.steps(steps)
    numbers = [sim.t] + [getattr(p, f) for p in sim.particles
                         for f in ("x", "y", "z", "vx", "vy", "vz", "ax", "ay", "az", "m")]
    return hashlib.sha256(struct.pack(f"<{len(numbers)}d", *numbers)).hexdigest()


if __name__ == "__main__":
    with open(RECORD, "w") as f:
        json.dump({name: digest(name) for name in runs()}, f, indent=1, sort_keys=True)
        f.write("\n")
    print(f"wrote {RECORD}")
