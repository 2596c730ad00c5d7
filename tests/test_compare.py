"""Scenes, the comparison runner, its reports and the compare CLI (issue 5)."""
import json
import math
import subprocess
import sys

import pytest

from rebound_pfvi import compare, report, runs, scenes
from rebound_pfvi.__main__ import main
from rebound_pfvi.runs import Run

pytestmark = pytest.mark.slow  # runners, CLI and pages: skipped by `pytest -m "not slow"`


@pytest.mark.parametrize("e", [0.0, 0.5, 0.9, 0.95, 0.99])
def test_kepler_reference_agrees_with_tight_ias15(e):
    """The exact reference (REBOUND's elements, M + n t) and IAS15 agree to 1e-10 AU over 10 orbits."""
    scene = scenes.Kepler(e=e, periods=10)
    sim = scene.build()
    sim.integrator = "ias15"
    sim.integrator.epsilon = 1e-11
    sim.integrate(scene.t_end)
    error = scene.position_error(sim, scene.reference())
    assert error < 1e-10, error


@pytest.mark.parametrize("name", ["comet", "triple"])
def test_integrated_references_are_converged(name):
    """IAS15 at epsilon 1e-11 and 1e-10 agree to 1e-9 AU: the reference's stated uncertainty."""
    scene = scenes.make(name, periods=1)
    reference = scene.reference()
    assert 0.0 < reference["uncertainty"] < 1e-9, reference["uncertainty"]
    assert len(reference["positions"]) == scene.build().N


def test_oscillator_with_known_omega_is_exact_for_fitted_two_point_scheme():
    """The seed's exact case, through the runner: s = 2, "phase", fixed omega."""
    scene = scenes.Oscillator(periods=20)
    setting = compare.Setting("pfvi", 1e-6, (("stages", 2), ("fitting", "phase"), ("frequency", "fixed")))
    row = compare.run_setting(scene, setting, scene.reference(), repeats=1, samples=5)
    assert row["status"] == "ok"
    assert row["position_error"] < 1e-12
    assert row["energy_error_max"] < 1e-13
    classical = compare.run_setting(scene, compare.Setting("pfvi", 1e-6, (("stages", 2), ("fitting", "none"))),
                                    scene.reference(), repeats=1, samples=5)
    assert classical["position_error"] > 1e3 * row["position_error"]
    # Forces are counted by the scene's own callback: one per step plus the first.
    assert row["force_evaluations"] >= row["steps"]


@pytest.mark.parametrize("family,value", [("pfvi", 1e-6), ("ias15", 1e-7), ("whfast", 100), ("leapfrog", 1000),
                                          ("bs", 1e-8)])
def test_counting_callback_leaves_the_run_bit_identical(family, value):
    scene = scenes.Comet(periods=0.2)
    setting = compare.Setting(family, value)
    plain = scene.build()
    compare.configure(plain, scene, setting)
    plain.integrate(scene.t_end)
    counter = [0]
    counted = scene.build(counter=counter)
    compare._install_counter(counted, scene, counter)
    compare.configure(counted, scene, setting)
    counted.integrate(scene.t_end)
    assert counter[0] >= plain.steps_done > 0
    state = [[(p.x, p.y, p.z, p.vx, p.vy, p.vz) for p in sim.particles] for sim in (counted, plain)]
    assert state[0] == state[1]  # exactly: the callback adds nothing and changes no step
    assert counted.t == plain.t


@pytest.mark.parametrize("family,value", [("pfvi", 1e-7), ("bs", 1e-6), ("ias15", 1e-2)])
def test_the_sampled_run_never_steps_back_to_a_time_it_passed(family, value, monkeypatch):
    # Sampled with exact_finish_time = 0, a step past the next sampling time
    # made REBOUND integrate backwards to it: up to 42 of 99 samples of a run
    # on the comet and sungrazer pages, their force evaluations counted (a
    # hostile trial).
    import rebound
    scene = scenes.Comet(periods=0.5)
    calls = []
    original = rebound.Simulation.integrate

    def watched(sim, tmax, *args, **kwargs):
        calls.append((sim.t, tmax))
        return original(sim, tmax, *args, **kwargs)
    monkeypatch.setattr(rebound.Simulation, "integrate", watched)
    run = compare._run_setting(scene, compare.Setting(family, value), scene.reference(), 1, 100, None)
    assert run.status == "ok", run.status
    backwards = [(t, tmax) for t, tmax in calls if tmax < t]
    assert len(calls) >= 10 and backwards == []


def _without_timing(rows):
    return [{k: v for k, v in r.to_dict().items() if k not in ("wall_s", "walls_s")} for r in rows]


SMALL_SWEEP = [compare.Setting("pfvi", 1e-6), compare.Setting("pfvi", 1e-5, (("stages", 2), ("fitting", "none"))),
               compare.Setting("ias15", 1e-7), compare.Setting("whfast", 100), compare.Setting("leapfrog", 1000),
               compare.Setting("bs", 1e-8)]


def test_same_numbers_in_process_local_pool_and_dask():
    from distributed import Client, LocalCluster

    scene = scenes.Kepler(e=0.9, periods=2)
    here = compare.run(scene, SMALL_SWEEP, repeats=1, samples=5, workers=1)
    pool = compare.run(scene, SMALL_SWEEP, repeats=1, samples=5, workers=2)
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster, \
            Client(cluster) as client:
        dask = compare.run(scene, SMALL_SWEEP, repeats=1, samples=5, scheduler=client)
    assert all(r["status"] == "ok" for r in here.rows)
    assert _without_timing(here.rows) == _without_timing(pool.rows) == _without_timing(dask.rows)
    assert (here.scheduler, pool.scheduler) == ("this process", "local pool")
    assert dask.scheduler.startswith("dask ") and dask.workers == 2


@pytest.mark.parametrize("workers", [1, 2])
def test_ctrl_c_stops_and_keeps_finished_runs(tmp_path, workers):
    scene = scenes.Kepler(e=0.5, periods=1)
    seen = []

    def progress(done, total, row):
        seen.append(row)
        if done == 2:
            raise KeyboardInterrupt

    results = compare.run(scene, SMALL_SWEEP, repeats=1, samples=3, workers=workers, progress=progress)
    assert results.interrupted and results.finished == 2 < len(SMALL_SWEEP)
    assert [r["line"] for r in results.rows] == sorted((r["line"] for r in seen[:2]),
                                                        key=[s.line for s in SMALL_SWEEP].index)
    paths = report.write(results, str(tmp_path))
    text = (tmp_path / "kepler-e0.5.md").read_text()
    assert "Interrupted" in text and "2 of 6 runs" in text
    assert json.loads((tmp_path / "kepler-e0.5.json").read_text())["interrupted"] is True
    assert set(paths) == {"json", "csv", "md", "png"}


def test_quick_cli_run_writes_table_data_and_png_with_every_integrator(tmp_path, capsys):
    out = tmp_path / "results"
    code = main(["compare", "--scene", "kepler", "--e", "0.9", "--periods", "2", "--repeats", "1", "--samples", "4",
                 "--workers", "1",
                 "--output", str(out)])
    assert code == 0
    data = json.loads((out / "kepler-e0.9.json").read_text())
    assert data["finished"] == data["settings"] == len(compare.default_settings(scenes.Kepler()))
    families = {r["family"] for r in data["rows"] if r["status"] == "ok"}
    assert families == set(compare.FAMILIES)
    table = (out / "kepler-e0.9.md").read_text()
    for label in ("pfvi s=6", "pfvi s=8", "pfvi seed s=4 phase reversible", "IAS15", "WHFast", "LEAPFROG", "BS",
                  "WHFast corrector=11 safe_mode=0", "TRACE", "MERCURIUS"):
        assert f"| {label} |" in table
    # TRACE and MERCURIUS run at REBOUND's defaults, with their knob the step; WHFast's corrector is set.
    rows = {(r["line"], r["value"]): r for r in data["rows"]}
    assert rows[("TRACE", 1000)]["knob"] == rows[("MERCURIUS", 1000)]["knob"] == "steps/period"
    corrected = rows[("WHFast corrector=11 safe_mode=0", 1000)]
    assert corrected["options"] == {"corrector": 11, "safe_mode": 0}
    assert corrected["position_error"] != rows[("WHFast", 1000)]["position_error"]
    png = (out / "kepler-e0.9.png").read_bytes()
    assert png[:8] == b"\x89PNG\r\n\x1a\n" and len(png) > 20000
    assert len((out / "kepler-e0.9.csv").read_text().splitlines()) == data["settings"] + 1
    out = capsys.readouterr().out
    assert "Fastest to a position error" in out
    # Every run has a verdict, counted per integrator on the page and on the command line.
    assert {r["verdict"] for r in data["rows"]} <= {"accurate", "inaccurate", "refused", "crashed"}
    assert "## Verdicts" in table and "| **all** |" in table
    assert "Verdicts" in out and "inaccurate" in out
    # WHFast is exact on two bodies: the page and the command line say so.
    assert "**WHFast caveat**: this is a pure two-body Kepler problem" in table
    assert "WHFast caveat: this is a pure two-body Kepler problem" in out


def test_main_job_is_the_comet_and_its_page_says_who_is_fastest_and_why(tmp_path, capsys):
    """The README's first command runs a scene in which no integrator is exact (issue 18, item 2)."""
    out = tmp_path / "results"
    assert main(["compare", "--periods", "0.5", "--repeats", "1", "--samples", "3", "--workers", "1",
                 "--output", str(out)]) == 0
    assert sorted(p.name for p in out.iterdir()) == ["comet-e0.95.csv", "comet-e0.95.json", "comet-e0.95.md",
                                                    "comet-e0.95.png"]
    page = (out / "comet-e0.95.md").read_text()
    data = json.loads((out / "comet-e0.95.json").read_text())
    assert "## Who is fastest at each accuracy, and why" in page and "WHFast is not exact here" in page
    assert "WHFast caveat" not in page
    best = report.fastest([Run.from_dict(r) for r in data["rows"]], 1e-2)
    winner = min(best.values(), key=lambda r: r["wall_s"])
    # The sentence names the measured winner, its time and its force evaluations.
    sentence = next(line for line in page.splitlines() if line.startswith("- To 1e-02 AU: "))
    if sentence.startswith("- To 1e-02 AU: a tie within the run-to-run noise"):
        assert f"{winner['line']} ({report._knob(winner)}) {winner['wall_s']:.3g} s" in sentence
    else:
        assert sentence.startswith(f"- To 1e-02 AU: {winner['line']} ") and f"{winner['wall_s']:.3g} s" in sentence
    # The reason: force evaluations of the fastest pfvi against the winner, or,
    # when pfvi is among the tied, of that pfvi against the next line.
    order = sorted(best.values(), key=lambda r: r.wall_s)
    pfvi = next((r for r in order if r.family == "pfvi"), None)
    if pfvi is not None and report.tied(winner, pfvi):
        if "; next, " in sentence:
            assert f"{pfvi.label} needs {pfvi.force_evaluations} force evaluations" in sentence, sentence
    elif pfvi is not None:
        assert f"{winner.label} needs {winner.force_evaluations} force evaluations" in sentence, sentence
    assert "- To 1e-02 AU: " in capsys.readouterr().out


@pytest.mark.parametrize("argv,words", [
    (["compare", "--a", "1 kg"], ["--a", "length"]),
    (["compare", "--a", "lots"], ["--a", "quantity"]),
    (["compare", "--mass", "2 AU"], ["--mass", "mass"]),
    (["compare", "--omega", "1 1/yr"], ["--omega", "oscillator"]),
    (["compare", "--scene", "oscillator", "--e", "0.5"], ["--e", "kepler"]),
    (["compare", "--e", "1.5"], ["e=1.5", "0 <= e < 1"]),
    (["compare", "--integrators", "ias15,rk4"], ["--integrators", "rk4", "whfast"]),
    (["compare", "--scene", "oscillator", "--integrators", "whfast"], ["--integrators", "whfast", "oscillator"]),
    (["compare", "--repeats", "0"], ["--repeats", "at least 1"]),
    (["compare", "--scene", "moon"], ["--scene", "kepler"]),
    (["compare", "--periods", "-3"], ["periods", "positive"]),
    (["paper", "fig4"], ["figure", "fig2"]),
    (["compare", "--a", "2"], ["argument --a: '2' has no unit", 'e.g. "2 AU"']),
    (["compare", "--scene", "kepler", "--m", "-1 Mjup"], ["m=-1 Mjup is negative"]),
    (["compare", "--scene", "kepler", "--mass", "-2.5e30  kg"], ["mass=-2.5e30 kg"]),
    (["compare", "--a", "2 parsecs"], ["--a", "parsecs is not a valid unit. Did you mean parsec?", "units: AU"]),
    (["compare", "--mass", "1 Msun"], ["--mass", "not a parameter of scene 'comet'"]),
    (["compare", "--budget", "0"], ["argument --budget: '0' must be positive"]),
    # A figure's unused options were silently ignored (hostile trial).
    (["paper", "fig1", "--epsilon", "1e-3"], ["argument --epsilon: fig1 does not use it"]),
    (["paper", "fig1", "--periods", "1"], ["argument --periods: fig1 does not use it"]),
    (["paper", "fig3", "--samples", "3"], ["argument --samples: fig3 does not use it", "--epsilon, --periods"]),
])
def test_argument_errors_name_the_argument(argv, words, capsys):
    with pytest.raises(SystemExit) as stop:
        main(argv)
    assert stop.value.code == 2
    err = capsys.readouterr().err
    for word in words:
        assert word in err, (word, err)
    assert "<Quantity" not in err and "has unit ," not in err and "def_unit" not in err
    assert len(err.strip().splitlines()[-1]) < 300, err  # one readable line, not astropy's advice
    # The usage is the subcommand's, whether argparse or the command found the error.
    assert err.startswith(f"usage: rebound-pfvi {argv[0]} "), err


@pytest.mark.parametrize("command", [["compare", "--repeats", "1"], ["stability", "--cases", "kepler-e0.99"],
                                     ["paper", "fig3", "--periods", "0.1"]])
@pytest.mark.parametrize("where", ["a file", "inside a file", "/proc"])
def test_an_output_folder_that_cannot_be_written_is_refused_before_anything_runs(command, where, tmp_path,
                                                                                 monkeypatch, capsys):
    from rebound_pfvi import paper, stability

    def must_not_run(*args, **kwargs):
        raise AssertionError("the sweep started before --output was checked")

    for module, name in ((compare, "run"), (stability, "run_all"), (paper, "figure3")):
        monkeypatch.setattr(module, name, must_not_run)
    (tmp_path / "taken").write_text("a file, not a folder")
    output = {"a file": tmp_path / "taken", "inside a file": tmp_path / "taken" / "results",
              "/proc": "/proc/rebound-pfvi-results"}[where]
    with pytest.raises(SystemExit) as stop:
        main(command + ["--output", str(output)])
    assert stop.value.code == 2
    err = capsys.readouterr().err
    assert f"argument --output: cannot write to the folder '{output}'" in err, err
    assert "Traceback" not in err


def test_an_output_folder_is_created_and_left_empty_by_the_check(tmp_path):
    from rebound_pfvi.__main__ import build_parser, check_output

    folder = tmp_path / "new" / "results"
    check_output(build_parser(), str(folder))
    assert folder.is_dir() and list(folder.iterdir()) == []


def test_an_unreachable_scheduler_is_one_line_before_anything_runs(monkeypatch, capsys, tmp_path):
    pytest.importorskip("distributed")
    from rebound_pfvi import __main__ as cli

    monkeypatch.setattr(cli, "CONNECT_TIMEOUT_S", 1.0)
    monkeypatch.setattr(compare, "run", lambda *a, **k: pytest.fail("the sweep started without a scheduler"))
    with pytest.raises(SystemExit) as stop:
        main(["compare", "--scheduler", "tcp://127.0.0.1:1", "--output", str(tmp_path)])
    assert stop.value.code == 2
    err = capsys.readouterr().err
    last = err.strip().splitlines()[-1]
    assert last.startswith("rebound-pfvi compare: error: argument --scheduler: could not connect to a Dask "
                           "scheduler at 'tcp://127.0.0.1:1': Timed out trying to connect"), err
    assert "Traceback" not in err


def test_progress_off_a_terminal_is_one_line_per_finished_run():
    import io

    from rebound_pfvi.__main__ import Progress

    log = io.StringIO()  # not a terminal: a log file, a pipe, CI
    bar = Progress(3, stream=log)
    for done, verdict in enumerate(("accurate", "inaccurate", "refused"), 1):
        run = Run(runs.COMPARE, "kepler", "ias15", "IAS15", knob="epsilon", value=10.0**-done, status="ok",
                  verdict=verdict)
        bar(done, 3, run)
    bar.close()
    lines = log.getvalue().splitlines()
    assert "\r" not in log.getvalue() and len(lines) == 3, lines
    assert lines[0].startswith("[1/3 runs, ") and lines[0].endswith("IAS15 epsilon=0.1: accurate")
    assert lines[2].startswith("[3/3 runs, ") and lines[2].endswith("IAS15 epsilon=0.001: refused")
    # On a terminal: tqdm's bar, with runs done of the total and the time left.
    class Terminal(io.StringIO):
        def isatty(self):
            return True

    screen = Terminal()
    bar = Progress(3, stream=screen)
    bar(3, 3, run)
    assert "3/3 [" in screen.getvalue() and "\r" in screen.getvalue()
    # Steps that are not runs (figure 2's samples) give a line per tenth, not per step.
    log = io.StringIO()
    bar = Progress(2000, unit="sample", stream=log)
    for k in range(1, 2001):
        bar(k, 2000)
    assert len(log.getvalue().splitlines()) == 10 and log.getvalue().splitlines()[-1].startswith("[2000/2000 samples")


@pytest.mark.parametrize("command, default", [("compare", "rebound-pfvi-results"),
                                              ("stability", "rebound-pfvi-stability"),
                                              ("paper", "rebound-pfvi-paper")])
def test_help_gives_the_default_output_folder(command, default, capsys):
    with pytest.raises(SystemExit):
        main([command, "--help"])
    import re

    out = re.sub(r"-\s+", "-", " ".join(capsys.readouterr().out.split()))  # undo argparse's wrapping
    assert f"(default: {default}" in out or f"(default {default})" in out, out


def test_unit_round_trip_and_one_g():
    import astropy.constants as const
    import astropy.units as u
    import rebound

    from rebound_pfvi import units

    for value in (1.3 * u.AU, 2.5e8 * u.km, 4.0 * u.pc, 0.7 * u.Msun, 3.0 * u.Mjup, 2.0e27 * u.kg, 5.0 * u.Mearth):
        kind = "length" if value.unit.physical_type == "length" else "mass"
        back = units.to_quantity(units.to_scene(value, kind, "x"), kind, value.unit)
        assert abs((back / value).decompose().value - 1.0) < 1e-15
    for value in (3.0 * u.day, 2.0 * u.yr, 1e6 * u.s):
        back = units.to_quantity(units.to_scene(value, "time", "t"), "time", value.unit)
        assert abs((back / value).decompose().value - 1.0) < 1e-15
    # Strings and Quantities give the same scene.
    from_strings = scenes.Kepler(a="149597870.7 km", m="1 Mjup").params
    assert from_strings == pytest.approx(scenes.Kepler(a=1.0 * u.AU, m=1 * u.Mjup).params, rel=1e-15)
    assert scenes.Kepler(m=1 * u.Mjup).m == pytest.approx(float(u.Mjup.to(u.Msun)), rel=1e-15)
    # One G: REBOUND's, which carries the nominal GM_sun in AU, yr, Msun ...
    G = scenes.rebound_G()
    sim = rebound.Simulation()
    sim.units = ("AU", "yr", "Msun")
    assert G == sim.G
    gm_sun = (const.GM_sun * u.yr**2 / u.AU**3).decompose().value
    assert abs(G / gm_sun - 1.0) < 1e-9
    # ... so a 1 AU orbit about 1 Msun has the astropy period to 1e-9, in days.
    scene = scenes.Kepler(a="1 AU", mass="1 Msun", m=0.0)
    period = scene.period_quantity().to(u.day)
    expected = (2 * math.pi * ((1 * u.AU)**3 / const.GM_sun)**0.5).to(u.day)
    assert abs((period / expected).value - 1.0) < 1e-9
    # REBOUND's G_SI and astropy's G differ (CODATA 2014 and 2018): a second
    # source of G would show up at this level.
    assert abs(rebound.units.G_SI / const.G.value - 1.0) > 1e-5


def scenes_quantity(value, unit):
    import astropy.units as u
    return value * u.Unit(unit)


def test_scene_errors_name_the_parameter():
    for make, words in ((lambda: scenes.Kepler(a="1 kg"), ("a=", "length")),
                        (lambda: scenes.Kepler(e=-0.1), ("e=-0.1",)),
                        (lambda: scenes.Kepler(m=-1.0), ("m=-1.0",)),
                        (lambda: scenes.Oscillator(omega="1 AU"), ("omega=", "frequency")),
                        (lambda: scenes.Triple(a_outer=2.0), ("a_outer",)),
                        (lambda: scenes.Kepler(periods=scenes_quantity(2.0, "yr")),
                         ("periods=", "has unit yr; periods takes a plain number")),
                        (lambda: scenes.make("moon"), ("moon", "kepler")),
                        (lambda: compare.Setting("rk4", 1.0), ("rk4", "ias15")),
                        (lambda: compare.Setting("ias15", -1.0), ("epsilon=-1.0",)),
                        # option values, checked when the setting is made (before: a
                        # refused or crashed row of the sweep)
                        (lambda: compare.Setting("pfvi", 1e-6, (("stages", 9),)), ("integrator.stages = 9", "2 to 8")),
                        (lambda: compare.Setting("pfvi", 1e-6, (("stages", True),)), ("integrator.stages = True",)),
                        (lambda: compare.Setting("pfvi", 1e-6, (("u_max", 4.0),)), ("integrator.u_max = 4",)),
                        (lambda: compare.Setting("pfvi", 1e-6, (("fitting", "bogus"),)), ("fitting", "bogus")),
                        (lambda: compare.Setting("ias15", 1e-6, (("min_dt", "x"),)), ("integrator.min_dt = 'x'",)),
                        (lambda: compare.default_settings(scenes.Kepler(), "huge"), ("size='huge'",))):
        with pytest.raises(ValueError) as error:
            make()
        for word in words:
            assert word in str(error.value)


def test_results_table_carries_quantities():
    import astropy.units as u

    scene = scenes.Kepler(e=0.5, periods=1)
    results = compare.run(scene, SMALL_SWEEP[2:4], repeats=1, samples=2, workers=1)
    table = results.table()
    assert table["wall_time"].unit == u.s and table["position_error"].unit == u.AU
    assert table["position_error_km"][0].to_value(u.km) == pytest.approx(
        table["position_error"][0].to_value(u.AU) * 149597870.7, rel=1e-12)


def test_figure2_and_figure3_short_runs():
    from rebound_pfvi import paper

    rows = paper.figure2_rows(e=0.95, periods=5, samples=10)
    assert len(rows) == 10 and rows[-1]["t_periods"] == pytest.approx(5.0, rel=1e-3)
    assert max(r["energy_error"] for r in rows) < 1e-5
    assert [r["steps"] for r in rows] == sorted(r["steps"] for r in rows)
    rows = paper.figure3_rows(e=0.95, periods=1)
    peak = 1.0 / (math.sqrt(1.95) * 0.05**1.5)  # v / (a (1 - e^2)) at pericentre, n = 1
    assert max(r["omega"] for r in rows) == pytest.approx(peak, rel=1e-2)
    assert max(abs(r["omega"] / r["omega_exact"] - 1.0) for r in rows) < 1e-3


def test_custom_scene_from_a_users_simulation(tmp_path):
    """A REBOUND user's own simulation (G = 1 units) goes through the same runner and report."""
    import rebound

    sim = rebound.Simulation()
    sim.add(m=1.0)
    sim.add(m=1e-3, a=1.0, e=0.6)
    sim.add(m=1e-3, a=2.0, e=0.1, inc=0.1)
    sim.move_to_com()
    sim.integrate(0.5)  # a start at t != 0
    scene = scenes.Custom(sim, duration=20.0, label="two-planets")
    assert scene.period == pytest.approx(min(o.P for o in sim.orbits()))
    results = compare.run(scene, SMALL_SWEEP, repeats=1, samples=4, workers=1)
    assert all(r["status"] == "ok" for r in results.rows)
    assert all(r["t_final"] == pytest.approx(20.5, abs=1e-12) for r in results.rows)
    ias15 = next(r for r in results.rows if r["family"] == "ias15")
    assert ias15["position_error"] < 1e-8
    report.write(results, str(tmp_path))
    assert "sim. length unit" in (tmp_path / "two-planets.md").read_text()
    assert results.table()["position_error"].unit is None
    with pytest.raises(ValueError, match="duration"):
        scenes.Custom(sim, duration=-1.0)

    def force(simp):
        pass

    sim.additional_forces = force
    with pytest.raises(ValueError, match="additional_forces"):
        scenes.Custom(sim, duration=1.0)


def test_heavy_imports_stay_lazy():
    """Importing the package and the comparison modules pulls in neither astropy, matplotlib, tqdm nor dask."""
    import subprocess
    import sys

    code = ("import sys, rebound_pfvi, rebound_pfvi.compare, rebound_pfvi.scenes, rebound_pfvi.report, "
            "rebound_pfvi.paper, rebound_pfvi.__main__ as cli; cli.build_parser(); "
            "print(sorted(m for m in ('astropy', 'matplotlib', 'tqdm', 'dask', 'distributed') if m in sys.modules))")
    out = subprocess.run([sys.executable, "-P", "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "[]"


def test_script_without_main_guard_fails_instead_of_respawning(tmp_path):
    # Spawned workers import the script; without a guard each one starts its
    # own sweep and dies. The pool must then fail with a message, not hang.
    script = tmp_path / "unguarded.py"
    script.write_text("from rebound_pfvi import compare, scenes\n"
                      "scene = scenes.Kepler(e=0.5, periods=1)\n"
                      "settings = compare.default_settings(scene, families=['whfast'])[:2]\n"
                      "compare.run(scene, settings, repeats=1, samples=2, workers=2)\n")
    done = subprocess.run([sys.executable, "-P", str(script)], cwd=tmp_path, capture_output=True, text=True,
                          timeout=300)
    assert done.returncode != 0
    assert "workers: a worker process died before returning its run" in done.stderr
    assert "__main__" in done.stderr


def test_ias15_warning_is_explained_not_printed_raw(capsys, tmp_path):
    """IAS15 at epsilon 1e-2 on the comet warns that its predictor-corrector did not converge:
    the row keeps the warning, the page and the command line explain it (issue 18, item 7)."""
    # (measured: the warning appears with 100 samples, not with 3; at 1e-3 only
    # where the sampled run stepped back to a time it had passed, as it no longer does)
    assert main(["compare", "--integrators", "ias15", "--full", "--repeats", "1", "--samples", "100", "--workers",
                 "1", "--output", str(tmp_path)]) == 0
    captured = capsys.readouterr()
    assert "RuntimeWarning" not in captured.err
    data = json.loads((tmp_path / "comet-e0.95.json").read_text())
    loose = next(r for r in data["rows"] if r["value"] == 1e-2)
    assert any("predictor corrector loops in IAS15 did not converge" in w for w in loose["warnings"])
    assert "steps are too long for the tolerance" in captured.out
    page = (tmp_path / "comet-e0.95.md").read_text()
    assert "## Warnings" in page and "(IAS15 epsilon 1e-02): IAS15's predictor-corrector" in page


def test_figure1_page_links_and_names_the_command_that_ran(tmp_path):
    from rebound_pfvi import paper
    from rebound_pfvi.__main__ import invocation

    command = invocation(["paper", "fig1", "--output", str(tmp_path / "a b")])
    assert command == f"python3 -P -m rebound_pfvi paper fig1 --output '{tmp_path / 'a b'}'"
    alone = tmp_path / "alone"
    paper.figure1(str(alone), eccentricities=(0.5,), epsilons=(1e-3,), command="the command as run")
    text = (alone / "figure1.md").read_text()
    assert "Generated by `the command as run`" in text
    # No docs/adaptive.md beside the page: no link that would break, its name in the source instead.
    assert "](../adaptive.md)" not in text and "docs/adaptive.md of the rebound_pfvi source repository" in text
    docs = tmp_path / "docs"
    (docs / "paper").mkdir(parents=True)
    (docs / "adaptive.md").write_text("# adaptive\n")
    paper.figure1(str(docs / "paper"), eccentricities=(0.5,), epsilons=(1e-3,))
    text = (docs / "paper" / "figure1.md").read_text()
    assert "[docs/adaptive.md](../adaptive.md)" in text
    # Without a command, the page names a call that reruns exactly these options.
    assert "eccentricities=[0.5], epsilons=[0.001], stages=2, step_control='seed'" in text


def test_version_names_the_package_and_rebound():
    import rebound

    import rebound_pfvi

    done = subprocess.run([sys.executable, "-P", "-m", "rebound_pfvi", "--version"], capture_output=True, text=True,
                          timeout=120)
    assert done.returncode == 0, done.stderr
    assert done.stdout == (f"rebound-pfvi {rebound_pfvi.__version__} (rebound {rebound.__version__}; C core "
                           f"compiled against rebound {rebound.__version__})\n")
    from importlib.metadata import version

    assert rebound_pfvi.__version__ == version("rebound_pfvi")  # the installed distribution's (pyproject)


def _timed(family, label, knob, value, wall, error, evaluations=100):
    return Run(runs.COMPARE, "comet", family, label, knob=knob, value=value, status="ok", verdict="accurate",
               wall_s=wall, position_error=error, force_evaluations=evaluations)


def test_pages_call_differences_within_the_noise_ties_and_say_what_each_ratio_is_of():
    from types import SimpleNamespace

    near = 1.0 + 0.5 * (report.TIE_RATIO - 1.0)  # inside the noise
    rows = [_timed("pfvi", "pfvi s=8", "epsilon", 1e-6, 0.010, 1e-3),
            _timed("bs", "BS", "eps", 1e-7, 0.010 * near, 1e-3),
            _timed("ias15", "IAS15", "epsilon", 1e-5, 0.050, 1e-3),
            _timed("whfast", "WHFast", "steps/period", 1000, 0.001, 1e-1)]
    results = SimpleNamespace(rows=rows)
    sentence = report.conclusions(results)[0]
    assert sentence.startswith("To 1e-02 AU: a tie within the run-to-run noise"), sentence
    assert "pfvi s=8 (epsilon 1e-06) 0.01 s, BS (eps 1e-07" in sentence
    assert "next, IAS15 (epsilon 1e-05) takes 5.0x the wall time of pfvi s=8" in sentence
    table = report.summary_table(rows)
    first = next(line for line in table.splitlines() if line.startswith("| 1e-02"))
    assert first.count("**") == 4, first  # pfvi and BS in bold, IAS15 not
    # Each cell names the setting that reached the target (issue 41).
    assert "0.01 s (epsilon 1e-06)" in first and "0.05 s (epsilon 1e-05)" in first, first
    # Outside the noise there is one fastest, and the ratio says of what to what.
    rows[1] = _timed("bs", "BS", "eps", 1e-7, 0.010 * report.TIE_RATIO * 1.5, 1e-3)
    sentence = report.conclusions(SimpleNamespace(rows=rows))[0]
    assert sentence.startswith("To 1e-02 AU: pfvi s=8 (epsilon 1e-06) is fastest, 0.01 s; next, BS (eps 1e-07) "
                               "takes "), sentence
    assert "the wall time of pfvi s=8" in sentence


def test_a_massless_orbiter_the_help_suggests_runs(tmp_path):
    """--m "0 kg" (the help's own example): the total energy is 0, so the
    energy error is the relative orbit's; every run finishes."""
    scene = scenes.make("kepler", m="0 kg", periods=0.5)
    results = compare.run(scene, [compare.Setting("whfast", 100), compare.Setting("pfvi", 1e-8)], repeats=1,
                          samples=3, workers=1)
    assert [r.status for r in results.rows] == ["ok", "ok"], [r.status for r in results.rows]
    assert all(r.energy_error_max < 1e-9 for r in results.rows)


@pytest.mark.parametrize("argv,words", [
    (["compare", "--scene", "kepler", "--a", "1e300 pc"], ["scene kepler: these parameters give no scene"]),
    (["compare", "--scene", "kepler", "--a", "1e300 AU"], ["no scene to integrate: a value overflows (Numerical result"]),
    (["compare", "--scene", "kepler", "--a", "1e-320 AU"], ["scene kepler: these parameters give no scene"]),
    (["compare", "--scene", "kepler", "--m", "1 AU"], ["argument --m: 1 AU has unit AU, which is not a mass"]),
    (["compare", "--scene", "triple", "--a-inner", "0 AU"], ["argument --a-inner: a_inner=0 AU must be positive"]),
])
def test_scene_parameters_that_give_no_scene_are_argument_errors(argv, words, capsys, monkeypatch):
    monkeypatch.setattr(compare, "run", lambda *a, **k: pytest.fail("the sweep started"))
    with pytest.raises(SystemExit) as stop:
        main(argv)
    assert stop.value.code == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err
    for word in words:
        assert word in err, err


def test_a_result_file_that_cannot_be_written_is_refused_before_the_runs(tmp_path, capsys, monkeypatch):
    monkeypatch.setattr(compare, "run", lambda *a, **k: pytest.fail("the sweep started"))
    (tmp_path / "kepler-e0.95.json").mkdir()  # where the sweep's JSON would go
    with pytest.raises(SystemExit) as stop:
        main(["compare", "--scene", "kepler", "--output", str(tmp_path)])
    assert stop.value.code == 2
    assert "exists and is not a file" in capsys.readouterr().err
    # A failed check removes the folders it made.
    deep = tmp_path / "new" / ("x" * 300)
    with pytest.raises(SystemExit):
        main(["compare", "--scene", "kepler", "--output", str(deep)])
    assert not (tmp_path / "new").exists()


def test_a_peer_that_is_not_a_dask_scheduler_is_one_line_within_the_deadline(monkeypatch, capsys, tmp_path):
    pytest.importorskip("distributed")
    import socket
    import threading
    import time

    from rebound_pfvi import __main__ as cli

    server = socket.socket()
    server.bind(("127.0.0.1", 0))
    server.listen(4)
    accepted = []
    threading.Thread(target=lambda: accepted.append(server.accept()), daemon=True).start()  # accepts, never answers
    monkeypatch.setattr(cli, "CONNECT_TIMEOUT_S", 1.0)
    monkeypatch.setattr(compare, "run", lambda *a, **k: pytest.fail("the sweep started without a scheduler"))
    address = f"tcp://127.0.0.1:{server.getsockname()[1]}"
    tick = time.perf_counter()
    with pytest.raises(SystemExit) as stop:
        main(["compare", "--scheduler", address, "--output", str(tmp_path / "o")])
    assert stop.value.code == 2 and time.perf_counter() - tick < 20
    err = capsys.readouterr().err
    assert f"argument --scheduler: could not connect to a Dask scheduler at '{address}'" in err, err
    assert not (tmp_path / "o").exists()  # nothing made before the scheduler answered
    server.close()


def test_a_setting_checks_its_option_names_when_it_is_made():
    assert compare.Setting("trace", 100, (("r_crit_hill", 1.0),)).line == "TRACE r_crit_hill=1.0"
    with pytest.raises(ValueError, match="'r_crit_hil' is not an option of trace"):
        compare.Setting("trace", 100, (("r_crit_hil", 1.0),))
    with pytest.raises(ValueError, match="'stagez' is not an option of pfvi"):
        compare.Setting("pfvi", 1e-6, (("stagez", 4),))
    with pytest.raises(ValueError, match="epsilon is ias15's accuracy knob"):
        compare.Setting("ias15", 1e-9, (("epsilon", 1e-3),))


def test_the_periodic_box_energy_counts_the_ghost_images():
    """REBOUND's sim.energy() leaves the images out and changes by 7% as the
    bodies meet through the boundary; the scene's energy is conserved."""
    scene = scenes.make("periodic-box")
    sim = scene.build()
    sim.integrator = "ias15"
    sim.integrator.epsilon = 1e-11
    E0, e0 = scene.energy(sim), sim.energy()
    ours, rebounds = 0.0, 0.0
    for k in range(1, 21):
        sim.integrate(scene.t_end * k / 20)
        ours = max(ours, abs(scene.energy(sim) / E0 - 1.0))
        rebounds = max(rebounds, abs(sim.energy() / e0 - 1.0))
    assert ours < 1e-12 and rebounds > 1e-2, (ours, rebounds)


def test_ratios_near_the_tie_ratio_show_enough_digits_and_no_pfvi_clause_without_pfvi():
    from types import SimpleNamespace

    rows = [_timed("bs", "BS", "eps", 1e-4, 1.0, 1e-3), _timed("trace", "TRACE", "steps/period", 30, 1.645, 1e-3)]
    sentence = report.conclusions(SimpleNamespace(rows=rows))[0]
    assert "takes 1.65x the wall time of BS" in sentence, sentence
    assert "pfvi" not in sentence  # no pfvi ran: nothing to say about it


def test_paper_writes_into_its_output_folder_under_the_current_one(tmp_path, monkeypatch, capsys):
    """Issue 41: `rebound-pfvi paper fig3` run from any folder writes to
    rebound-pfvi-paper there (as compare and stability do), never into a
    docs/paper below the folder it runs from; --output is taken as given."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "docs" / "paper").mkdir(parents=True)
    assert main(["paper", "fig3", "--periods", "0.2"]) == 0
    assert sorted(p.name for p in (tmp_path / "rebound-pfvi-paper").iterdir()) == [
        "figure3.json", "figure3.md", "figure3.png"]
    assert list((tmp_path / "docs" / "paper").iterdir()) == []
    assert main(["paper", "fig3", "--periods", "0.2", "--output", str(tmp_path / "elsewhere")]) == 0
    assert (tmp_path / "elsewhere" / "figure3.md").is_file()
    assert "rebound-pfvi-paper/figure3.md" in capsys.readouterr().out


def test_a_tighter_setting_that_ends_less_accurate_is_named_with_why():
    """Issue 41: the main job's pfvi s = 8 had a larger error at epsilon 1e-8
    than at 1e-4 with no word of why."""
    rows = [_timed("pfvi", "pfvi s=8", "epsilon", 1e-4, 0.010, 2.5e-7),
            _timed("pfvi", "pfvi s=8", "epsilon", 1e-8, 0.011, 4.7e-7),
            _timed("pfvi", "pfvi s=8", "epsilon", 1e-10, 0.012, 4e-9),
            _timed("whfast", "WHFast", "steps/period", 100, 0.001, 1e-1),
            _timed("whfast", "WHFast", "steps/period", 1000, 0.002, 1e-3)]
    rows[0].steps, rows[1].steps = 102, 106
    notes = report.tighter_less_accurate(rows)
    assert notes == ["pfvi s=8: epsilon 1e-08 ends 4.7e-07 from the reference against 2.5e-07 at epsilon 1e-04 "
                     "(106 steps against 102)."], notes
    section = report._tighter_section(rows)
    assert "epsilon_effective" in section and "along the track" in section
    assert report._tighter_section(rows[2:]) == ""


def test_a_page_without_matplotlib_links_no_figure(tmp_path, monkeypatch):
    # The page linked a .png that was never written (hostile trial).
    monkeypatch.setitem(sys.modules, "matplotlib", None)
    monkeypatch.setitem(sys.modules, "matplotlib.pyplot", None)
    scene = scenes.Kepler(e=0.5, periods=0.5)
    results = compare.run(scene, [compare.Setting("pfvi", 1e-6)], repeats=1, samples=2, workers=1)
    paths = report.write(results, str(tmp_path))
    page = (tmp_path / (scene.slug + ".md")).read_text()
    assert "png" not in paths and "![work-precision diagram]" not in page
    assert "No plot: matplotlib is not installed" in page


def test_a_setting_checks_its_value_and_options_by_name():
    # (a hostile trial: True ran as epsilon 1, numpy's float32 was refused, a
    # dict of options failed to unpack naming nothing, and a statistic given
    # as an option made every run "crashed")
    np = pytest.importorskip("numpy")
    with pytest.raises(ValueError, match=r"^epsilon=True for pfvi must be a positive number"):
        compare.Setting("pfvi", True)
    assert compare.Setting("pfvi", np.float32(1e-6)).value == pytest.approx(1e-6, rel=1e-7)
    assert compare.Setting("pfvi", 1e-6, {"stages": 6}).options == (("stages", 6),)
    with pytest.raises(ValueError, match=r"^options: n_steps is a statistic pfvi counts"):
        compare.Setting("pfvi", 1e-6, (("n_steps", 3),))
    with pytest.raises(ValueError, match=r"^options=\('stages', 6\): give \(name, value\) pairs"):
        compare.Setting("pfvi", 1e-6, ("stages", 6))


def test_a_warning_without_an_explanation_is_quoted_once():
    # (a hostile trial: a REBOUNDx warning no entry explained was quoted, then
    # repeated as its own explanation, ending in "..")
    from rebound_pfvi.report import warnings_section
    from rebound_pfvi.runs import Run

    unknown = "Something new happened."
    rebx = ("REBOUNDx: Passing a velocity-dependent force to WHFAST, will accumulate errors proportional to the "
            "force. See ipython_examples/IntegrateForce.ipynb.")
    rows = [Run(kind="compare", scene="s", family="whfast", label="WHFast", knob="steps/period", value=10.0,
                warnings=[unknown, rebx])]
    lines = warnings_section(rows).splitlines()
    assert lines[0] == f'- "{unknown}" (WHFast 10 steps/period).'
    assert lines[1].startswith(f'- "{rebx}" (WHFast 10 steps/period): REBOUNDx\'s warning that WHFast\'s kick')
    assert lines[1].count("IntegrateForce") == 1 and not lines[1].endswith("..")
