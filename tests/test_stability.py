"""rebound-pfvi stability: the cases' references, the isolated runner, the CLI."""
import json
import math
import os
import subprocess
import sys
import time

import pytest

from rebound_pfvi import runner, stability

pytestmark = pytest.mark.slow  # runners, CLI and pages: skipped by `pytest -m "not slow"`


def test_every_listed_case_builds_and_is_finite():
    for name, case in stability.cases().items():
        sim = case.build()
        assert sim.N >= 2 and sim.t == 0.0, name
        assert case.t_end > 0 and case.time_scale > 0, name
        assert all(math.isfinite(p.x) and math.isfinite(p.vx) for p in sim.particles), name


def test_radial_infall_exact_solution_matches_ias15():
    # The radial Kepler equation against IAS15 at 1e-11, at the stop (r = 0.01 AU).
    case = stability.cases()["radial-infall"]
    sim = case.build()
    sim.integrator = "ias15"
    sim.integrator.epsilon = 1e-11
    sim.integrate(case.t_end, exact_finish_time=1)
    d = sim.particles[1] - sim.particles[0]
    assert math.dist((d.x, d.y, d.z), case.exact(case.t_end)) < 1e-12
    assert case.exact(case.t_end)[0] == pytest.approx(0.01, rel=1e-9)
    assert case.exact(0.0)[0] == pytest.approx(1.0, abs=1e-12)


@pytest.mark.parametrize("name", ["flyby-e1", "flyby-e1.5", "flyby-e5"])
def test_flyby_duration_takes_the_body_to_the_mirror_point(name):
    # t_end comes from Barker's equation (e = 1) or the hyperbolic Kepler
    # equation: after it the body is at the mirror image of its start.
    case = stability.cases()[name]
    sim = case.build()
    d0 = sim.particles[1] - sim.particles[0]
    sim.integrator = "ias15"
    sim.integrator.epsilon = 1e-11
    sim.integrate(case.t_end, exact_finish_time=1)
    d1 = sim.particles[1] - sim.particles[0]
    r0 = math.hypot(d0.x, d0.y)
    assert math.dist((d1.x, d1.y), (d0.x, -d0.y)) < 1e-9 * r0


def test_a_run_over_its_budget_is_stopped_and_reported():
    config = stability.Config("pfvi", (("stages", 4), ("fitting", "phase")), 1e-6)
    row = stability.run("long-e0.99", config, budget=0.2)
    assert row["status"] == "stopped by the budget of 0.2 s"
    assert 0 < row["fraction"] < 0.01 and row["finite"]
    assert row["wall_s"] < 1.0


def test_a_run_whose_steps_collapse_is_stopped_inside_integrate():
    # s = 2 "phase" breaks the stiff binary (the centre-of-mass instability)
    # and its steps collapse to ~1e-12 yr: one checkpoint is never reached.
    # The budget must still stop it, from the timer thread.
    config = stability.Config("pfvi", (("stages", 2), ("fitting", "phase")), 1e-6)
    row = stability.run("stiff-binary", config, budget=3.0)
    assert row["status"] == "stopped by the budget of 3 s"
    assert row["wall_s"] < 10.0
    assert row["n_steps"] == row["steps"] > 0


def test_fixed_step_cases_give_pfvi_fixed_steps():
    case = stability.cases()["fixed-u-at"]
    config = stability.Config("pfvi", (("stages", 2), ("fitting", "phase")), 1e-6)
    sim = case.build()
    stability.configure(sim, case, config)
    assert sim.integrator.epsilon == 0.0 and sim.dt == case.fixed_dt


def test_isolated_runner_reports_results_crashes_and_hangs(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)  # a core file of the aborted run, if the system writes one, lands here
    jobs = [(math.sqrt, (4.0,)), (os.abort, ()), (time.sleep, (60.0,)), (math.sqrt, (-1.0,))]
    tick = time.monotonic()
    outcomes = runner.run_tasks([runner.Task(f, args, limit) for (f, args), limit in
                                 zip(jobs, [30.0, 30.0, 2.0, 30.0])], workers=2, fresh=True)
    assert outcomes[0] == ("ok", 2.0)
    assert outcomes[1][0] == "crashed" and outcomes[1][1] != 0
    assert outcomes[2] == ("killed", 2.0)
    assert outcomes[3] == ("error", "ValueError: math domain error")
    assert time.monotonic() - tick < 30.0


def cli(*args, cwd):
    return subprocess.run([sys.executable, "-P", "-m", "rebound_pfvi", "stability", *args], cwd=cwd,
                          capture_output=True, text=True, timeout=600)


def test_cli_writes_the_report(tmp_path):
    done = cli("--cases", "radial-infall,flyby-e5", "--integrators", "pfvi,ias15", "--budget", "20",
               "--output", str(tmp_path / "out"), cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    data = json.loads((tmp_path / "out" / "stability.json").read_text())
    rows = {(r["case"], r["integrator"]): r for r in data["rows"]}
    assert len(rows) == 2 * 8  # the defaults, 6 rows at s = 2 and 4, IAS15
    assert all(r["status"] == "finished" for r in rows.values())
    # Measured with the default (symmetric) step control: IAS15 7.8e-15 AU;
    # pfvi s = 4 9.9e-15 AU, s = 2 1.6e-12 AU (its density follows the fall;
    # the osculating-circle control held the steps at the cap on a radial
    # path: 2.2e-7 and 2.4e-4 AU, and s = 2 ended with an energy error of 7.8).
    assert rows["radial-infall", "IAS15"]["position_error"] < 1e-12
    assert rows["radial-infall", "pfvi seed s=4 phase"]["position_error"] < 1e-12
    assert rows["radial-infall", "pfvi seed s=2 phase"]["position_error"] < 1e-10
    assert {rows["radial-infall", label]["verdict"] for label in ("pfvi seed s=2 phase", "pfvi seed s=2 phase-literal",
                                                                "pfvi s=2")} == {"accurate"}
    assert rows["radial-infall", "IAS15"]["verdict"] == rows["flyby-e5", "IAS15"]["verdict"] == "accurate"
    text = (tmp_path / "out" / "stability.md").read_text()
    assert "## radial-infall" in text and "## flyby-e5" in text
    assert "python3 -P -m rebound_pfvi stability --cases radial-infall,flyby-e5" in text  # the command as run
    counts = {}
    for r in rows.values():
        counts.setdefault(r["integrator"], []).append(r["verdict"])
    for name, verdicts in counts.items():  # the page counts the verdicts per integrator
        line = f"| {name} | " + " | ".join(str(verdicts.count(v)) for v in stability.verdict.VERDICTS) + " |"
        assert line in text
    assert "Verdicts" in done.stdout and "IAS15" in done.stdout
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out"]


@pytest.mark.parametrize("args, message", [
    (["--cases", "nope"], "argument --cases: nope not a case; allowed: kepler-e0.99"),
    (["--integrators", "bs"], "argument --integrators: bs not an integrator; allowed: pfvi, ias15, whfast"),
    (["--budget", "0"], "argument --budget: '0' must be positive"),
])
def test_cli_argument_errors_name_the_argument(args, message, tmp_path):
    done = cli(*args, cwd=tmp_path)
    assert done.returncode == 2
    assert message in done.stderr


def test_cli_progress_bar_and_failed_runs_in_full_at_the_end(tmp_path):
    # u = 40 u_max at pericentre: s = 4's stage solve cannot converge and pfvi refuses (docs/stability.md).
    done = cli("--cases", "fixed-u-40x", "--integrators", "pfvi", "--budget", "20", "--output", str(tmp_path / "o"),
               cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    # Off a terminal, a line per finished run (a tqdm bar on one, tests/test_compare.py); it names
    # runs and their verdicts, never their messages.
    # (Its workers' RuntimeWarnings, pfvi's on fixed steps this coarse, pass through to stderr.)
    progress = [line for line in done.stderr.splitlines() if line.startswith("[")]
    assert len(progress) == 7 and progress[-1].startswith("[7/7 runs, "), done.stderr
    assert "fixed-u-40x: pfvi s=8: refused" in done.stderr and "\r" not in done.stderr
    assert "did not converge" not in done.stderr
    refusals = [line for line in done.stdout.splitlines() if line.startswith("- fixed-u-40x: pfvi ")]
    # s = 4 with each fitting and the default s = 8 (the solve does not converge), and since issue 36
    # s = 2 with each fitting (a step over more than an orbit: refused, not integrated to nonsense).
    assert len(refusals) == 7, done.stdout
    for line in refusals:  # the whole message, to its last word
        if " s=2" in line:
            assert ": refused: pfvi: the fixed step dt = " in line and "radians of the fastest orbit" in line, line
            assert line.endswith("Use a shorter dt or epsilon > 0."), line
            continue
        assert (" s=4" in line and ": refused: pfvi: the 4-stage solve did not converge" in line
                or " s=8: refused: pfvi: the 8-stage solve did not converge" in line), line
        assert line.endswith("step not taken, state restored. Lower dt."), line


def test_a_stability_case_is_a_scene_compare_can_sweep():
    from rebound_pfvi import compare

    case = stability.cases()["kepler-e0.99"]
    assert case.t_end == case.duration and case.describe() == case.title and case.slug == "kepler-e0.99"
    settings = [compare.Setting("ias15", 1e-9), compare.Setting("pfvi", 1e-8, (("stages", 4),))]
    results = compare.run(case, settings, repeats=1, samples=10, workers=1)
    rows = {r["family"]: r for r in results.rows}
    assert results.reference["how"] == "exact"
    # The exact reference: IAS15 to round-off, pfvi at epsilon 1e-8 within the verdict's tolerance.
    assert rows["ias15"]["position_error"] < 1e-9
    assert rows["ias15"]["verdict"] == rows["pfvi"]["verdict"] == "accurate"
