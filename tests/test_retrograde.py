"""Inclined and retrograde bodies inside Jupiter's orbit against IAS15 (issue 40,
item 6): a reduced grid of benchmarks/retrograde_sweep.py (the dense sweep and its
table: docs/step-control.md)."""
import math
import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))
import retrograde_sweep  # noqa: E402  (the sweep's systems, reference and measure)

def _goal(system, s, eps):
    """The largest position error at the sweep's T in units of epsilon_effective a n t."""
    return retrograde_sweep.run((system, s, eps, retrograde_sweep.reference(system)))[3]


# (system (inclination, mass, a, e, f), s, epsilon). The build before the fix
# (547cb7b) failed five of them: 2.3e4, 617, 31, 1.1e4 and 4.5e3 epsilon a n;
# the prograde body and s = 4 are controls.
@pytest.mark.parametrize("system, s, eps", [
    ((math.pi, 1e-5, 3.0, 0.3, 2.0), 8, 1e-10),
    ((math.pi, 0.0, 3.0, 0.0, 2.0), 6, 1e-6),
    ((math.pi / 2, 0.0, 3.0, 0.3, 0.0), 8, 1e-6),
    ((math.pi, 1e-5, 2.0, 0.0, 2.0), 8, 1e-9),
    ((0.0, 0.0, 3.0, 0.3, 0.0), 8, 1e-10),
    ((math.pi, 0.0, 3.0, 0.3, 2.0), 4, 1e-6),
    ((math.pi, 0.0, 3.0, 0.3, 0.0), 8, 1e-6),
    ((2.5, 0.0, 3.0, 0.0, 0.0), 8, 1e-10),
    ((math.pi / 2, 1e-5, 3.0, 0.0, 2.0), 8, 1e-6),
])
def test_inclined_and_retrograde_bodies_within_the_goal(system, s, eps):
    assert _goal(system, s, eps) <= 10.0
