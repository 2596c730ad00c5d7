"""Command line: ``rebound-pfvi`` or ``python -m rebound_pfvi``."""
import argparse
import sys


def main(argv=None):
    parser = argparse.ArgumentParser(prog="rebound-pfvi",
                                     description="Phase-fitted discrete Lagrangian integrator for REBOUND.")
    commands = parser.add_subparsers(dest="command")
    demo = commands.add_parser("demo", help="circular and e = 0.95 orbits with pfvi, IAS15 and WHFast (default)")
    demo.add_argument("--orbits", type=int, default=100, help="orbits to integrate (default 100)")
    args = parser.parse_args(argv)
    if args.command in (None, "demo"):
        orbits = getattr(args, "orbits", 100)
        if orbits < 1:
            parser.error(f"--orbits must be a positive integer, got {orbits}")
        from .demo import run_demo
        run_demo(orbits)
    return 0


if __name__ == "__main__":
    sys.exit(main())
