"""A slice of benchmarks/random_systems.py as a test: systems nobody designed
a scene for (planets to e = 0.995, binaries, test particles, flybys,
retrograde orbits), against IAS15, where the dynamics do not amplify
errors. The full sweep (400 systems) and its table: docs/step-control.md,
"Random systems".

Seeds 180-199 hold the two systems of the first 400 whose error the split
(docs/step-control.md, "The split") brought under the goal: test particles
falling into pericentre from under a planet's time scale, 13.3 epsilon a n
at epsilon 1e-9 (seed 186) and 10.6 at 1e-6 (seed 187) before it; 0.62 and
0.91 now (the slice's largest: 2.7, seed 187 at 1e-9).
"""
import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "benchmarks"))
import random_systems  # noqa: E402

sys.path.pop(0)


@pytest.mark.parametrize("seed", range(180, 200))
def test_a_random_system_keeps_to_what_epsilon_promises(seed):
    for row in random_systems.measure(seed, [1e-6, 1e-9]):
        if row["amplification"] < random_systems.AMPLIFICATION_MAX:
            # The step control's goal is 10 epsilon a n; the sweep's largest is 2.7.
            assert row["error"] < 5.0, row
