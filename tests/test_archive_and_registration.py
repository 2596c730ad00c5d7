"""Simulationarchive round trips, registration once per process, relocatable install."""
import os
import re
import shutil
import subprocess
import sys
import textwrap

import pytest
import rebound

import rebound_pfvi
from conftest import fixed_step_pfvi, two_planets

STATE = ("x", "y", "z", "vx", "vy", "vz")


def setup_sim(stages=2):
    sim = rebound.Simulation()
    sim.add(m=1.0)
    sim.add(m=1e-3, a=1.0, e=0.6)
    sim.add(m=0.0, a=1.7, e=0.2, inc=0.1)
    sim.move_to_com()
    fixed_step_pfvi(sim)
    sim.integrator.fitting = "phase"
    sim.integrator.u_max = 0.8
    sim.integrator.stages = stages
    sim.dt = 0.013
    return sim


def run_python(code, timeout=120):
    return subprocess.run([sys.executable, "-P", "-c", textwrap.dedent(code)], capture_output=True,
                          text=True, timeout=timeout)


@pytest.mark.parametrize("stages, fitting", [(2, "phase"), (3, "phase"), (4, "phase"), (5, "phase"), (6, "phase"),
                                             (2, "exact"), (4, "exact"), (6, "exact")])
def test_archive_round_trip_in_a_fresh_process_is_bit_identical(tmp_path, stages, fitting):
    # For s >= 3 this needs the last step's stage accelerations, which seed
    # the next solve, and for "exact" the positions they were evaluated at:
    # both are saved with the simulation.
    archive = tmp_path / "run.bin"
    sim = setup_sim(stages)
    if fitting == "exact":
        sim.integrator.fitting = "exact"
        sim.integrator.frequency = "radial"
        sim.integrator.centre = "partner"
    sim.integrate(7.3)
    sim.save_to_file(str(archive))
    sim.integrate(20.0)
    expected = [repr(getattr(p, f)) for p in sim.particles for f in STATE]
    result = run_python(f"""
        import rebound, rebound_pfvi
        sim = rebound.Simulation({str(archive)!r})
        assert str(sim.integrator) == "pfvi"
        assert sim.integrator.u_max == 0.8 and sim.integrator.fitting == {fitting!r}
        assert sim.integrator.stages == {stages}
        sim.integrate(20.0)
        print(" ".join(repr(getattr(p, f)) for p in sim.particles for f in {STATE!r}))
        print(sim.t, sim.integrator.n_steps, sim.integrator.n_iterations)
    """)
    assert result.returncode == 0, result.stderr
    lines = result.stdout.split("\n")
    assert lines[0].split() == expected
    assert float(lines[1].split()[0]) == sim.t
    assert int(lines[1].split()[1]) == sim.integrator.n_steps
    assert int(lines[1].split()[2]) == sim.integrator.n_iterations


@pytest.mark.parametrize("stages", [2, 4])
@pytest.mark.parametrize("fitting, centre", [("phase", "origin"), ("phase-literal", "origin"), ("none", "origin"),
                                             ("exact", "partner"), ("exact", "barycentre")])
def test_fields_survive_save_and_load(tmp_path, fitting, centre, stages):
    sim = setup_sim(stages)
    sim.integrator.fitting = fitting
    sim.integrator.centre = centre
    sim.integrator.frequency = "fixed"
    sim.integrator.omega = 0.25
    sim.integrate(1.0)
    path = str(tmp_path / "a.bin")
    sim.save_to_file(path)
    loaded = rebound.Simulation(path)
    assert str(loaded.integrator) == "pfvi"
    for field in ("fitting", "frequency", "centre", "omega", "stages", "u_max", "n_steps",
                  "n_u_limited", "n_force_evaluations", "omega_min", "omega_max",
                  "n_iterations", "iterations_max", "iterations_mean"):
        assert getattr(loaded.integrator, field) == getattr(sim.integrator, field), field


def test_registered_once_even_after_reimport_and_reload():
    # REBOUND 5.2.2 hangs on a second custom registration: a timeout here is the bug.
    result = run_python("""
        import ctypes, importlib, rebound
        import rebound_pfvi
        importlib.reload(rebound_pfvi._core)
        importlib.reload(rebound_pfvi)
        import rebound_pfvi
        names = rebound.clibrebound.reb_integrators_registered
        names.restype = ctypes.POINTER(ctypes.c_char_p)
        lst = names()
        found = []
        i = 0
        while lst[i]:
            found.append(lst[i].decode()); i += 1
        print(found.count("pfvi"))
        sim = rebound.Simulation(); sim.add(m=1.); sim.add(a=1.)
        sim.integrator = "pfvi"; sim.integrate(1.)
        print(sim.integrator)
    """, timeout=60)
    assert result.returncode == 0, result.stderr
    assert result.stdout.split() == ["1", "pfvi"]


def test_import_is_light():
    result = run_python("""
        import sys, rebound_pfvi
        print(sorted(m for m in ("astropy", "matplotlib", "dask", "scipy") if m in sys.modules))
    """)
    assert result.returncode == 0, result.stderr
    assert result.stdout.strip() == "[]"


def test_core_links_relocatably():
    core = rebound_pfvi._core._path
    out = subprocess.run(["readelf", "-d", core], capture_output=True, text=True)
    if out.returncode != 0:
        pytest.skip("readelf not available")
    paths = [line.split("[")[1].rstrip("]") for line in out.stdout.splitlines()
             if "RPATH" in line or "RUNPATH" in line]
    assert paths == ["$ORIGIN/.."]


def test_installed_package_still_imports_after_being_moved(tmp_path):
    site = os.path.dirname(os.path.dirname(os.path.abspath(rebound.__file__)))
    moved = tmp_path / "moved"
    moved.mkdir()
    shutil.copytree(os.path.dirname(rebound.__file__), moved / "rebound")
    shutil.copytree(os.path.dirname(rebound_pfvi.__file__), moved / "rebound_pfvi")
    for name in os.listdir(site):
        if name.startswith("librebound"):
            shutil.copy2(os.path.join(site, name), moved / name)
    result = run_python(f"""
        import sys
        sys.path.insert(0, {str(moved)!r})
        import rebound, rebound_pfvi
        assert rebound.__file__.startswith({str(moved)!r}), rebound.__file__
        assert rebound_pfvi.__file__.startswith({str(moved)!r})
        sim = rebound.Simulation(); sim.add(m=1.); sim.add(a=1.)
        sim.integrator = "pfvi"; sim.integrator.epsilon = 0.; sim.dt = 0.01; sim.integrate(1.)
        print(sim.integrator.n_steps)
    """)
    assert result.returncode == 0, result.stderr
    assert result.stdout.strip() == "100"


def test_a_rebound_installed_elsewhere_is_named_with_the_command_that_helps(tmp_path):
    # The guide's venv (--system-site-packages) with the system's rebound:
    # rebound_pfvi in one site-packages, rebound and its C library in another.
    # Rebuilding cannot help (the core finds librebound beside rebound_pfvi
    # only); installing that rebound into the environment does.
    site = os.path.dirname(os.path.dirname(os.path.abspath(rebound.__file__)))
    elsewhere = tmp_path / "venv-site"
    shutil.copytree(os.path.dirname(rebound_pfvi.__file__), elsewhere / "rebound_pfvi")
    result = run_python(f"""
        import sys
        sys.path.insert(0, {str(elsewhere)!r})
        import rebound
        assert not rebound.__file__.startswith({str(elsewhere)!r})
        import rebound_pfvi
    """)
    assert result.returncode != 0
    message = result.stderr.strip().splitlines()[-1]
    assert message.startswith("ImportError: rebound_pfvi: cannot load its C core " + str(elsewhere)), message
    assert f"in {elsewhere}, where rebound_pfvi is installed, but the running rebound {rebound.__version__} " \
           f"is installed in {site}" in message, message
    assert message.endswith(f"{sys.executable} -m pip install --ignore-installed --no-deps "
                            f"'rebound=={rebound.__version__}'"), message
    assert "Rebuild" not in message


def test_abi_check_refuses_a_core_built_against_another_rebound(monkeypatch):
    core = rebound_pfvi._core
    rebuild = f"{sys.executable} -m pip install --force-reinstall --no-deps "
    # Simulated: a core compiled against 5.1.1 under a running 5.2.2 (the
    # sizes alike: the versions alone are refused).
    message = core.abi_mismatch("5.1.1", "5.2.2", "5.2.2", (816, 112), (816, 112))
    assert message.startswith("rebound_pfvi's C core was compiled against rebound 5.1.1 "
                              "(sizeof(struct reb_simulation) = 816, sizeof(struct reb_particle) = 112) "
                              "but rebound 5.2.2 (C library 5.2.2, sizes 816 and 112) is running. "
                              "Rebuild rebound_pfvi against the running rebound: " + rebuild), message
    # A size alone, or the Python package and its C library disagreeing.
    assert core.abi_mismatch("5.2.2", "5.2.2", "5.2.2", (816, 112), (824, 112)) is not None
    assert core.abi_mismatch("5.2.2", "5.2.2", "5.1.1", (816, 112), (816, 112)) is not None
    assert core.abi_mismatch("5.2.2", "5.2.2", "5.2.2", (816, 112), (816, 112)) is None
    # The real check, the running version simulated.
    compiled = core.lib.pfvi_rebound_version_compiled().decode()
    assert compiled == rebound.__version__  # this build passed it
    monkeypatch.setattr(rebound, "__version__", "9.9.9")
    with pytest.raises(ImportError, match=rf"compiled against rebound {re.escape(compiled)} .* but rebound "
                                          rf"9\.9\.9 .*{re.escape(rebuild)}"):
        core._check_abi()


def test_rebuild_command_names_the_source_folder_pip_recorded():
    command = rebound_pfvi._core.rebuild_command()
    assert command.startswith(f"{sys.executable} -m pip install --force-reinstall --no-deps ")
    source = command.split()[-1]
    if source != "folder>":  # installed from a folder: pip's direct_url.json names it
        assert os.path.isfile(os.path.join(source, "pyproject.toml")), source


def test_documentation_lists_every_field():
    sim = rebound.Simulation()
    sim.integrator = "pfvi"
    doc = " ".join(sim.integrator.__doc__.split())
    assert "Kosmas and D. S. Vlachos, \"Phase-fitted Discrete Lagrangian Integrators\"" in doc
    for field in ("fitting", "frequency", "centre", "omega", "stages", "u_max", "epsilon", "step_control",
                  "n_steps", "n_u_limited", "n_force_evaluations", "n_iterations", "iterations_max",
                  "iterations_mean", "n_rejected", "n_attempts", "n_asymmetric", "error_estimate",
                  "omega_min", "omega_max"):
        assert f"{field} :" in doc
    assert "'phase-literal'" in doc
    assert (sim.integrator.fitting, sim.integrator.frequency, sim.integrator.centre, sim.integrator.stages,
            sim.integrator.u_max, sim.integrator.omega, sim.integrator.epsilon,
            sim.integrator.step_control) == ("none", "mean-motion", "partner", 8, 1.0, 0.0, 1e-6, "symmetric")


# Each scene empties one of the last step's buffers (stages, variational
# stages, end state) after an archive's first snapshot held it: written as a
# field header without data, REBOUND's reader crashed on the file (a
# hostile trial, six ways). Each ends with the snapshots after its last
# edit continuing the run bit for bit.
ARCHIVE_SCENES = {
    "megno, then stages = 2": """
        sim.init_megno(seed=3)
        sim.integrate(1.0)
        sim.save_to_file(path, interval=1.0, delete_file=True)
        sim.integrate(4.0)
        sim.integrator.stages = 2
        mark = sim.t
        sim.integrate(9.0)
    """,
    "a refused step after an added particle": """
        sim.integrate(1.0)
        sim.save_to_file(path, step=1, delete_file=True)
        sim.integrate(2.0)
        sim.add(m=1e-6, x=float("nan"), y=0.0, z=0.0)
        try:
            sim.integrate(3.0)
        except RuntimeError as e:
            assert "not finite" in str(e), e
        sim.remove(sim.N - 1)
        mark = sim.t
        sim.integrate(4.0)
    """,
    "megno, an edit, then a refused fixed step": """
        sim.init_megno(seed=3)
        sim.integrate(1.0)
        sim.save_to_file(path, step=1, delete_file=True)
        sim.integrate(2.0)
        sim.particles[2].vx *= 1.0001
        sim.integrator.epsilon = 0.0
        sim.dt = 50.0
        try:
            sim.integrate(100.0)
        except RuntimeError as e:
            assert "pfvi" in str(e), e
        sim.dt = 0.05
        mark = sim.t
        sim.integrate(sim.t + 1.0)
    """,
    "a load with fewer particles, then stages = 2": """
        sim.integrate(1.0)
        sim.save_to_file(path, delete_file=True)
        sim.integrate(2.0)
        sim.save_to_file(path)
        sim.remove(2)
        sim.save_to_file(path)
        sim = rebound.Simulationarchive(path)[-1]
        sim.integrator.stages = 2
        sim.save_to_file(path, interval=0.5)
        mark = sim.t
        sim.integrate(sim.t + 2.0)
    """,
}


@pytest.mark.parametrize("scene", list(ARCHIVE_SCENES))
def test_an_archive_whose_run_empties_a_step_buffer_opens_and_continues_the_run(tmp_path, scene):
    # In a child process, so that the old crash fails this test instead of the suite.
    body = textwrap.indent(textwrap.dedent(ARCHIVE_SCENES[scene]), "        ")
    code = f"""
        import rebound, rebound_pfvi
        path = {str(tmp_path / "run.bin")!r}
        sim = rebound.Simulation()
        sim.add(m=1.0)
        sim.add(m=1e-3, a=1.0, e=0.3)
        sim.add(m=1e-3, a=1.7, e=0.1)
        sim.move_to_com()
        sim.integrator = "pfvi"
{body}
        end, final = sim.t, [p.xyz + p.vxyz for p in sim.particles]
        archive = rebound.Simulationarchive(path)
        later = 0
        for k in range(len(archive)):
            again = archive[k]            # every snapshot loads
            if again.t > mark:
                again.integrate(end)
                assert again.t == end, (k, again.t, end)
                assert [p.xyz + p.vxyz for p in again.particles] == final, k
                later += 1
        assert later >= 2, later
        print("ok", len(archive), later)
    """
    out = run_python(code)
    assert out.returncode == 0 and out.stdout.startswith("ok"), (out.returncode, out.stdout, out.stderr[-2000:])


@pytest.mark.parametrize("how", ["copy", "archive"])
@pytest.mark.parametrize("edit", ["G", "softening", "N_active"])
def test_a_force_model_edited_on_a_copy_at_an_output_starts_from_the_shown_state(tmp_path, how, edit):
    # A copy (or a snapshot) taken at an output keeps the run's own state for
    # the next step only if the force model is the one it was drawn under:
    # with G changed on the copy it went on from a state drawn under the old
    # G, 9e-5 off the original given the same edit (a hostile trial).
    build = two_planets
    sim = build()
    sim.integrate(1.0)
    sim.integrate(2.0)
    assert sim.integrator.n_outputs >= 1
    if how == "copy":
        other = sim.copy()
    else:
        path = str(tmp_path / "at-output.bin")
        sim.save_to_file(path)
        other = rebound.Simulationarchive(path)[-1]
    for s in (sim, other):
        if edit == "G":
            s.G = 1.0001
        elif edit == "softening":
            s.softening = 1e-3
        else:
            s.testparticle_hidewarnings = 1   # (the third body becomes a test particle of mass 1e-3)
            s.N_active = 2
        s.integrate(5.0)
    assert [p.xyz + p.vxyz for p in other.particles] == [p.xyz + p.vxyz for p in sim.particles]


@pytest.mark.parametrize("direction", [1.0, -1.0])
@pytest.mark.parametrize("variational", [False, True])
def test_an_archive_begun_after_an_output_opens_and_every_snapshot_continues_the_run(tmp_path, direction,
                                                                                      variational):
    # REBOUND stores each snapshot after the first as a difference from the
    # first; a buffer saved there (a shown output's) and empty later was
    # written as a field header without its data, and opening the file
    # crashed REBOUND's reader (a hostile trial). Opened in a child process,
    # so that the old crash fails this test instead of the suite.
    archive = tmp_path / "begun-mid-run.bin"
    code = f"""
        import rebound, rebound_pfvi
        sim = rebound.Simulation()
        sim.add(m=1.0)
        sim.add(m=1e-3, a=1.0, e=0.5)
        sim.add(m=1e-4, a=2.0, e=0.1, inc=0.2)
        sim.add(m=0.0, a=1.5, e=0.6)
        sim.move_to_com()
        sim.integrator = "pfvi"
        if {variational}:
            sim.init_megno(seed=3)
        sim.integrate(10.0)            # an output shown: its buffers are saved in the first snapshot
        sim.save_to_file({str(archive)!r}, interval=1.0, delete_file=True)
        end = 10.0 + {direction}*6.0
        sim.integrate(end)
        final = [p.xyz + p.vxyz for p in sim.particles]
        archive = rebound.Simulationarchive({str(archive)!r})
        assert len(archive) >= 6, len(archive)
        for k in range(len(archive)):
            again = archive[k]
            again.integrate(end)
            assert again.t == sim.t, (k, again.t, sim.t)
            assert [p.xyz + p.vxyz for p in again.particles] == final, k
        print("ok", len(archive))
    """
    out = run_python(code)
    assert out.returncode == 0 and out.stdout.startswith("ok"), (out.returncode, out.stdout, out.stderr[-2000:])


def four_bodies():
    sim = two_planets()
    sim.add(m=0.0, a=2.4, e=0.6)
    sim.move_to_com()
    return sim


def damping(simp):
    s = simp.contents
    for p in s.particles[1:s.N]:
        p.vx *= 1.0 - 1e-5*s.dt_last_done
        p.vy *= 1.0 - 1e-5*s.dt_last_done


@pytest.mark.parametrize("case", ["reversible-s3", "reversible-s8", "backward-with-hook"])
def test_interval_snapshots_between_two_finishing_steps_restart_bit_identically(tmp_path, case):
    # An interval archive written during outputs: where the step control cut
    # a finishing step short of the time, REBOUND cut again without a new last
    # full step, and restores the step before the first after the call; a
    # snapshot written between the two began its restart on the cut and kept
    # it (a hostile trial: 'reversible' s = 3, 3.5e-10 off; backwards with a
    # post-timestep hook, 2e-16).
    path = str(tmp_path / "run.bin")

    def build():
        sim = four_bodies()
        if case.startswith("reversible"):
            sim.integrator.step_control = "reversible"
            sim.integrator.stages = int(case[-1])
        else:
            sim.post_timestep_modifications = damping
        return sim

    sim = build()
    if case.startswith("reversible"):
        times = [0.37*j for j in range(1, 14)]
    else:
        sim.integrate(6.0)
        times = [6.0 - 0.37*j for j in range(1, 14)]
    sim.save_to_file(path, interval=0.29, delete_file=True)
    for t in times:
        sim.integrate(t)
    final = [p.xyz + p.vxyz for p in sim.particles]
    archive = rebound.Simulationarchive(path)
    assert len(archive) >= 15
    for k in range(len(archive)):
        again = archive[k]
        if not case.startswith("reversible"):
            again.post_timestep_modifications = damping
        for t in times:
            if (t - again.t)*(times[-1] - times[0]) > 0:
                again.integrate(t)
        assert [p.xyz + p.vxyz for p in again.particles] == final, f"snapshot {k} at t = {archive[k].t}"
