"""Sun, Jupiter, Saturn over 2000 time units (G = 1) with one integrate()
call or N evenly spaced outputs: the steps and output steps, for the
instruction counts of docs/outputs.md ("What it costs").

    python -P benchmarks/hooks_cost.py 1000
    valgrind --tool=callgrind --collect-atstart=no --toggle-collect=reb_simulation_step \\
        --toggle-collect=reb_simulation_synchronize python3 -P benchmarks/hooks_cost.py 1000
    callgrind_annotate callgrind.out.<pid> | grep "PROGRAM TOTALS"
"""
import sys

import rebound

import rebound_pfvi  # noqa: F401  (registers "pfvi")


def main(outputs=1):
    sim = rebound.Simulation()
    sim.add(m=1.0)
    sim.add(m=9.547919e-4, a=5.2, e=0.048, inc=0.0228)
    sim.add(m=2.858860e-4, a=9.58, e=0.056, inc=0.0434, Omega=1.98, omega=5.9, M=3.1)
    sim.move_to_com()
    sim.integrator = "pfvi"
    t_end = 2000.0
    for k in range(outputs):
        sim.integrate(t_end * (k + 1) / outputs)
    print(f"outputs {outputs}: steps {sim.integrator.n_steps}, output steps {sim.integrator.n_outputs}, "
          f"Jupiter x {sim.particles[1].x!r}")


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 1)
