"""REBOUNDx forces with pfvi (issue 18, item 7): Mercury with REBOUNDx's
velocity-dependent "gr" force against IAS15, and the scene `mercury-gr`.

The tests that need reboundx are skipped without it (the `reboundx` extra);
the first two run everywhere. `pytest -k reboundx` selects this file.
"""
import json
import math
import subprocess
import sys

import pytest
import rebound

from rebound_pfvi import compare, scenes
from rebound_pfvi.integrators import SEED_MODEL
from rebound_pfvi.__main__ import main


def test_missing_reboundx_names_the_extra(monkeypatch, capsys):
    monkeypatch.setitem(sys.modules, "reboundx", None)  # import reboundx now fails
    with pytest.raises(ImportError, match=r"rebound_pfvi\[reboundx\]"):
        scenes.MercuryGR()
    with pytest.raises(SystemExit) as stop:
        main(["compare", "--scene", "mercury-gr"])
    assert stop.value.code == 2
    assert 'pip install "rebound_pfvi[reboundx]"' in capsys.readouterr().err


def test_import_does_not_import_reboundx():
    code = ("import sys, rebound_pfvi, rebound_pfvi.scenes, rebound_pfvi.compare, rebound_pfvi.__main__ as cli; "
            "cli.build_parser(); print(sorted(m for m in ('reboundx', 'astropy', 'matplotlib') if m in sys.modules))")
    out = subprocess.run([sys.executable, "-P", "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "[]"


def _advance(integrator, epsilon, gr=True, velocity_dependent=None):
    """Perihelion advance of Mercury over the scene's 415 orbits, in rad."""
    scene = scenes.MercuryGR()
    sim = scene.build()
    if not gr:  # the same simulation, Newtonian
        sim = scenes.new_simulation()
        sim.add(m=1.0)
        sim.add(m=scene.MASS, a=scene.A, e=scene.E)
        sim.move_to_com()
    sim.integrator = integrator
    if integrator == "pfvi":  # as measured: the seed's scheme and the osculating-circle control
        sim.integrator.fitting = "phase"
        sim.integrator.step_control = "reversible"
        for name, value in SEED_MODEL.items():
            setattr(sim.integrator, name, value)
    sim.integrator.epsilon = epsilon
    sim.dt = scene.period / (10.0 if integrator == "pfvi" else 100.0)
    if velocity_dependent is not None:
        sim.force_is_velocity_dependent = velocity_dependent
    start = scene.perihelion_longitude(sim)
    sim.integrate(scene.t_end)
    return math.remainder(scene.perihelion_longitude(sim) - start, 2.0 * math.pi)


def test_pfvi_with_reboundx_gr_advances_perihelion_as_ias15():
    pytest.importorskip("reboundx")
    assert scenes.MercuryGR().build().force_is_velocity_dependent == 1  # REBOUNDx sets it for "gr"
    ias15 = _advance("ias15", 1e-9)
    # 43 arcsec/century: 6 pi G (M + m) / (c^2 a (1 - e^2)) per orbit. The run
    # ends at perihelion after whole orbits, where the osculating elements'
    # short-period terms are those of the start: measured 3.4e-6 relative.
    scene, c = scenes.MercuryGR(), scenes.SPEED_OF_LIGHT_AU_YR
    textbook = (6 * math.pi * scenes.rebound_G() * (1 + scene.MASS) / (c * c * scene.A * (1 - scene.E**2))
                * scene.periods)
    assert ias15 == pytest.approx(textbook, rel=1e-4)
    assert abs(_advance("ias15", 1e-9, gr=False)) < 1e-13  # IAS15 adds no precession of its own
    # pfvi at epsilon 1e-8 (s = 4, "phase"): measured 3.55e-10 rad from IAS15,
    # 1.7e-6 of the advance. That difference is pfvi's own (Newtonian)
    # precession at this tolerance, the same with the force off (measured
    # -3.55e-10 rad); gr's part alone equals IAS15's to 5e-14 rad (measured).
    # Tolerances: about 3 times and 20 times the measured differences.
    pfvi = _advance("pfvi", 1e-8)
    assert abs(pfvi - ias15) < 1e-9
    newtonian = _advance("pfvi", 1e-8, gr=False)
    assert abs((pfvi - newtonian) - ias15) < 1e-12
    # The check can fail: told that the force is not velocity dependent,
    # pfvi evaluates "gr" with predicted velocities and gr's part is
    # 4.4e-8 rad off (measured).
    wrong = _advance("pfvi", 1e-8, velocity_dependent=0)
    assert abs((wrong - newtonian) - ias15) > 1e-8


# REBOUNDx warns that WHFast takes a velocity-dependent force approximately;
# the comparison shows how much (the WHFast rows).
@pytest.mark.filterwarnings("ignore:.*velocity-dependent force to WHFAST:RuntimeWarning")
def test_mercury_gr_compare_short_run_reboundx(tmp_path):
    pytest.importorskip("reboundx")
    out = tmp_path / "results"
    code = main(["compare", "--scene", "mercury-gr", "--periods", "10", "--repeats", "1", "--samples", "4",
                 "--workers", "1", "--output", str(out)])
    assert code == 0
    data = json.loads((out / "mercury-gr.json").read_text())
    rows = data["rows"]
    assert data["finished"] == data["settings"] == len(compare.default_settings(scenes.MercuryGR()))
    assert {r["family"] for r in rows if r["status"] == "ok"} == set(compare.FAMILIES)
    ok = [r for r in rows if r["status"] == "ok"]
    best = {f: min(r["position_error"] for r in ok if r["family"] == f) for f in compare.FAMILIES}
    assert best["ias15"] < 1e-10 and best["pfvi"] < 1e-8 and best["bs"] < 1e-8
    for row in rows:
        if row["family"] == "pfvi" and row["status"] == "ok":
            # The scene's counting wrapper around REBOUNDx's force sees every evaluation pfvi counts.
            assert row["force_evaluations"] == row["pfvi_force_evaluations"]
    # The energy is REBOUNDx's "gr" Hamiltonian, which IAS15 conserves to round-off.
    assert min(r["energy_error_max"] for r in rows if r["family"] == "ias15") < 1e-13
    assert "Mercury with REBOUNDx gr" in (out / "mercury-gr.md").read_text()


def test_counting_wrapper_leaves_the_run_bit_identical_reboundx():
    pytest.importorskip("reboundx")
    scene = scenes.MercuryGR(periods=2)
    runs = []
    for counter in (None, [0]):
        sim = scene.build(counter=counter)
        compare.configure(sim, scene, compare.Setting("pfvi", 1e-7))
        sim.integrate(scene.t_end)
        runs.append([(p.x, p.y, p.vx, p.vy) for p in sim.particles])
    assert runs[0] == runs[1]
    assert counter[0] == sim.integrator.n_force_evaluations > 0


# REBOUNDx operators (issue 40, item 2): rx.add_operator(op) places an
# operator for "pfvi" as for IAS15 (after the step, the whole dt: rebound_pfvi
# wraps REBOUNDx's add_operator), and the operators act over exactly the time
# each output's state lived (docs/outputs.md). Before, REBOUNDx added nothing
# for "pfvi": a stayed 1.000000.
def _operator_run(integrator, name, outputs):
    import rebound
    reboundx = pytest.importorskip("reboundx")
    sim = rebound.Simulation()
    sim.integrator = integrator
    sim.add(m=1.0)
    sim.add(m=1e-3, a=1.0)
    sim.move_to_com()
    rx = reboundx.Extras(sim)
    op = rx.load_operator(name)
    rx.add_operator(op)
    if name == "modify_orbits_direct":
        sim.particles[1].params["tau_a"] = -1e3
    else:
        sim.particles[0].params["tau_mass"] = -1e3
    for k in range(outputs):
        sim.integrate(500.0 * (k + 1) / outputs)
    assert sim.t == pytest.approx(500.0, rel=1e-12, abs=0)
    return sim.particles[1].a if name == "modify_orbits_direct" else sim.particles[0].m


@pytest.mark.filterwarnings("ignore::RuntimeWarning")  # REBOUNDx's "do not change the integrator"
@pytest.mark.parametrize("outputs", [1, 40, 700])
@pytest.mark.parametrize("name, bound", [("modify_orbits_direct", 3e-4), ("modify_mass", 8e-4)])
def test_reboundx_operators_land_after_the_step_at_outputs(name, bound, outputs):
    # exp(-500/1e3) for both; the operators are split from the step (first
    # order in it): IAS15's thousands of steps measured 3.1e-5 and 7.5e-5 off,
    # pfvi's fewer steps 1.6e-4 and 3.9e-4 (benchmarks/reboundx_operators.py).
    exact = math.exp(-0.5)
    ias15 = _operator_run("ias15", name, outputs)
    pfvi = _operator_run("pfvi", name, outputs)
    assert abs(ias15 - exact) / exact < 1e-4
    assert abs(pfvi - exact) / exact < bound


def test_reboundx_add_operator_keeps_explicit_placements_and_recorders():
    import rebound
    reboundx = pytest.importorskip("reboundx")
    assert getattr(reboundx.Extras.add_operator, "_pfvi", False)
    sim = rebound.Simulation()
    sim.integrator = "pfvi"
    rx = reboundx.Extras(sim)
    rx.add_operator(rx.load_operator("track_min_distance"))  # REBOUNDx's own: once after the step
    assert bool(rx._post_timestep_modifications) and not rx._pre_timestep_modifications
    rx.add_operator(rx.load_operator("modify_mass"), dtfraction=0.5, timing="pre")  # as asked
    assert bool(rx._pre_timestep_modifications)


@pytest.mark.filterwarnings("ignore::RuntimeWarning")
@pytest.mark.parametrize("outputs", [1, 40])
def test_reboundx_tides_spin_ode_converges_with_epsilon(outputs):
    # REBOUNDx's tides_spin: an ODE for the spins beside a force that depends
    # on them. Before, pfvi refused it (sim.dt capped every step with the ODE
    # set, leaving slivers of the track's interval down to 5e-18). The spin
    # after 5 time units against BS at 1e-13 (IAS15 at its default: 8e-5
    # off). Measured, 1 output: pfvi at 1e-6 (default) 1.1e-3, at 1e-11 4e-6.
    pytest.importorskip("reboundx")
    sys.path.insert(0, str(__import__("pathlib").Path(__file__).resolve().parents[1] / "benchmarks"))
    import reboundx_operators as bench

    def spin(integrator, epsilon, n):
        sim, measure, _ = bench.tides_spin(integrator)
        if integrator == "bs":
            sim.integrator.eps_rel = sim.integrator.eps_abs = epsilon
        else:
            sim.integrator.epsilon = epsilon
        for k in range(n):
            sim.integrate(5.0 * (k + 1) / n)
        return measure(sim)

    reference = spin("bs", 1e-13, 1)
    assert abs(spin("pfvi", 1e-6, outputs) - reference) / reference < 2e-3
    assert abs(spin("pfvi", 1e-11, outputs) - reference) / reference < 2e-5


@pytest.mark.parametrize("first", ["rebound_pfvi", "reboundx"])
def test_add_operator_is_wrapped_whichever_is_imported_first(first):
    pytest.importorskip("reboundx")
    second = "reboundx" if first == "rebound_pfvi" else "rebound_pfvi"
    code = (f"import rebound, {first}, {second}, reboundx; "
            "print(getattr(reboundx.Extras.add_operator, '_pfvi', False))")
    out = subprocess.run([sys.executable, "-P", "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "True"


def test_a_reboundx_error_inside_the_forces_refuses_the_step_reboundx():
    # "gr" without the speed of light: REBOUNDx raises inside the force call;
    # the step that had called it was taken (IAS15 still takes one).
    reboundx = pytest.importorskip("reboundx")
    import rebound

    sim = rebound.Simulation()
    sim.add(m=1.0)
    sim.add(m=1e-3, a=1.0, e=0.5)
    sim.move_to_com()
    sim.integrator = "pfvi"
    rx = reboundx.Extras(sim)
    rx.add_force(rx.load_force("gr"))
    before = (sim.t, [(p.x, p.y, p.z, p.vx, p.vy, p.vz) for p in sim.particles])
    with pytest.raises(RuntimeError, match="Need to set speed of light"):
        sim.integrate(10.0)
    assert (sim.t, [(p.x, p.y, p.z, p.vx, p.vy, p.vz) for p in sim.particles]) == before


@pytest.mark.parametrize("change", ["add a force", "remove a force", "change a parameter"])
def test_a_reboundx_change_between_calls_acts_from_the_output(change):
    # REBOUNDx's forces sit behind one additional_forces pointer: pfvi sees a
    # force added, removed or re-parametrised between calls only by the forces
    # themselves (pfvi_output_forces_hold). Before: 3.2e-4, 4.1e-4 and 7.9e-3
    # off IAS15, the run going on from its step past the output.
    reboundx = pytest.importorskip("reboundx")
    import numpy as np
    import rebound

    def run(integrator):
        sim = rebound.Simulation()
        sim.add(m=1.0)
        sim.add(m=1e-3, a=1.0, e=0.5)
        sim.add(m=1e-3, a=2.2, e=0.1, inc=0.2)
        sim.move_to_com()
        sim.integrator = integrator
        sim.integrator.epsilon = 1e-10 if integrator == "pfvi" else 1e-12
        rx = reboundx.Extras(sim)
        gr = rx.load_force("gr")
        gr.params["c"] = 30.0
        rx.add_force(gr)
        migration = rx.load_force("modify_orbits_forces")
        if change == "remove a force":
            rx.add_force(migration)
            sim.particles[1].params["tau_a"] = -20.0
        sim.integrate(3.3)
        if change == "add a force":
            rx.add_force(migration)
            sim.particles[1].params["tau_a"] = -20.0
        elif change == "remove a force":
            rx.remove_force(migration)
        else:
            gr.params["c"] = 10.0
        sim.integrate(9.7)
        return np.array([[p.x, p.y, p.z] for p in sim.particles])

    pfvi, ias15 = run("pfvi"), run("ias15")
    assert np.max(np.abs(pfvi - ias15)) < 1e-9*np.max(np.abs(ias15))


@pytest.mark.filterwarnings("ignore::RuntimeWarning")  # REBOUNDx's "10 iterations in gr.c failed to converge"
def test_a_force_not_finite_at_a_first_iterate_halves_the_step():
    # REBOUNDx's gr with c = 30 on e = 0.84 gives inf at a stage point of a
    # long step's first iterate (its own iteration diverges there), while
    # the orbit itself stays where it is finite. Until 2026-11-29 pfvi
    # refused at t = 23.06 ("the force on particle 0 is not finite") where
    # IAS15 went on; the step is now halved as for a solve that did not
    # converge, and the run ends 2.6e-8 from IAS15 at epsilon 1e-12.
    reboundx = pytest.importorskip("reboundx")
    ends = {}
    for integrator in ("ias15", "pfvi"):
        sim = rebound.Simulation()
        sim.add(m=1.0)
        sim.add(m=1e-3, a=1.0, e=0.84, f=math.pi, inc=0.3)
        sim.move_to_com()
        rebx = reboundx.Extras(sim)
        gr = rebx.load_force("gr")
        rebx.add_force(gr)
        gr.params["c"] = 30.0
        sim.integrator = integrator
        if integrator == "ias15":
            sim.integrator.epsilon = 1e-12
        for k in range(1, 16):
            sim.integrate(2.0 * k)
        ends[integrator] = [c for p in sim.particles for c in p.xyz]
    assert max(abs(a - b) for a, b in zip(ends["pfvi"], ends["ias15"])) < 1e-6
