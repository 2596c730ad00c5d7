"""The demo (bare `rebound-pfvi`): it runs and reports what it claims."""
import pytest
import rebound

from rebound_pfvi.__main__ import main
from rebound_pfvi.demo import run_demo


def test_demo_rows_and_errors():
    lines = []
    rows = run_demo(orbits=2, write=lines.append)
    notes = [line for line in lines if line.startswith("Note (")]
    assert len(rows) == 8 and len(lines) == 12 + len(notes)
    # pfvi's warnings come as notes under the table, never as Python's
    # RuntimeWarning with a site-packages path in its middle (issue 41).
    assert all(line.startswith("Note (") for line in lines[-1 - len(notes):-1])
    by = {(r["e"], r["integrator"]): r for r in rows}
    # The defaults first, named as such.
    assert rows[0]["integrator"] == "pfvi (defaults)" and "pfvi (defaults)" in lines[3]
    # Within their promise: epsilon (1e-6) per orbit of a = 1, 2 orbits.
    for e in (0.0, 0.95):
        assert by[(e, "pfvi (defaults)")]["position_error"] < 2e-6
    # Circular orbit: the seed's fitted two-point scheme is exact to round-off.
    assert by[(0.0, "pfvi seed s=2 phase, fixed dt")]["energy_error"] < 1e-13
    assert by[(0.0, "pfvi seed s=2 phase, fixed dt")]["position_error"] < 1e-11
    # The reference (REBOUND's elements, M advanced by n t) agrees with IAS15:
    # to 6e-13 with rebound 5.2. Before 5.2, REBOUND's orbit() puts this
    # pericentre start at M = 7.5e-10 instead of 0 (e = 0.95), which moves the
    # reference by 4.7e-9 at the pericentre where the run ends.
    reference_bound = 1e-9 if tuple(map(int, rebound.__version__.split(".")[:2])) >= (5, 2) else 1e-8
    assert by[(0.95, "ias15")]["position_error"] < reference_bound


def test_cli_rejects_bad_orbits(capsys):
    with pytest.raises(SystemExit):
        main(["demo", "--orbits", "0"])
    err = capsys.readouterr().err
    assert "argument --orbits: 0 must be at least 1" in err, err


def test_bare_command_prints_no_python_warning(tmp_path):
    """Issue 41: `rebound-pfvi` with no arguments printed pfvi's RuntimeWarning
    about the seed's fixed step at e = 0.95, with a site-packages path, in the
    middle of its table; the demo states it as a note under the table."""
    import subprocess
    import sys

    run = subprocess.run([sys.executable, "-P", "-W", "default", "-m", "rebound_pfvi", "demo", "--orbits", "100"],
                         capture_output=True, text=True, cwd=tmp_path, timeout=300)
    assert run.returncode == 0, run.stderr
    assert "Warning" not in run.stderr and "site-packages" not in run.stdout + run.stderr, run.stderr
    assert "Note (pfvi seed s=2 phase, fixed dt, e = 0.95): pfvi: the fixed step" in run.stdout
