"""Verdicts on every run of compare and stability (issue 17, item 4): an O(1)
error is never "finished" alone."""
import math

import pytest

from rebound_pfvi import compare, scenes, stability, verdict
from rebound_pfvi.runs import COMPARE, STABILITY, Run

pytestmark = pytest.mark.slow  # runners, CLI and pages: skipped by `pytest -m "not slow"`


def test_judge_separates_accurate_from_inaccurate_at_the_tolerance():
    assert verdict.judge(1e-8, 1e-6) == (verdict.ACCURATE, "energy error 1e-08, position error 1e-06 of the distance")
    # The radial infall's s = 2 energy error (docs/stability): O(1), so inaccurate, with the error.
    kind, detail = verdict.judge(7.8, 2.4e-2)
    assert kind == verdict.INACCURATE
    assert detail == "energy error 7.8 > 0.01, position error 0.024 of the distance > 0.01"
    assert verdict.judge(1e-3, 0.5)[0] == verdict.INACCURATE  # position alone
    assert verdict.judge(0.02, 1e-9)[0] == verdict.INACCURATE  # energy alone
    assert verdict.judge(1e-3, None) == (verdict.ACCURATE, "energy error 0.001")
    assert verdict.judge(1e-3, math.nan)[0] == verdict.INACCURATE
    assert verdict.judge(1e-3, 1e-3, finite=False)[0] == verdict.INACCURATE
    tight = verdict.Tolerance(energy=1e-12, position=1e-12)
    assert verdict.judge(1e-10, 1e-13, tight)[0] == verdict.INACCURATE


def test_relative_position_error_is_per_body_about_body_0():
    reference = [(0.0, 0.0, 0.0), (0.01, 0.0, 0.0), (10.0, 0.0, 0.0)]
    # The same absolute error (1e-4 AU) is 1% of a 0.01 AU orbit and 1e-5 of a 10 AU one.
    assert verdict.relative_position_error([(0, 0, 0), (0.01, 1e-4, 0), (10, 0, 0)], reference) == pytest.approx(1e-2)
    assert verdict.relative_position_error([(0, 0, 0), (0.01, 0, 0), (10, 1e-4, 0)], reference) == pytest.approx(1e-5)
    # A shift of the whole system (body 0 too) is no error of the orbits.
    shifted = [(x + 3.0, y, z) for x, y, z in reference]
    assert verdict.relative_position_error(shifted, reference) < 1e-13  # round-off of 3.01 - 3.0
    assert verdict.relative_position_error([(2.0, 0, 0)], [(1.0, 0, 0)]) == 1.0
    assert verdict.relative_vector_error((0, 0, 0), (0, 0, 0)) == 0.0
    assert verdict.relative_vector_error((1e-3, 0, 0), (0, 0, 0)) == math.inf
    with pytest.raises(ValueError, match="positions"):
        verdict.relative_position_error([(0, 0, 0)], reference)


def test_a_moon_is_measured_about_its_planet():
    # Sun, planet at 1 AU, moon 0.0026 AU beyond it; the moon on the far side of its planet.
    reference = [(0.0, 0.0, 0.0), (1.0, 0.0, 0.0), (1.0026, 0.0, 0.0)]
    flipped = [(0.0, 0.0, 0.0), (1.0, 0.0, 0.0), (0.9974, 0.0, 0.0)]
    assert verdict.relative_position_error(flipped, reference) == pytest.approx(0.0052 / 1.0026)  # under 1%
    assert verdict.relative_position_error(flipped, reference, {2: 1}) == pytest.approx(2.0)
    assert verdict.judge(1e-9, verdict.relative_position_error(flipped, reference, {2: 1}))[0] == verdict.INACCURATE
    for bad in ({2: 2}, {2: 3}, {2: -1}):
        with pytest.raises(ValueError, match="primaries: body 2's primary"):
            verdict.relative_position_error(flipped, reference, bad)


def test_stability_statuses_map_to_verdicts():
    case = stability.cases()["kepler-e0.99"]
    base = {"energy_error_max": 1e-7, "relative_position_error": 1e-6, "finite": True, "fraction": 0.25}

    def row(**fields):
        return Run(STABILITY, "kepler-e0.99", "pfvi", "pfvi seed s=4 phase", **{**base, **fields})

    assert stability.judge(case, row(status="finished"))[0] == verdict.ACCURATE
    assert stability.judge(case, row(status="finished", energy_error_max=4.2e5)) == (
        verdict.INACCURATE, "energy error 4.2e+05 > 0.01, position error 1e-06 of the distance")
    kind, detail = stability.judge(case, row(status="stopped by the budget of 60 s"))
    assert kind == verdict.OVER_BUDGET and "at 0.25 of the run" in detail and "energy error 1e-07" in detail
    message = "pfvi: the reversible step equation from t = 2.76 did not converge (a long message, kept whole)"
    assert stability.judge(case, row(status="refused: " + message)) == (verdict.REFUSED, message)
    assert stability.judge(case, row(status="crashed: process exit code -6", fraction=None))[0] == \
        verdict.CRASHED
    assert stability.judge(case, row(status="killed: no result 120 s after the start",
                                     fraction=None))[0] == verdict.OVER_BUDGET
    assert stability.judge(case, row(status="error: ValueError: bad"))[0] == verdict.CRASHED
    # The round-off case holds runs to round-off, not to a percent.
    tiny = stability.cases()["fixed-1e-12"]
    assert tiny.tolerance.position == 1e-12
    assert stability.judge(tiny, row(status="finished"))[0] == verdict.INACCURATE


def test_radial_infall_at_s2_is_inaccurate_and_ias15_accurate():
    # Measured: pfvi s = 2 under the osculating-circle control ends the fall
    # with an energy error of 7.8 (docs/stability.md): finished, but it must
    # never be reported as merely "finished". (The symmetric control, the
    # default now, ends it accurate.)
    name, budget = "radial-infall", 30.0
    case = stability.cases()[name]
    rows = {}
    for config in (stability.Config("pfvi", (("stages", 2), ("fitting", "phase"), ("step_control", "reversible")), 1e-6), stability.Config("ias15", epsilon=1e-9)):
        row = stability.run(name, config, budget)
        row.relative_position_error = stability.relative_position_error(case, row, case.exact(row["t"]))
        row.verdict, row.verdict_detail = stability.judge(case, row)
        rows[config.family] = row
    assert rows["pfvi"]["status"] == "finished" and rows["pfvi"]["energy_error_max"] > 1.0
    assert rows["pfvi"]["verdict"] == verdict.INACCURATE
    assert rows["pfvi"]["verdict_detail"].startswith("energy error ")
    assert rows["ias15"]["verdict"] == verdict.ACCURATE
    assert rows["ias15"]["relative_position_error"] < 1e-10


def test_compare_rows_carry_verdicts():
    scene = scenes.Kepler(e=0.9, periods=2)
    settings = [compare.Setting("leapfrog", 30), compare.Setting("ias15", 1e-9)]
    results = compare.run(scene, settings, repeats=1, samples=4, workers=1)
    loose, tight = results.rows
    # 30 fixed steps per period cannot follow an e = 0.9 pericentre passage.
    assert loose["verdict"] == verdict.INACCURATE and "> 0.01" in loose["verdict_detail"]
    assert tight["verdict"] == verdict.ACCURATE and tight["relative_position_error"] < 1e-9
    counts = results.verdict_counts()
    assert counts["LEAPFROG"][verdict.INACCURATE] == 1 and counts["IAS15"][verdict.ACCURATE] == 1
    table = verdict.markdown_counts(counts)
    assert "| LEAPFROG | 0 | 1 | 0 | 0 | 0 |" in table and "| **all** | 1 | 1 | 0 | 0 | 0 |" in table


@pytest.mark.parametrize("status, expected", [
    ("failed: RuntimeError: pfvi: the 4-stage solve did not converge", (verdict.REFUSED,
                                                                       "pfvi: the 4-stage solve did not converge")),
    ("failed: ZeroDivisionError: float division by zero", (verdict.CRASHED,
                                                          "ZeroDivisionError: float division by zero")),
    ("diverged (non-finite energy or position)", (verdict.INACCURATE, "diverged (non-finite energy or position)")),
])
def test_compare_failures_map_to_verdicts(status, expected):
    assert compare.judge(scenes.Kepler(), Run(COMPARE, "kepler", "pfvi", "pfvi seed s=4 phase reversible", status=status)) == expected


def test_compare_budget_stops_a_slow_run_as_over_budget(tmp_path):
    # pfvi s = 2 at epsilon 1e-11 needs 1.4 s for one run of 100 periods already at e = 0.95
    # (docs/results), and the setting runs twice (timed, then sampled): a 1.5 s budget stops it inside
    # integrate(). IAS15 needs 0.1-0.4 s for both runs (measured, on a loaded machine).
    scene = scenes.Kepler(e=0.99, periods=100)
    slow = compare.Setting("pfvi", 1e-11, (("stages", 2), ("fitting", "none")))
    results = compare.run(scene, [slow, compare.Setting("ias15", 1e-9)], repeats=1, samples=4, workers=1,
                          budget=1.5)
    stopped, fine = results.rows
    assert stopped["verdict"] == verdict.OVER_BUDGET
    assert stopped["verdict_detail"].startswith("stopped by the budget of 1.5 s at ")
    fraction = float(stopped["verdict_detail"].split(" at ")[1].split()[0])
    assert 0.0 < fraction < 1.0
    assert fine["verdict"] == verdict.ACCURATE
    assert results.verdict_counts()["pfvi s=2"][verdict.OVER_BUDGET] == 1
    from rebound_pfvi import report

    report.write(results, str(tmp_path))
    page = (tmp_path / "kepler-e0.99.md").read_text()
    assert "Budget: 1.5 s of wall time per setting." in page and "| over budget |" in page
    with pytest.raises(ValueError, match="budget=-1"):
        compare.run(scene, [slow], budget=-1)


def test_a_scene_without_reference_positions_is_judged_on_energy():
    # A scene with its own exact reference (no "positions") and no relative_position_error of its own,
    # as a new scene may be: its runs are judged on the energy, not crashed by a missing key.
    class Exact(scenes.Kepler):
        def reference(self):
            return {"elements": scenes.orbit_elements(self.build()), "uncertainty": 0.0, "how": "exact"}

        def relative_position_error(self, sim, reference):
            return scenes.Scene.relative_position_error(self, sim, reference)

    scene = Exact(e=0.5, periods=1)
    row = compare.run_setting(scene, compare.Setting("ias15", 1e-9), scene.reference(), repeats=1, samples=3)
    assert row["status"] == "ok" and row["relative_position_error"] is None
    assert row["verdict"] == verdict.ACCURATE and row["verdict_detail"].startswith("energy error ")
    assert "position" not in row["verdict_detail"]
