"""Whether this build and another (--baseline) give the same bits: a set of
runs as users make them (pages' scenes, flybys, retrograde crossings,
binaries with planets, test particles of both types, softening, the
two-point and s-point schemes with every fitting, the seed and reversible
step controls, outputs, a reversal, contacts, MEGNO and variational
particles (the variational particles' states compared too), force callbacks of
positions and of velocities, REBOUNDx's gr and gr_potential), each run by both builds in
child processes; prints each run's verdict (same bits, or the largest
coordinate difference; where only the variational particles differ, and
MEGNO with them, the real trajectory's bits said apart with the
variational state's largest difference relative to its largest value) and
the count.

    python -P benchmarks/same_bits.py --baseline "PYTHONPATH=<other build> python3"

For a change meant to leave every trajectory as it was (a faster path to
the same arithmetic), every line must say "same bits". For one of the
tangent solve's alone, every real trajectory must.
"""
import argparse
import hashlib
import importlib.util
import json
import shlex
import subprocess
import sys

CHILD = r"""
import json, math, sys
import rebound, rebound_pfvi
from rebound_pfvi import scenes
name = sys.argv[1]

def planets(sim, inc=0.2):
    sim.add(m=1.0)
    sim.add(m=1e-3, a=1.0, e=0.3, inc=0.05, f=0.4)
    sim.add(m=3e-4, a=2.1, e=0.25, inc=inc, f=2.5)

sim = rebound.Simulation()
times = [None]
if name.startswith("scene:"):
    scene = scenes.make(name.split(":")[1])
    sim = scene.build()
    times = [scene.t_end]
elif name.startswith("kepler-e"):
    e, f = (float(x) for x in name[8:].split("-f"))
    sim.add(m=1.0)
    sim.add(m=1e-3, a=1.0, e=e, f=f)
    times = [30.0]
elif name.startswith("retrograde-i"):
    planets(sim)
    sim.add(m=0.0, a=0.6, e=0.2, inc=float(name[12:]), f=1.0)
    times = [40.0]
elif name == "flyby":
    planets(sim)
    sim.add(m=0.2, x=-30.0, y=0.7, z=0.1, vx=2.5)
    times = [25.0]
elif name == "binary-planet":
    sim.add(m=1.0)
    sim.add(m=0.4, a=0.15, e=0.4)
    sim.add(m=1e-3, a=1.5, e=0.1, inc=0.3, primary=None)
    times = [30.0]
elif name.startswith("testparticles-type"):
    planets(sim)
    for k in range(4):
        sim.add(m=1e-8, a=0.5 + 0.7 * k, e=0.5, inc=0.9 * k, f=k)
    sim.N_active = 3
    sim.testparticle_type = int(name[-1])
    sim.testparticle_hidewarnings = 1
    times = [20.0]
elif name == "softened":
    sim.softening = 0.02
    planets(sim)
    times = [20.0]
elif name.startswith("stages"):
    s, fitting = name[6:].split("-", 1)
    planets(sim)
    times = [15.0]
elif name.endswith("-control"):
    planets(sim)
    times = [6.0]
elif name == "outputs":
    planets(sim)
    times = [0.37 * k for k in range(1, 80)]
elif name == "reversal":
    planets(sim)
    times = [20.0, "flip", 0.0]
elif name == "contacts":
    planets(sim)
    sim.add(m=1e-6, a=1.0, e=0.0, f=0.9, r=1e-3)
    sim.particles[1].r = 5e-3
    sim.collision = "direct"
    sim.collision_resolve = "merge"
    times = [60.0]
elif name == "megno":
    planets(sim)
    times = ["megno", 20.0]
elif name in ("variations", "variations-testparticles", "variation-of-one"):
    # Two variations of every particle (one varying a mass), over a
    # reversal; with test particles pulling; a test particle's variation.
    planets(sim)
    if name.endswith("testparticles"):
        sim.add(m=1e-8, a=1.6, e=0.6, inc=2.7, f=1.0)
        sim.N_active = 3
        sim.testparticle_type = 1
        sim.testparticle_hidewarnings = 1
    times = [name.split("-")[0], 15.0, "flip", 3.0]
elif name == "variations-pull":
    # Variations of every particle beside a force callback of positions
    # that adds its variational term too, over a reversal.
    planets(sim)
    def force(simp):
        s = simp.contents
        for p in s.particles[:s.N]:
            p.az -= 0.05 * p.z
        for v in range(s.N_var):
            s._particles_var[v].az -= 0.05 * s._particles_var[v].z
    sim.additional_forces = force
    sim.force_is_velocity_dependent = 0
    times = ["variations", 12.0, "flip", 3.0]
elif name in ("pull", "drag"):
    # A force callback of positions alone, and one of velocities too
    # (called beside pfvi's own gravity pass at each stage).
    planets(sim)
    def force(simp, drag=(name == "drag")):
        ps = simp.contents.particles
        for i in range(1, simp.contents.N):
            if drag:
                ps[i].ax -= 0.02 * ps[i].vx
                ps[i].ay -= 0.02 * ps[i].vy
            else:
                ps[i].az -= 0.05 * ps[i].z
    sim.additional_forces = force
    sim.force_is_velocity_dependent = int(name == "drag")
    times = [12.0]
elif name.startswith("reboundx-"):
    import reboundx
    planets(sim)
    extras = reboundx.Extras(sim)
    effect = extras.load_force(name[9:])
    extras.add_force(effect)
    effect.params["c"] = 30.0   # (strong, so that it shows in the last bits)
    times = [12.0]
sim.move_to_com()
sim.integrator = "pfvi"
if name.startswith("stages"):
    sim.integrator.stages = int(s)
    sim.integrator.fitting = fitting
if name.endswith("-control"):
    sim.integrator.step_control = name.split("-")[0]
for t in times:
    if t is None:
        continue
    if t == "flip":
        sim.dt *= -1
    elif t == "megno":
        sim.init_megno(seed=1)  # (its deviation vectors are random otherwise)
    elif t == "variations":
        var = sim.add_variation()
        var.particles[1].x, var.particles[2].vy, var.particles[1].m = 1e-3, 1e-4, 1e-5
        sim.add_variation().particles[2].z = 1e-6
    elif t == "variation":
        sim.add_variation(testparticle=1).particles[0].vx = 1e-5
    else:
        sim.integrate(t)
real = [[p.x, p.y, p.z, p.vx, p.vy, p.vz, p.m] for p in sim.particles] + [[sim.t, sim.integrator.n_steps]]
ps_var = sim._particles_var
variational = [[ps_var[i].x, ps_var[i].y, ps_var[i].z, ps_var[i].vx, ps_var[i].vy, ps_var[i].vz] for i in range(sim.N_var)]
if name == "megno":
    variational.append([sim.megno()])
print(json.dumps({"real": real, "variational": variational}))
"""

RUNS = (["scene:" + s for s in ("kepler", "comet", "triple", "jupiter-comet", "retrograde", "sungrazer",
                                "circumbinary", "outer-solar-system", "periodic-box")]
        + [f"kepler-e{e}-f{f}" for e in (0.0, 0.3, 0.6, 0.9, 0.97) for f in (0.0, 3.14159)]
        + [f"retrograde-i{i}" for i in (0.0, 1.2, 1.9, 2.6, 3.14159)]
        + ["flyby", "binary-planet", "testparticles-type0", "testparticles-type1", "softened"]
        + [f"stages{s}-{f}" for s in (3, 4, 6, 8) for f in ("none", "phase", "exact")]
        + [f"stages2-{f}" for f in ("none", "phase", "exact", "phase-literal")]   # the two-point scheme
        + ["stages5-phase-literal", "stages7-none", "seed-control", "reversible-control"]
        + ["outputs", "reversal", "contacts", "megno", "variations", "variations-testparticles",
           "variation-of-one", "variations-pull", "pull", "drag"]
        # (REBOUNDx's forces where it is installed: an optional extra)
        + (["reboundx-gr", "reboundx-gr_potential"] if importlib.util.find_spec("reboundx") else []))


def run(prefix, name):
    out = subprocess.run(["env"] + prefix + ["-P", "-c", CHILD, name], capture_output=True, text=True)
    if out.returncode != 0:
        return {"error": out.stderr.strip().splitlines()[-1] if out.stderr.strip() else "failed"}
    return json.loads(out.stdout)


def largest_difference(a, b):
    return max((abs(x - y) for ra, rb in zip(a, b) for x, y in zip(ra, rb)), default=0.0)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--baseline", required=True)
    args = parser.parse_args()
    same = same_real = 0
    for name in RUNS:
        a, b = run([sys.executable], name), run(shlex.split(args.baseline), name)
        if a == b:
            same += 1
            digest = hashlib.sha1(json.dumps(a).encode()).hexdigest()[:10]
            print(f"{name}: same bits ({digest})")
        elif "error" in a or "error" in b:
            print(f"{name}: DIFFERENT (this: {a.get('error', 'ran')}; baseline: {b.get('error', 'ran')})")
        elif a["real"] == b["real"]:
            same_real += 1
            digest = hashlib.sha1(json.dumps(a["real"]).encode()).hexdigest()[:10]
            scale = max((abs(x) for row in b["variational"] for x in row), default=0.0)
            diff = largest_difference(a["variational"], b["variational"])
            print(f"{name}: real trajectory same bits ({digest}); variational particles DIFFERENT "
                  f"(largest difference {diff/scale if scale else diff:.3g} of their largest value)")
        else:
            print(f"{name}: DIFFERENT (largest difference {largest_difference(a['real'], b['real']):.3g})")
    print(f"{same} of {len(RUNS)} runs give the same bits" + (f"; {same_real} more the same real trajectory, "
          "their variational particles differing" if same_real else ""))
    return 0 if same == len(RUNS) else 1


if __name__ == "__main__":
    sys.exit(main())
