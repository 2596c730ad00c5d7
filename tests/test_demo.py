"""The main job: the demo runs and reports what it claims."""
import pytest

from rebound_pfvi.__main__ import main
from rebound_pfvi.demo import run_demo


def test_demo_rows_and_errors():
    lines = []
    rows = run_demo(orbits=2, write=lines.append)
    assert len(rows) == 8 and len(lines) == 11
    by = {(r["e"], r["integrator"]): r for r in rows}
    # Circular orbit: the fitted scheme is exact to round-off, the classical one is not.
    assert by[(0.0, "pfvi:phase")]["energy_error"] < 1e-13
    assert by[(0.0, "pfvi:phase")]["position_error"] < 1e-11
    assert by[(0.0, "pfvi:none")]["position_error"] > 1e-3
    # The reference (REBOUND's elements, M advanced by n t) agrees with IAS15.
    assert by[(0.95, "ias15")]["position_error"] < 1e-9


def test_cli_rejects_bad_orbits(capsys):
    with pytest.raises(SystemExit):
        main(["demo", "--orbits", "0"])
    err = capsys.readouterr().err
    assert "argument --orbits: 0 must be at least 1" in err, err
