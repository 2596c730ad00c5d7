"""N_active larger than N (found by a hostile trial of issue 42): REBOUND's basic gravity (src/gravity.c) loops
i < N_active over sim.particles and so reads and writes past the array
(valgrind: invalid reads at gravity.c:199-201, invalid writes at 207-208,
through pfvi_update_acceleration). pfvi passes such a simulation to it
(pfvi_gravity_own leaves N_active > N to REBOUND's routine), giving a
segfault, heap corruption or a random "did not converge" depending on the
heap. Bad input is to be refused with an error naming N_active, t and the
particles unchanged. Run in a child process: the defect can kill it."""
import json
import subprocess
import sys

import pytest

CHILD = r"""
import json, rebound, rebound_pfvi
sim = rebound.Simulation()
sim.add(m=1.0)
for k in range(7):
    sim.add(m=1e-5, a=0.7 + 0.4*k, e=0.1, f=k)
sim.move_to_com()
sim.integrator = "pfvi"
sim.N_active = sim.N + EXTRA
before = [[p.x, p.y, p.z, p.vx, p.vy, p.vz] for p in sim.particles] + [[sim.t]]
try:
    sim.integrate(2.0)
    message = None
except Exception as e:
    message = f"{type(e).__name__}: {e}"
after = [[p.x, p.y, p.z, p.vx, p.vy, p.vz] for p in sim.particles] + [[sim.t]]
print(json.dumps({"message": message, "unchanged": repr(before) == repr(after)}))
"""


@pytest.mark.parametrize("extra", [1, 4])
def test_n_active_above_n_is_refused_naming_it(extra):
    out = subprocess.run([sys.executable, "-P", "-c", CHILD.replace("EXTRA", str(extra))],
                         capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, f"the process died (rc {out.returncode}): {out.stderr[-400:]}"
    result = json.loads(out.stdout.strip().splitlines()[-1])
    assert result["message"] is not None and "N_active" in result["message"], result
    assert result["unchanged"], result
