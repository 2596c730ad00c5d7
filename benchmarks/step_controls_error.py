"""What epsilon means under each step control: the position error after 3
orbits of a Kepler pair (m = 1e-3) against IAS15 at 1e-13, with the steps
taken, for 'seed' (K&V), 'reversible' and 'symmetric' (the default). The
figures in help(sim.integrator)'s step_control text come from here.

    python -P benchmarks/step_controls_error.py     # a few seconds
"""
import math
import sys
from pathlib import Path

import rebound_pfvi  # noqa: F401

sys.path.insert(0, str(Path(__file__).resolve().parent))

from stages import two_body as kepler  # noqa: E402  (Sun and a planet of 1e-3, a = 1)

CASES = ((0.5, 2, 1e-6), (0.99, 2, 1e-6), (0.99, 4, 1e-4), (0.99, 8, 1e-4))


def main():
    T = 3 * 2 * math.pi
    print("| e | s | epsilon | seed: error (steps) | reversible | symmetric |")
    print("|---|---|---|---|---|---|")
    for e, stages, epsilon in CASES:
        ref = kepler(e)
        ref.integrator = "ias15"
        ref.integrator.epsilon = 1e-13
        ref.integrate(T)
        cells = []
        for control in ("seed", "reversible", "symmetric"):
            sim = kepler(e)
            sim.integrator = "pfvi"
            sim.integrator.step_control = control
            sim.integrator.stages = stages
            sim.integrator.epsilon = epsilon
            sim.integrate(T)
            error = math.dist(sim.particles[1].xyz, ref.particles[1].xyz)
            cells.append(f"{error:.2g} ({sim.integrator.n_steps})")
        print(f"| {e} | {stages} | {epsilon:g} | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    main()
