"""Command line: ``rebound-pfvi`` or ``python -m rebound_pfvi``."""
import argparse
import sys


def main(argv=None):
    parser = argparse.ArgumentParser(prog="rebound-pfvi",
                                     description="Phase-fitted discrete Lagrangian integrator for REBOUND.")
    commands = parser.add_subparsers(dest="command")
    demo = commands.add_parser("demo", help="circular and e = 0.95 orbits with pfvi, IAS15 and WHFast (default)")
    demo.add_argument("--orbits", type=int, default=100, help="orbits to integrate (default 100)")
    paper = commands.add_parser("paper", help="rerun a figure of the seed paper")
    paper.add_argument("figure", choices=("fig1",), help="fig1: steps against energy error, phase vs none")
    paper.add_argument("--output", default="docs/paper", help="folder for the page, data and PNG (default docs/paper)")
    paper.add_argument("--stages", type=int, default=2, choices=range(2, 7), metavar="{2..6}",
                       help="Gauss-Lobatto nodes (default 2, as in the seed's Figure 1)")
    paper.add_argument("--step-control", default="seed", choices=("seed", "reversible"))
    args = parser.parse_args(argv)
    if args.command == "paper":
        from . import paper as seed_paper
        seed_paper.figure1(args.output, stages=args.stages, step_control=args.step_control,
                           progress=lambda row: print(
                               f"e = {row['e']}, epsilon = {row['epsilon']:.0e}: phase {row['phase_steps']} steps,"
                               f" none {row['none_steps']} steps", flush=True))
        return 0
    if args.command in (None, "demo"):
        orbits = getattr(args, "orbits", 100)
        if orbits < 1:
            parser.error(f"--orbits must be a positive integer, got {orbits}")
        from .demo import run_demo
        run_demo(orbits)
    return 0


if __name__ == "__main__":
    sys.exit(main())
