"""Issue 42, the Python boundary (third hostile trial): the Python API checks
what the command line checks, with the same checks, and errors name the
argument or field and the value at fault."""
import math
import warnings

import astropy.units as u
import pytest

from rebound_pfvi import compare, demo, paper, report, scenes, stability, units
from rebound_pfvi.__main__ import main
from conftest import needs_python_heartbeat

#: Sweeps in which no run gets to its end: every run crashes (an overflow) or is refused (a force that is not finite).
NOTHING_FINISHES = [
    (["--scene", "oscillator", "--omega", "1e300 1/yr", "--integrators", "ias15"], "oscillator.md", "4 crashed"),
    (["--scene", "kepler", "--m", "1e300 kg", "--integrators", "pfvi", "--periods", "1"], "kepler-e0.95.md",
     "16 refused"),
]


@pytest.mark.parametrize("argv, page, what", NOTHING_FINISHES)
def test_a_sweep_in_which_no_run_finished_writes_its_page_and_fails(argv, page, what, tmp_path, capsys):
    code = main(["compare", *argv, "--output", str(tmp_path), "--workers", "1", "--repeats", "1",
                 "--samples", "2"])
    assert code == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert err[-1] == (f"error: no run finished with finite errors ({what}); each run's verdict: "
                       f"{tmp_path / page}")
    text = (tmp_path / page).read_text()
    assert f"**Nothing measured**: no run finished with finite errors ({what})." in text
    assert "| crashed |" in text or "| refused |" in text


def test_compare_run_says_when_no_run_finished():
    scene = scenes.Oscillator(omega=1e300, periods=1)
    with pytest.warns(compare.NoRunFinished, match=r"oscillator: no run finished with finite errors \(2 crashed\)"):
        results = compare.run(scene, [compare.Setting("ias15", 1e-5), compare.Setting("pfvi", 1e-6)], repeats=1,
                              samples=2, workers=1)
    assert results.failure == "no run finished with finite errors (2 crashed)"
    assert [r.verdict for r in results.rows] == ["crashed", "crashed"]
    with warnings.catch_warnings():
        warnings.simplefilter("error", compare.NoRunFinished)
        fine = compare.run(scenes.Kepler(periods=1), [compare.Setting("ias15", 1e-5)], repeats=1, samples=2,
                           workers=1)
    assert fine.failure == ""


ONE = [compare.Setting("ias15", 1e-5)]


def kepler_run(**keywords):
    return compare.run(scenes.Kepler(periods=1), ONE, **{"repeats": 1, "samples": 2, "workers": 1, **keywords})


# Each refused before anything runs (demo.run_demo(nan) integrated for ever; repeats=2.5 ran 2 repeats).
@pytest.mark.parametrize("call, message", [
    (lambda: demo.run_demo(math.nan), "orbits=nan is not an integer"),
    (lambda: demo.run_demo(2.5), "orbits=2.5 is not an integer"),
    (lambda: demo.run_demo(0), "orbits=0 must be at least 1"),
    (lambda: kepler_run(repeats=2.5), "repeats=2.5 is not an integer"),
    (lambda: kepler_run(samples=True), "samples=True is not an integer"),
    (lambda: kepler_run(workers=0), "workers=0 must be at least 1"),
    (lambda: kepler_run(budget=5 * u.m), "budget=5 m has unit m, which is not a time; allowed: yr, day, d, s, h"),
    (lambda: kepler_run(budget=-1 * u.s), "budget=-1 s must be positive"),
    (lambda: kepler_run(budget=math.inf), "budget=inf is not finite"),
    (lambda: stability.run_all(["kepler-e0.99"], budget=math.nan), "budget=nan is not finite"),
    (lambda: stability.run_all(["kepler-e0.99"], workers=1.5), "workers=1.5 is not an integer"),
    (lambda: units.parse("1 AU", "time", "duration"), "duration=1 AU has unit AU, which is not a time"),
    (lambda: units.parse("2 kg", "length", "a"), "a=2 kg has unit kg, which is not a length"),
    (lambda: paper.figure2_rows(periods=math.nan), "periods=nan is not finite"),
    (lambda: paper.figure2_rows(periods=1, samples=0), "samples=0 must be at least 1"),
], ids=lambda v: v if isinstance(v, str) else "")
def test_the_python_api_makes_the_command_lines_checks(call, message):
    with pytest.raises(ValueError) as refused:
        call()
    assert str(refused.value) == message or str(refused.value).startswith(message + ";"), str(refused.value)


def test_an_empty_list_of_settings_is_named_as_such():
    # (It said "no integrator family applies to this scene", a hostile trial.)
    with pytest.raises(ValueError, match="an empty list was given"):
        compare.run(scenes.make("kepler"), [])


def test_a_budget_may_be_a_time_quantity():
    assert kepler_run(budget=2 * u.min).budget == 120.0
    assert units.parse("3 day", "time", "t").to_value(u.day) == 3.0


@pytest.mark.parametrize("basename", ["../x", "a/b", "..", "", "/tmp/x"])
def test_a_page_name_with_a_folder_is_refused_and_nothing_written(basename, tmp_path):
    results = kepler_run()
    with pytest.raises(ValueError, match=r"basename=.* is not a file name: give a name without a folder"):
        report.write(results, str(tmp_path / "out"), basename=basename)
    assert list(tmp_path.iterdir()) == []
    assert set(report.write(results, str(tmp_path / "out"), basename="mine")) == {"json", "csv", "md", "png"}


# A name given twice ran twice (stability --cases a,a; --integrators pfvi,pfvi); compare's --integrators
# dropped the second silently. Now refused, naming it, by the command line and the Python functions alike.
@pytest.mark.parametrize("argv, message", [
    (["stability", "--cases", "kepler-e0.99,flyby-e1,kepler-e0.99"],
     "argument --cases: kepler-e0.99 given twice; give each once (comma-separated)"),
    (["stability", "--integrators", "pfvi,ias15,PFVI"],
     "argument --integrators: pfvi given twice; give each once (comma-separated)"),
    (["compare", "--integrators", "ias15,ias15"],
     "argument --integrators: ias15 given twice; give each once (comma-separated)"),
])
def test_a_name_given_twice_is_an_argument_error(argv, message, capsys, tmp_path):
    with pytest.raises(SystemExit) as stop:
        main([*argv, "--output", str(tmp_path / "out")])
    assert stop.value.code == 2
    assert capsys.readouterr().err.strip().splitlines()[-1].endswith(message)
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("call, message", [
    (lambda: stability.run_all(["flyby-e1", "flyby-e1"]), "case_names: flyby-e1 given twice; give each once"),
    (lambda: stability.run_all(["nope"]), "case_names: nope not a case; allowed: kepler-e0.99, "),
    (lambda: stability.default_configs(["whfast", "whfast"]), "integrators: whfast given twice; give each once"),
    (lambda: compare.default_settings(scenes.Kepler(), families=["bs", "bs"]),
     "families: bs given twice; give each once"),
], ids=["run_all", "unknown", "default_configs", "default_settings"])
def test_the_python_functions_refuse_a_name_given_twice(call, message):
    with pytest.raises(ValueError) as refused:
        call()
    assert str(refused.value).startswith(message), str(refused.value)


def _two_bodies(triple):
    import rebound

    sim = rebound.Simulation()
    if triple is not None:
        sim.units = triple
    mass, a = (1.0, 1.0) if triple is None else ((1 * u.Msun).to_value(triple[2]), (1 * u.AU).to_value(triple[0]))
    sim.add(m=mass)
    sim.add(m=1e-3 * mass, a=a, e=0.1)
    sim.move_to_com()
    return sim


# Quantities were taken only where sim.units was AU, yr, Msun; every other unit set was called "no units set".
@pytest.mark.parametrize("triple, length", [(("m", "s", "kg"), "m"), (("km", "day", "Msun"), "km"),
                                            (("AU", "yr", "Msun"), "AU")])
def test_a_custom_scene_converts_quantities_to_the_simulations_units(triple, length, tmp_path):
    scene = scenes.Custom(_two_bodies(triple), 2 * u.yr, period=1 * u.day, label="mine")
    assert scene.duration == pytest.approx((2 * u.yr).to_value(triple[1]), rel=1e-15)
    assert scene.period == pytest.approx((1 * u.day).to_value(triple[1]), rel=1e-15)
    assert scenes.Custom(_two_bodies(triple), "3 h").duration == pytest.approx((3 * u.h).to_value(triple[1]))
    with pytest.raises(ValueError, match=r"^duration=2 m has unit m, which is not a time"):
        scenes.Custom(_two_bodies(triple), 2 * u.m)
    if length == "km":  # the page and the table in the simulation's length unit
        results = compare.run(scene, ONE, repeats=1, samples=2, workers=1)
        report.write(results, str(tmp_path))
        text = (tmp_path / "mine.md").read_text()
        assert " km. Energy:" in text and "- To 1e-02 km: IAS15" in text
        assert results.to_dict()["units"]["length"] == "km"
        table = results.table()
        assert table["position_error_km"][0].to_value(u.km) == pytest.approx(results.rows[0].position_error)


def test_a_quantity_for_a_simulation_without_units_says_how_to_set_them():
    with pytest.raises(ValueError) as refused:
        scenes.Custom(_two_bodies(None), 1 * u.yr)
    assert str(refused.value) == (
        "duration=1 yr: this simulation has no units (sim.units is not set), so a Quantity cannot be converted; "
        "give a plain number in its time unit, or set its units before adding particles, e.g. "
        "sim.units = ('AU', 'yr', 'Msun') or ('m', 's', 'kg')")
    assert scenes.Custom(_two_bodies(None), 2.0).describe().endswith("in its own units")


def test_figure2_samples_go_forward_and_each_row_is_a_step_end():
    # Sampled with exact_finish_time = 0, a step past several sampling times
    # made the next integrate() go back: 463 of 2000 samples over 10 periods
    # went backwards, and over 1 period the reversible control refused a
    # step back (a hostile trial).
    rows = paper.figure2_rows(periods=10, samples=2000)
    times = [r["t_periods"] for r in rows]
    assert 100 < len(rows) <= 2000
    assert all(b > a for a, b in zip(times, times[1:]))
    assert times[-1] >= 10.0


def test_a_paper_figure_without_matplotlib_writes_its_page_and_data(tmp_path, monkeypatch):
    # matplotlib is the optional [plot] extra: without it the figure ended in
    # a traceback after the run and left nothing (a hostile trial).
    import sys
    monkeypatch.setitem(sys.modules, "matplotlib", None)
    paper.figure3(str(tmp_path), periods=1)
    page = (tmp_path / "figure3.md").read_text()
    assert "No plot: matplotlib is not installed" in page and "](figure3.png)" not in page
    assert (tmp_path / "figure3.json").exists() and not (tmp_path / "figure3.png").exists()


@pytest.mark.parametrize("hook", ["post_timestep_modifications", "pre_timestep_modifications",
                                  pytest.param("heartbeat", marks=needs_python_heartbeat), "ode",
                                  "collision_resolve", "reboundx"])
def test_a_custom_scene_refuses_what_its_copy_would_drop(hook):
    # A copy keeps no timestep hook, heartbeat, ODE, resolve function or
    # REBOUNDx: the comparison integrated another problem and called it
    # accurate (REBOUNDx's migration dropped, a = 1.000 against the user's
    # 0.606; a hostile trial).
    sim = _two_bodies(("AU", "yr", "Msun"))
    if hook in ("post_timestep_modifications", "pre_timestep_modifications", "heartbeat"):
        setattr(sim, hook, lambda simp: None)
        named = hook
    elif hook == "ode":
        ode = sim.create_ode(length=1)
        ode.derivatives = lambda ode, y_dot, y, t: None
        named = "an ODE"
    elif hook == "collision_resolve":
        sim.collision = "direct"
        sim.collision_resolve = "merge"
        named = "collision_resolve"
    else:
        reboundx = pytest.importorskip("reboundx")
        extras = reboundx.Extras(sim)  # noqa: F841  (attached to sim)
        named = "REBOUNDx"
    with pytest.raises(ValueError, match=rf"^sim: .*{named}.* set; a copy of the simulation does not keep"):
        scenes.Custom(sim, 1.0)


@pytest.mark.parametrize("call, words", [
    (lambda: scenes.Kepler(a=[1.0, 2.0] * u.AU), "a=[1. 2.] AU is not a single value"),
    (lambda: units.parse("[1,2] AU", "length", "a"), "is not a single value"),
    (lambda: units.parse("3", "speed", "v"), "v: '3' has no unit; write a number and a unit, e.g. \"3 AU / yr\""),
    (lambda: scenes.Kepler(a=1 * u.AU * u.rad), "a=1 AU rad has unit AU rad, which is not a length"),
])
def test_units_errors_name_the_argument(call, words):
    # (numpy's bare "only 0-dimensional arrays" TypeError, a KeyError for the
    # speed kind, and 1 AU rad taken for 1 AU: a hostile trial)
    with pytest.raises(ValueError) as refused:
        call()
    assert words in str(refused.value)


def test_a_frequency_may_still_be_given_in_radians_per_time():
    assert units.to_scene(2 * math.pi * u.rad / u.yr, "frequency", "omega") == pytest.approx(2 * math.pi)
    assert units.to_scene(1 * u.cycle / u.yr, "frequency", "omega") == pytest.approx(2 * math.pi)


@pytest.mark.parametrize("omega", [1 * u.Hz, 2 * u.kHz, "1 Hz", "3 rad Hz"])
def test_hertz_is_refused_for_an_angular_frequency(omega):
    # (a hostile trial: astropy reads 1 Hz as 1/s, so omega = 1 Hz ran at
    # 1 rad/s, 2 pi slower than a cycle a second, without a word)
    with pytest.raises(ValueError, match=r"omega=.*: hertz is ambiguous for an angular frequency"):
        units.to_scene(omega, "frequency", "omega")


def test_the_integrator_page_tool_takes_help_for_help(tmp_path, monkeypatch, capsys):
    # (--help was taken for the output path: a 33 kB file named "--help" in the working directory)
    from rebound_pfvi import integrator_page
    monkeypatch.chdir(tmp_path)
    assert integrator_page.main(["--help"]) == 0
    assert "usage: python -m rebound_pfvi.integrator_page [PATH]" in capsys.readouterr().out
    assert integrator_page.main([str(tmp_path / "missing" / "page.md")]) == 1
    assert "cannot write" in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == []


def test_a_custom_scenes_label_is_checked_when_the_scene_is_made():
    # (it names the page's files; refused only by report.write after the whole sweep, blaming basename=)
    with pytest.raises(ValueError, match=r"^label='runs/2026' is not a file name"):
        scenes.Custom(_two_bodies(("AU", "yr", "Msun")), 1.0, label="runs/2026")
