"""The solar system from JPL's DE421 (issue 41, item 1): scenes.solar_system()
at any epoch DE421 covers, and the scene solar-system, on a short span.

The tests that need DE421 are skipped without the ``ephemeris`` extra (the
skip names its install line); those with GR also without REBOUNDx. The
first test runs everywhere. `pytest -k solar_system` selects this file.
"""
import json
import math
import re
import subprocess
import sys
from pathlib import Path

import pytest

from rebound_pfvi import compare, report, scenes
from rebound_pfvi.__main__ import main

INSTALL = 'pip install ".[ephemeris]"'


def _installed(*names):
    try:
        for name in names:
            __import__(name)
    except ImportError:
        return False
    return True


needs_ephemeris = pytest.mark.skipif(not _installed("de421", "jplephem"),
                                     reason=f"needs the ephemeris extra (JPL's DE421): {INSTALL}")
needs_reboundx = pytest.mark.skipif(not _installed("reboundx"),
                                    reason='GR needs the reboundx extra: pip install ".[reboundx]"')

J2000 = 2451545.0


def test_missing_ephemeris_names_the_extra(monkeypatch, capsys):
    monkeypatch.setitem(sys.modules, "de421", None)  # import de421 now fails
    scenes.de421.cache_clear()
    try:
        with pytest.raises(ImportError, match=r'pip install "rebound_pfvi\[ephemeris\]"'):
            scenes.solar_system()
        with pytest.raises(SystemExit) as stop:
            main(["compare", "--scene", "solar-system"])
        assert stop.value.code == 2
        assert "rebound_pfvi[ephemeris]" in capsys.readouterr().err
    finally:
        scenes.de421.cache_clear()


def test_import_does_not_load_the_ephemeris():
    code = ("import sys, rebound_pfvi, rebound_pfvi.scenes, rebound_pfvi.__main__ as cli; cli.build_parser(); "
            "print(sorted(m for m in ('de421', 'jplephem', 'reboundx', 'astropy') if m in sys.modules))")
    out = subprocess.run([sys.executable, "-P", "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "[]"


@needs_ephemeris
def test_bodies_masses_and_states_are_de421s():
    sim = scenes.solar_system(J2000, gr=False)
    assert sim.N == 11 and sim.t == 0.0
    assert [sim.particles[name].m for name in scenes.DE421_BODIES] == [p.m for p in sim.particles]
    eph = scenes.de421()
    # GM from the kernel's constants: the Earth/Moon mass ratio is DE421's EMRAT,
    # the Sun's GM over REBOUND's G (the IAU nominal GM_sun) is 1 within DE421's difference from it.
    assert sim.particles["Earth"].m / sim.particles["Moon"].m == pytest.approx(eph.EMRAT, rel=1e-14)
    assert sim.particles["Sun"].m == pytest.approx(1.0, abs=1e-8)
    assert sim.particles["Jupiter"].m == pytest.approx(1.0 / 1047.3486, rel=1e-6)
    pos, vel = scenes.de421_states(J2000, 0.0)
    for i, p in enumerate(sim.particles):
        assert (p.x, p.y, p.z) == tuple(pos[0, i]) and (p.vx, p.vy, p.vz) == tuple(vel[0, i])
    # Barycentric: the Sun within 0.01 AU of the origin, the Earth 0.98 AU from it in January.
    assert math.hypot(pos[0, 0, 0], pos[0, 0, 1]) < 0.01
    earth = sim.particles["Earth"] - sim.particles["Sun"]
    assert 0.983 < math.sqrt(earth.x**2 + earth.y**2 + earth.z**2) < 0.984
    moon = sim.particles["Moon"] - sim.particles["Earth"]
    assert 356000 < math.sqrt(moon.x**2 + moon.y**2 + moon.z**2) * scenes.AU_KM < 407000


@needs_ephemeris
def test_epochs_as_julian_date_iso_string_and_astropy_time():
    from astropy.time import Time

    def earth(epoch):
        p = scenes.solar_system(epoch, gr=False).particles["Earth"]
        return (p.x, p.y, p.z)

    assert earth("2000-01-01 12:00") == earth(J2000) == earth(Time(J2000, format="jd", scale="tdb")) \
        == earth("2451545.0")
    # A Time in UTC is converted to TDB (64.18 s later at J2000): the Earth moves ~1900 km in that time.
    utc = Time("2000-01-01 12:00", scale="utc")
    # (a Julian date in one double resolves 40 us: 1.3 m of the Earth's motion)
    assert earth(utc) == pytest.approx(earth(utc.tdb.jd), abs=2e-11)
    shift = math.dist(earth(utc), earth(J2000)) * scenes.AU_KM
    assert 1800 < shift < 2000
    assert scenes.solar_system("1900-01-01", gr=False).N == 11


@needs_ephemeris
@pytest.mark.parametrize("epoch, shown", [("1800-01-01", "'1800-01-01'"), (2600000.5, "2600000.5")])
def test_epoch_outside_de421_names_it_and_the_span(epoch, shown):
    start, end = scenes.de421_span()
    with pytest.raises(ValueError) as error:
        scenes.solar_system(epoch)
    message = str(error.value)
    assert message.startswith(f"epoch={shown}") and "outside DE421's span" in message
    assert f"JD {start:.1f} to {end:.1f} TDB" in message


@needs_ephemeris
def test_an_epoch_just_past_the_span_says_by_how_much_and_an_mjd_says_what_it_may_be():
    # (a hostile trial: "JD 2524624.50 TDB, 2200-02-01 is outside DE421's span
    # ... (1899-12-04 to 2200-02-01)" for a UTC epoch 69 s past the end, and
    # a year of -4571 cut to "-4571-01-0" for an MJD)
    from astropy.time import Time

    with pytest.raises(ValueError, match=r"is outside DE421's span, 69.\d s after its end"):
        scenes.solar_system(Time("2200-02-01", scale="utc"))
    assert scenes.solar_system(Time("2200-02-01", scale="tdb"), gr=False).N == 11
    with pytest.raises(ValueError) as error:
        scenes.solar_system(51544.5)
    message = str(error.value)
    assert "-4571-01-09 00:00:00.000" in message and "days before its start" in message
    assert message.endswith("if it is a Modified Julian Date, the Julian date is 2451545.000000")


@needs_ephemeris
@pytest.mark.parametrize("gr", ["no", "False", 0, 1, 1.0])
def test_gr_is_true_false_or_none(gr):
    # (a hostile trial: gr="no" switched GR on, as any true value did)
    with pytest.raises(ValueError, match=r"gr=.* is not True, False or None"):
        scenes.solar_system(gr=gr)
    with pytest.raises(ValueError, match=r"gr=.* is not True, False or None"):
        scenes.SolarSystem(years=1, gr=gr)


@needs_ephemeris
def test_the_run_length_takes_a_time_as_the_output_interval_does():
    import astropy.units as u

    assert scenes.SolarSystem(years=0.5 * u.yr, gr=False).years == 0.5
    assert scenes.SolarSystem(years="730.5 day", gr=False).years == 2.0
    with pytest.raises(ValueError, match=r"years=1 AU has unit AU, which is not a time"):
        scenes.SolarSystem(years=1 * u.AU, gr=False)
    with pytest.raises(ValueError, match=r"years=-1 yr must be positive"):
        scenes.SolarSystem(years=-1 * u.yr, gr=False)


@needs_ephemeris
@pytest.mark.parametrize("epoch, match", [("yesterday", "not a date astropy can read"), (True, "not an epoch"),
                                          (float("nan"), "not finite"),
                                          (None, r"epoch=None is not an epoch; give an astropy Time, a Julian date "
                                                 r"\(TDB\) or an ISO date such as"),
                                          ([2451545.0], r"epoch=\[2451545.0\] is not an epoch"),
                                          (b"2000-01-01", r"epoch=b'2000-01-01' is not an epoch")])
def test_bad_epochs_are_named(epoch, match):
    with pytest.raises(ValueError, match=match):
        scenes.solar_system(epoch)


@needs_ephemeris
def test_scene_outputs_and_their_interval():
    import astropy.units as u

    scene = scenes.SolarSystem(years=1, every=30 * u.day, gr=False)
    assert scene.every == pytest.approx(30.0)
    times = scene.output_times()
    assert len(times) == 13 and times[0] == pytest.approx(30 / 365.25) and times[-1] == 1.0
    assert scenes.SolarSystem(years=1, every="1 week", gr=False).every == pytest.approx(7.0)
    with pytest.raises(ValueError, match=r"every=-1 must be positive"):
        scenes.SolarSystem(every=-1, gr=False)
    with pytest.raises(ValueError, match=r"every=400 days is longer than the run"):
        scenes.SolarSystem(years=1, every=400, gr=False)


@needs_ephemeris
def test_without_reboundx_the_scene_is_newtonian_and_says_how_to_get_gr(monkeypatch):
    monkeypatch.setitem(sys.modules, "reboundx", None)  # import reboundx now fails
    told = 'Newtonian (no GR: REBOUNDx is not installed; pip install "rebound_pfvi[reboundx]" for GR)'
    scene = scenes.SolarSystem(years=1)
    assert scene.gr is False and scene.describe().endswith(told)
    asked = scenes.SolarSystem(years=1, gr=False)   # Newtonian by choice: nothing to install
    assert asked.describe().endswith("Newtonian (no GR)")
    with pytest.raises(ImportError, match=r'rebound_pfvi\[reboundx\]'):
        scenes.SolarSystem(years=1, gr=True)


@needs_ephemeris
def test_run_past_de421s_end_is_refused():
    start, end = scenes.de421_span()
    with pytest.raises(ValueError, match=r"years=10: the run would end .* after DE421's span ends"):
        scenes.SolarSystem(epoch=end - 100.0, years=10)


def _errors(gr, integrator, epsilon, years=1.0):
    """Each body's largest error (km) over the outputs against DE421 and the
    IAS15 reference, as compare measures them."""
    scene = scenes.SolarSystem(years=years, gr=gr)
    setting = compare.Setting(integrator, epsilon)
    run = compare.run_setting(scene, setting, scene.reference(), repeats=1, samples=3)
    assert run.status == "ok", run.status
    return run


# Measured (1 yr from J2000, an output every 10 days, pfvi's defaults; IAS15
# at 1e-9 gives the same to 1 mm): with GR, the Moon 22.6 km from DE421 and
# every other body within 0.43 km (the Earth), every body within 9e-6 km of
# IAS15 at epsilon 1e-11, relative energy error 9e-16; without GR, Mercury
# 155 km from DE421, 540 times its distance with GR.
@needs_ephemeris
@needs_reboundx
def test_pfvi_stays_near_de421_and_ias15_with_gr():
    run = _errors(True, "pfvi", 1e-6)
    de421, ias15 = run.bodies["DE421"], run.bodies["IAS15"]
    assert de421["Moon"] < 30.0
    assert max(v for k, v in de421.items() if k != "Moon") < 0.6
    assert max(ias15.values()) < 1e-4  # 10 cm
    assert run.energy_error_max < 1e-13


# Measured: backward a year from J2000 (sim.dt < 0), the Moon 24.4 km from
# DE421, the Earth 0.53 km, every other body within 0.36 km; pfvi and IAS15
# the same to the digits shown.
@needs_ephemeris
@needs_reboundx
def test_backward_from_j2000_as_an_ephemeris_user_would():
    import numpy as np

    days = np.arange(-10.0, -366.0, -10.0)
    reference, _ = scenes.de421_states(J2000, days)
    found = {}
    for integrator in ("pfvi", "ias15"):
        sim = scenes.solar_system(J2000)
        sim.integrator = integrator
        sim.dt = -0.01
        states = []
        for day in days:
            sim.integrate(day / 365.25)
            states.append([(p.x, p.y, p.z) for p in sim.particles])
        found[integrator] = np.array(states)
        worst = np.linalg.norm(found[integrator] - reference, axis=2).max(axis=0) * scenes.AU_KM
        assert worst[scenes.DE421_BODIES.index("Moon")] < 30.0
        assert np.delete(worst, scenes.DE421_BODIES.index("Moon")).max() < 0.6
    assert np.abs(found["pfvi"] - found["ias15"]).max() * scenes.AU_KM < 1e-4


@needs_ephemeris
def test_newtonian_model_is_far_from_de421_at_mercury():
    newtonian = _errors(False, "pfvi", 1e-6).bodies
    assert max(newtonian["IAS15"].values()) < 1e-4
    assert newtonian["DE421"]["Mercury"] > 100.0  # GR's perihelion advance, left out
    if _installed("reboundx"):
        assert _errors(True, "ias15", 1e-9).bodies["DE421"]["Mercury"] < newtonian["DE421"]["Mercury"] / 100


@needs_ephemeris
def test_compare_writes_each_bodys_error(tmp_path):
    scene = scenes.SolarSystem(years=0.5, gr=False)
    settings = [compare.Setting("pfvi", 1e-6), compare.Setting("ias15", 1e-9),
                compare.Setting("whfast", 10, (("corrector", 11), ("safe_mode", 0)))]
    results = compare.run(scene, settings, repeats=1, samples=3, workers=1)
    assert [r.verdict for r in results.rows][:2] == ["accurate", "accurate"]
    paths = report.write(results, str(tmp_path), command="test")
    text = open(paths["md"]).read()
    assert "Against DE421 (km):" in text and "Against IAS15 (km):" in text
    rows = json.load(open(paths["json"]))["rows"]
    assert set(rows[0]["bodies"]["DE421"]) == set(scenes.DE421_BODIES)
    # WHFast in Jacobi coordinates drifts the Moon about the inner solar system's barycentre: far off.
    assert rows[2]["bodies"]["IAS15"]["Moon"] > 1000 * rows[0]["bodies"]["IAS15"]["Moon"]


@needs_ephemeris
def test_cli_epoch_error_names_the_option(capsys):
    with pytest.raises(SystemExit) as stop:
        main(["compare", "--scene", "solar-system", "--epoch", "1700-01-01"])
    assert stop.value.code == 2
    err = capsys.readouterr().err
    assert "argument --epoch: epoch='1700-01-01'" in err and "outside DE421's span" in err


@pytest.mark.parametrize("option, text, words", [("--years", "1 AU", "argument --years: 1 AU has unit AU, which is not a time"),
                                                 ("--every", "five", "argument --every: cannot read 'five' as a quantity"),
                                                 ("--years", "-2", "argument --years: years=-2.0 must be positive")])
def test_cli_run_length_and_interval_take_numbers_or_times(capsys, option, text, words):
    from rebound_pfvi.__main__ import SCENE_OPTIONS, _argument, _number_or_time

    assert SCENE_OPTIONS[option][1] == "number or time"
    assert _number_or_time("2", "years") == 2.0 and str(_number_or_time("12 h", "every").unit) == "h"
    if words.endswith("must be positive"):
        pytest.importorskip("de421")
    with pytest.raises(SystemExit) as stop:
        main(["compare", "--scene", "solar-system", option, text])
    assert stop.value.code != 0
    assert words in capsys.readouterr().err


def _page_snippets():
    page = Path(__file__).resolve().parent.parent / "docs" / "solar-system.md"
    # ```py, not ```python: tests/test_docs.py runs those without the extra; this file runs these with it.
    return re.findall(r"```py\n(.*?)```", page.read_text(encoding="utf-8"), re.S)


def test_the_page_has_snippets():
    assert _page_snippets()


@needs_ephemeris
@pytest.mark.slow
@pytest.mark.parametrize("code", _page_snippets())
def test_page_snippet_runs_saved_as_a_script(code, tmp_path):
    script = tmp_path / "snippet.py"
    script.write_text(code, encoding="utf-8")
    done = subprocess.run([sys.executable, "-P", str(script)], cwd=tmp_path, capture_output=True, text=True,
                          timeout=600)
    assert done.returncode == 0, done.stderr[-3000:]
