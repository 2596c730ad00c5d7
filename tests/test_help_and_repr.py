"""What a user reads about the integrator: help(sim.integrator) complete
without the repository, repr showing options and statistics (no scratch
pointers), and the README's statements on when options are checked and on
loading archives."""
import re
import subprocess
import sys

import pytest
import rebound

import rebound_pfvi

OPTIONS = ("fitting", "frequency", "centre", "omega", "stages", "u_max", "epsilon", "step_control")


def pfvi():
    sim = rebound.Simulation()
    sim.add(m=1.0)
    sim.add(m=1e-3, a=1.0, e=0.5)
    sim.integrator = "pfvi"
    return sim


def documented_fields(sim):
    return [fd.name.decode() for fd in sim.integrator.callbacks.field_descriptor_list if fd.documentation]


def test_help_documents_every_option_with_its_default_and_no_repository_paths():
    sim = pfvi()
    doc = sim.integrator.__doc__
    fields = documented_fields(sim)
    assert set(OPTIONS) <= set(fields)
    for name in fields:
        assert re.search(rf"^{name} : ", doc, re.M), name
    sections = re.split(r"^(\w+) : .*$", doc, flags=re.M)
    text = dict(zip(sections[1::2], sections[2::2]))
    for name in OPTIONS:
        assert "Default" in text[name], name
    # References by title, not by the seed's section numbers or files an installed package lacks.
    flat = " ".join(doc.split())
    assert "seed section" not in flat and ".md" not in flat
    assert "Phase-fitted Discrete Lagrangian Integrators" in flat


def test_constants_in_the_help_are_the_ones_in_force():
    sim = pfvi()
    doc = " ".join(sim.integrator.__doc__.split())
    assert sim.integrator.epsilon == 1e-6 and "Default 1e-6" in doc
    assert sim.integrator.u_max == 1.0 and "Default 1.0," in doc
    assert "an integer from 2 to 8" in doc and rebound_pfvi.STAGES == (2, 3, 4, 5, 6, 7, 8)


def test_repr_shows_options_and_statistics_and_no_scratch_pointers():
    sim = pfvi()
    sim.integrate(1.0)
    text = repr(sim.integrator)
    for name in documented_fields(sim):
        assert f"{name}=" in text
    assert "fitting=none" in text and "centre=partner" in text and "step_control=symmetric" in text
    assert "compensation" not in text and "stage_accelerations" not in text
    assert len(re.findall(r"0x[0-9a-f]+", text)) == 1  # the object's own address only
    ias15 = rebound.Simulation()
    ias15.integrator = "ias15"
    assert "epsilon=" in repr(ias15.integrator)  # other integrators keep REBOUND's repr


def test_options_are_checked_when_the_next_step_starts_as_the_readme_says():
    sim = pfvi()
    sim.integrator.stages = 9  # accepted on assignment
    before = (sim.t, sim.particles[1].x)
    with pytest.raises(RuntimeError, match=r"^pfvi: integrator.stages = 9 is not supported; allowed: 2 to 8.$"):
        sim.integrate(1.0)
    assert (sim.t, sim.particles[1].x) == before
    with pytest.raises(TypeError):
        sim.integrator.stages = 2.5


def test_an_archive_needs_the_import_as_the_readme_says(tmp_path):
    path = tmp_path / "archive.bin"
    sim = pfvi()
    sim.integrate(0.5)
    sim.save_to_file(str(path))
    load = ("import rebound{}\nsa = rebound.Simulationarchive({!r})\nprint(sa[-1].integrator, sa[-1].t)")
    without = subprocess.run([sys.executable, "-P", "-c", load.format("", str(path))],
                             capture_output=True, text=True)
    assert without.returncode != 0
    assert "Integrator not found." in without.stderr
    assert "seems to be corrupted" in without.stderr
    with_import = subprocess.run([sys.executable, "-P", "-c", load.format("\nimport rebound_pfvi", str(path))],
                                 capture_output=True, text=True, check=True)
    assert with_import.stdout.split() == ["pfvi", "0.5"]


def test_module_help_lists_every_field_with_the_cores_default():
    # help(rebound_pfvi) is generated from the core's field list at import:
    # a field added to the core is in it, with the default a new simulation has.
    doc = rebound_pfvi.__doc__
    sim = pfvi()
    for name in documented_fields(sim):
        assert re.search(rf"^    {name}\b", doc, re.M), name
    for name, value in rebound_pfvi.DEFAULTS.items():
        assert f"    {name} = {value!r}:" in doc
        assert getattr(sim.integrator, name) == value
    assert "sim.dt =" not in doc.split("Options")[0].split("::")[1]  # the example needs no dt


def test_a_compare_setting_runs_pfvi_at_the_cores_defaults_but_what_it_names():
    from rebound_pfvi import compare, scenes

    scene = scenes.Kepler(e=0.5, periods=1)
    for options, label in (((), "pfvi s=8"), ((("stages", 6),), "pfvi s=6"),
                           ((("stages", 4), ("fitting", "phase")), "pfvi seed s=4 phase")):
        setting = compare.Setting("pfvi", 1e-8, options)
        assert setting.line == label
        sim = scene.build()
        compare.configure(sim, scene, setting)
        expected = {**rebound_pfvi.DEFAULTS, "epsilon": 1e-8, **dict(options)}
        if dict(options).get("fitting") == "phase":
            expected.update(frequency="curvature", centre="origin")  # the seed's scheme
        assert {name: getattr(sim.integrator, name) for name in expected} == expected


def test_help_opens_with_a_short_summary_naming_the_epsilon_that_matches_ias15():
    """Issue 41: help(sim.integrator) ran to 346 lines with no summary first;
    it opens with at most 15 lines (REBOUND's title, a blank, the summary)
    that say what the default epsilon buys and which epsilon matches IAS15."""
    lines = pfvi().integrator.__doc__.splitlines()
    end = lines.index("", 2)  # the blank line after the summary
    assert end <= 15, lines[:end]
    summary = " ".join(lines[2:end])
    assert summary.startswith("In short:")
    assert "sim.integrator.epsilon = 1e-12" in summary and "IAS15's default error" in summary
    assert "default 1e-6" in summary
