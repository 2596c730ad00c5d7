"""The round-off floor (issue 42, item 4): how small an error each
integrator reaches when its accuracy knob is turned down, measured over an
ensemble rather than one run, since at that level the error is a random
walk and one run's end can be anywhere in its spread.

- Kepler e = 0.95 (m = 1 and 1e-3, AU, yr, Msun; 100 orbits, exact
  reference) from 16 starting phases. Reported: the error in mean anomaly
  (rad; the along-track distance from the exact position over v/n): a
  phase error is what round-off leaves on a Kepler orbit, and this measure
  does not depend on where the run ends. (The relative position error at
  an end near pericentre is the phase error times v/(n r), 125 at e = 0.95:
  the scene's 1e-12 there would need the mean anomaly, about 628 rad after
  100 orbits, to 2e-15, below the doubles' own resolution of 628, 1.1e-13.)
- The outer solar system page's scene (rebound_pfvi.scenes, 992 yr), eight
  members whose Jupiter starts 2^-40 x k (relative) apart, each against
  its own IAS15 reference at epsilon 1e-12: Jupiter's relative position
  error. The reference's own round-off is of the same size; IAS15 against
  it at a looser epsilon shows that level.

    python -P benchmarks/roundoff_floor.py [--scenes kepler,outer]
        [--pfvi 1e-12,1e-13,1e-14] [--ias15 1e-9,1e-10,1e-11]
        [--baseline "PYTHONPATH=<another build> python3"]

--baseline adds pfvi as another build runs it (e.g. a7bd4da, the last
build with the fixed-point stage solve). Each setting's runs are child
processes of the interpreter given (default: this one).
"""
import argparse
import json
import shlex
import statistics
import subprocess
import sys

CHILD = r"""
import json, math, sys
import rebound, rebound_pfvi
scene, integrator, knob, member = sys.argv[1], sys.argv[2], float(sys.argv[3]), int(sys.argv[4])
G = 4.0 * math.pi**2
if scene == "kepler":
    sim = rebound.Simulation(); sim.G = G
    sim.add(m=1.0); sim.add(m=1e-3, a=1.0, e=0.95, f=2.0 * math.pi * member / 16 + 0.01)
    sim.move_to_com()
    o = sim.particles[1].orbit(primary=sim.particles[0])
    sim.integrator = integrator; sim.integrator.epsilon = knob
    sim.integrate(100 * o.P, exact_finish_time=1)
    ex = rebound.Simulation(); ex.G = G
    ex.add(m=1.0); ex.add(m=1e-3, a=o.a, e=o.e, omega=o.omega, M=(o.M + o.n * sim.t) % (2 * math.pi))
    d, de = sim.particles[1] - sim.particles[0], ex.particles[1] - ex.particles[0]
    error = math.dist(d.xyz, de.xyz) / math.hypot(de.vx, de.vy, de.vz) * o.n
else:
    from rebound_pfvi import scenes
    sc = scenes.make("outer-solar-system")
    def run(integrator, knob):
        sim = sc.build()
        sim.particles[1].x *= 1.0 + member * 2.0**-40
        sim.integrator = integrator; sim.integrator.epsilon = knob
        sim.integrate(sc.t_end, exact_finish_time=1)
        return [(p.x, p.y, p.z) for p in sim.particles]
    got, ref = run(integrator, knob), run("ias15", 1e-12)
    sun = ref[0]
    error = math.dist([a - b for a, b in zip(got[1], got[0])], [a - b for a, b in zip(ref[1], sun)]) \
        / math.dist(ref[1], sun)
print(json.dumps(error))
"""

MEMBERS = {"kepler": 16, "outer": 8}


def floor(prefix, scene, integrator, knob):
    errors = []
    for member in range(MEMBERS[scene]):
        out = subprocess.run(prefix + ["-P", "-c", CHILD, scene, integrator, repr(knob), str(member)],
                             capture_output=True, text=True, check=True)
        errors.append(json.loads(out.stdout.strip().splitlines()[-1]))
    errors.sort()
    return statistics.median(errors), errors[len(errors) // 4], errors[(3 * len(errors)) // 4], errors[-1]


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--scenes", default="kepler,outer")
    parser.add_argument("--pfvi", default="1e-12,1e-13,1e-14")
    parser.add_argument("--ias15", default="1e-9,1e-10,1e-11")
    parser.add_argument("--baseline", default=None)
    args = parser.parse_args()
    lines = [("pfvi", [sys.executable], args.pfvi), ("ias15", [sys.executable], args.ias15)]
    if args.baseline:
        lines.insert(1, ("pfvi (baseline)", ["env"] + shlex.split(args.baseline), args.pfvi))
    for scene in args.scenes.split(","):
        what = ("mean-anomaly error (rad), 16 phases" if scene == "kepler"
                else "Jupiter's relative position error, 8 members")
        print(f"\n### {scene}: {what}\n")
        print("| integrator | epsilon | median | quartiles | largest |")
        print("|---|---|---|---|---|")
        for label, prefix, knobs in lines:
            integrator = label.split()[0]
            for knob in (float(x) for x in knobs.split(",")):
                med, q1, q3, top = floor(prefix, scene, integrator, knob)
                print(f"| {label} | {knob:g} | {med:.2e} | {q1:.2e} ... {q3:.2e} | {top:.2e} |", flush=True)


if __name__ == "__main__":
    main()
