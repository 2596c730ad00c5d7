"""A particle edited every step, swept: a post-timestep hook that multiplies
a mass by 1 - 1e-14 (physically nothing, but an edit: every step starts its
track afresh) at pfvi's defaults and REBOUND's default sim.dt, against IAS15
at epsilon 1e-12 with the same hook, beside pfvi without the hook. Kepler
e = 0, 0.01, ..., 0.99 from four mean anomalies (pericentre, apocentre and
two between) over 3 orbits, a flyby, a binary with a planet, and a
retrograde crosser with test particles; 6 outputs, then sim.dt flipped and
back to 0. About 3 s.

    python -P benchmarks/edited_every_step.py

Prints the runs whose error with the edits is largest against the error
without them, the largest error with edits, and the steps with edits over
those without.
"""
import math
import warnings

import numpy as np
import rebound
import rebound_pfvi  # noqa: F401

warnings.simplefilter("ignore")
def hook(sp):
    c = sp.contents; c.particles[1].m *= (1 - 1e-14)
def builders():
    for e in np.arange(0.0, 0.995, 0.01):
        for M in (0.0, 1.6, math.pi, 4.7):
            def b(e=e, M=M):
                s = rebound.Simulation(); s.add(m=1.); s.add(m=1e-3, a=1., e=float(e), M=M); s.move_to_com(); return s
            yield f"kepler e={e:.2f} M={M:.1f}", b, 2*math.pi*3
    def flyby():
        s = rebound.Simulation(); s.add(m=1.); s.add(m=1e-3, a=1., e=0.1); s.add(m=0.5, x=-20., y=0.6, vx=1.2); s.move_to_com(); return s
    yield "flyby", flyby, 30.
    def binary_planet():
        s = rebound.Simulation(); s.add(m=1.); s.add(m=0.5, a=0.2, e=0.3); s.add(m=1e-3, a=1.5, e=0.1, inc=0.2); s.move_to_com(); return s
    yield "binary+planet", binary_planet, 30.
    def retro():
        s = rebound.Simulation(); s.add(m=1.); s.add(m=1e-3, a=5.2, e=0.05); s.add(m=0., a=3.3, e=0.6, inc=2.5, Omega=0.5, omega=0.5, M=1.0)
        s.add(m=0., a=2., e=0.9, M=3.); s.move_to_com(); return s
    yield "retrograde+test particles", retro, 60.
def run(build, T, integ, with_hook, nout=6):
    s = build(); s.integrator = integ
    if integ == "ias15": s.integrator.epsilon = 1e-12
    if with_hook: s.post_timestep_modifications = hook
    for t in np.linspace(0, T, nout+1)[1:]: s.integrate(t)
    x = np.array([[p.x, p.y, p.z] for p in s.particles]); n = s.steps_done
    s.dt = -s.dt; s.integrate(0.)
    back = np.array([[p.x, p.y, p.z] for p in s.particles])
    return x, n, back
worst = []
for name, b, T in builders():
    ref, _, refback = run(b, T, "ias15", True)
    xh, nh, bh = run(b, T, "pfvi", True)
    x0, n0, b0 = run(b, T, "pfvi", False)
    scale = np.max(np.abs(ref))
    eh, e0 = np.max(np.abs(xh-ref))/scale, np.max(np.abs(x0-ref))/scale
    worst.append((eh/max(e0, 1e-13), name, eh, e0, nh, n0, np.max(np.abs(bh-refback))/scale))
worst.sort(reverse=True)
print("runs", len(worst))
for w in worst[:8]: print("ratio %.2g %s: with edits %.2e, without %.2e, steps %d vs %d, back %.1e" % w)
print("largest error with edits: %.2e" % max(w[2] for w in worst), " median ratio %.2f" % np.median([w[0] for w in worst]))
print("steps with edits / without: median %.2f, max %.2f" % (np.median([w[4]/w[5] for w in worst]), max(w[4]/w[5] for w in worst)))
