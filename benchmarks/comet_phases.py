"""The Encke-like comet of benchmarks/comet_steps.py from several starting
phases: its end error depends on where the steps fall at each perihelion, so
one start per epsilon is a lottery; this gives the spread.

    python -P benchmarks/comet_phases.py 1.2e-7,1e-7,5e-8,2e-8,1e-8,1e-9 [8]   # about 5 s

For each epsilon: the end error (largest over bodies, against IAS15 at 1e-13)
in epsilon a n (a = 2.2 AU, n = 20) from comet mean anomalies 0.5 + 0.7 k,
k = 0 ... 7 (k = 0 is comet_steps.py's start), and the work summed over the
runs (steps plus rejected trials).
"""
import math
import statistics
import sys

import rebound_pfvi  # noqa: F401
from rebound_pfvi import scenes

def build(M, sim=None):
    """The comet at mean anomaly M among the planets, in a new simulation of
    the scenes' units, or added to `sim` (tests/test_split.py's G = 1)."""
    sim = scenes.new_simulation() if sim is None else sim
    sim.add(m=1.0)
    for m, a, e, Mp in ((2.45e-6, 0.723, 0.007, 1.0), (3.0e-6, 1.0, 0.017, 2.0), (3.2e-7, 1.524, 0.093, 3.0), (9.55e-4, 5.203, 0.048, 4.0)):
        sim.add(m=m, a=a, e=e, M=Mp)
    sim.add(m=0.0, a=2.2, e=0.85, inc=math.radians(12.0), omega=3.0, M=M)
    sim.move_to_com()
    return sim

P = 2*math.pi*math.sqrt(2.2**3/scenes.rebound_G())
T = 20*P
def one(M, eps):
    sim = build(M); sim.integrator = "pfvi"; sim.integrator.epsilon = eps
    sim.integrate(T)
    ref = build(M); ref.integrator = "ias15"; ref.integrator.epsilon = 1e-13; ref.integrate(sim.t)
    err = max(math.dist((p.x, p.y, p.z), (q.x, q.y, q.z)) for p, q in zip(sim.particles, ref.particles))
    return err/(eps*2.2*20), sim.integrator.n_steps + sim.integrator.n_rejected

def main():
    for eps in map(float, sys.argv[1].split(",")):
        errs, work = [], 0
        for k in range(int(sys.argv[2]) if len(sys.argv) > 2 else 8):
            e, w = one(0.5 + 0.7*k, eps); errs.append(e); work += w
        print(f"eps {eps:g}: errors {' '.join(f'{e:.2g}' for e in errs)} | max {max(errs):.3g} "
              f"median {statistics.median(errs):.3g} over3 {sum(e>3 for e in errs)} work {work}", flush=True)


if __name__ == "__main__":
    main()
