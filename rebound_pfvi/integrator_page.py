"""docs/integrator.md, the integrator's page in the form of REBOUND's own
integrator pages (what it is, when to use it, references, its fields with
types, values and defaults, an example, loading an archive), generated from
the C core: the description and every field's text are the strings
``help(sim.integrator)`` prints, the defaults are :data:`rebound_pfvi.DEFAULTS`, the values the core's
option lists. Rewrite the page after changing the core::

    python3 -P -m rebound_pfvi.integrator_page docs/integrator.md

and tests/test_docs.py fails while page and core differ.
"""
from __future__ import annotations

import sys
from typing import Any, List, NamedTuple, Tuple

#: When to use pfvi, and when not: what the pages measured (docs/results.md
#: holds the numbers and the commands that rerun them).
WHEN = """\
- **Eccentric orbits and hierarchies over many orbits**, where you would use
  IAS15 and want the same trust at less wall time: Kepler orbits up to
  e = 0.99, a comet among planets, a stellar triple, the outer solar system.
  At equal final position error pfvi's defaults took a fraction of IAS15's
  wall time on these pages (docs/results.md has the ratios and where they
  do not hold).
- **Time-symmetric runs**: the default step control reads the same forward
  and backward; integrating forward and back retraces the steps.
- **MEGNO and Lyapunov maps**, above all of eccentric systems: variational
  particles follow the tangent map of pfvi's own step (docs/megno.md has
  the map against IAS15 and WHFast).
- **Collisions** are found inside a step (the step is retaken to the
  contact, counted in ``n_contact_steps``; docs/collisions.md).
- **Not** for: planetary systems of low eccentricity at moderate accuracy
  (WHFast with its corrector is faster to 1e-6 AU on the triple and on
  Mercury with GR, to 1e-4 AU on the outer solar system), pure Kepler pairs
  (WHFast is exact there), very short accurate runs (BS is often faster),
  and forces that jump within a step (a tree code's cells: the steps are
  kept but counted in ``n_unresolved``).
"""

#: The papers the description cites, in full.
REFERENCES = (
    'O. T. Kosmas and D. S. Vlachos, "Phase-fitted Discrete Lagrangian Integrators" (the seed: '
    "phase fitting, the osculating-circle control, interior points; its journal reference could not be "
    "checked here, see CITATION.cff).",
    'J. E. Marsden and M. West, "Discrete mechanics and variational integrators", '
    "Acta Numerica 10 (2001) 357-514.",
    'E. Hairer and G. Soderlind, "Explicit, time reversible, adaptive step size control", '
    "SIAM J. Sci. Comput. 26 (2005) 1838-1851 (the symmetric step control).",
    'M. Antonana, J. Makazaga and A. Murua, "Reducing and monitoring round-off error '
    'propagation for symplectic implicit Runge-Kutta schemes", Numerical Algorithms (2017), '
    "doi:10.1007/s11075-017-0287-z (IRKGL16: the stage solve's stop).",
    'M. Antonana, J. Makazaga and A. Murua, "Efficient implementation of symplectic implicit '
    'Runge-Kutta schemes with simplified Newton iterations", Numerical Algorithms 78 (2018) 63-86 '
    "(the stage solve's Newton iteration).",
    'E. Hairer, R. I. McLachlan and A. Razakarivony, "Achieving Brouwer\'s law with implicit '
    'Runge-Kutta methods", BIT Numerical Mathematics 48 (2008) 231-243 (round-off as a random walk).',
    'P. Hut, J. Makino and S. McMillan, "Building a better leapfrog", ApJ 443 (1995) L93 '
    "(the 'reversible' control).",
)

#: A ten-line run: every line a REBOUND user would write, nothing pfvi-specific but its name.
EXAMPLE = """\
import rebound
import rebound_pfvi  # registers "pfvi" with REBOUND

sim = rebound.Simulation()
sim.add(m=1.0)
sim.add(m=1e-3, a=1.0, e=0.9)
sim.move_to_com()
sim.integrator = "pfvi"  # adaptive, s = 8, epsilon 1e-6; no sim.dt needed
# sim.integrator.epsilon = 1e-12  # IAS15's default accuracy, to compare the two
sim.integrate(100.0)
print(sim.integrator.n_steps, sim.integrator.epsilon_effective)
"""


class Field(NamedTuple):
    name: str
    statistic: bool
    type: str  # as the page names it: text, int, float, count
    values: Tuple[str, ...]  # an option's allowed values where the core lists them
    default: Any
    documentation: str  # the core's text (a statistic's without "Statistic: ")


def fields() -> List[Field]:
    """Every documented field of the integrator, from the C core's field list."""
    import rebound

    from . import INTEGRATOR_NAME, STAGES

    sim = rebound.Simulation()
    sim.integrator = INTEGRATOR_NAME
    result = []
    for fd in sim.integrator.callbacks.field_descriptor_list:
        if not fd.documentation:
            continue  # scratch saved for archives, not a user's field
        name, doc = fd.name.decode(), fd.documentation.decode()
        statistic = doc.startswith("Statistic:")
        if statistic:
            doc = doc[len("Statistic:"):].strip()
        values: Tuple[str, ...] = ()
        if fd.enum_descriptor_list:
            kind = "text"
            values = tuple(e.name.decode() for e in fd.enum_descriptor_list)
        elif name == "stages":
            kind, values = "int", tuple(map(str, STAGES))
        else:
            kind = {1: "float", 2: "int"}.get(fd.dtype, "count")
        value = getattr(sim.integrator, name)
        default = str(value) if isinstance(value, str) else value
        result.append(Field(name, statistic, kind, values, default, doc))
    return result


def description() -> str:
    """The integrator's description, as ``help(sim.integrator)`` begins."""
    import rebound

    from . import INTEGRATOR_NAME

    sim = rebound.Simulation()
    sim.integrator = INTEGRATOR_NAME
    return sim.integrator.callbacks.documentation.decode()


def _cell(text: str) -> str:
    return text.replace("|", "\\|").replace("\n", " ")


def page() -> str:
    """docs/integrator.md as the core describes the integrator today."""
    from . import ARCHIVE_FAILURE, ARCHIVE_RECIPE

    everything = fields()
    lines = ["# The pfvi integrator", "",
             "*Generated from the C core by `python3 -P -m rebound_pfvi.integrator_page docs/integrator.md`: "
             "the description and the fields' texts are the strings `help(sim.integrator)` prints.*", "",
             "## What it is", "", description(), "",
             "## When to use it", "", WHEN, "## References", ""]
    lines += [f"- {ref}" for ref in REFERENCES]
    lines += ["", "## Options", "",
              "Set as `sim.integrator.<name> = value` after `sim.integrator = \"pfvi\"`; checked when the "
              "next step starts; saved in Simulationarchives.", "",
              "| Field | Type | Values | Default | Description |", "|---|---|---|---|---|"]
    for f in everything:
        if not f.statistic:
            values = ", ".join(f"`{v}`" for v in f.values) if f.values else "a number (see the description)"
            lines.append(f"| `{f.name}` | {f.type} | {values} | `{f.default!r}` | {_cell(f.documentation)} |")
    lines += ["", "## Statistics", "",
              "Read-only counts and measures, since the integrator was set (`sim.integrator.<name>`).", "",
              "| Field | Type | Description |", "|---|---|---|"]
    for f in everything:
        if f.statistic:
            lines.append(f"| `{f.name}` | {f.type} | {_cell(f.documentation)} |")
    lines += ["", "## Example", "", "```python", EXAMPLE.rstrip("\n"), "```", ""]
    lines += ["## Simulationarchives", "", ARCHIVE_FAILURE, "", "```python", ARCHIVE_RECIPE.rstrip("\n"), "```", ""]
    return "\n".join(lines)


def main(argv: List[str]) -> int:
    """python -m rebound_pfvi.integrator_page [PATH]: the page to PATH, or to standard output."""
    asked = bool(argv) and argv[0] in ("-h", "--help")
    if asked or len(argv) > 1 or (argv and argv[0].startswith("-")):
        # (a hostile trial: --help was taken for the path, and a 33 kB file named "--help" written)
        print("usage: python -m rebound_pfvi.integrator_page [PATH]\n\n"
              "Writes docs/integrator.md's text (every option and statistic, from the C core's strings)\n"
              "to PATH, or to standard output without one.", file=sys.stdout if asked else sys.stderr)
        return 0 if asked else 2
    text = page()
    if not argv:
        sys.stdout.write(text)
        return 0
    try:
        with open(argv[0], "w", encoding="utf-8") as out:
            out.write(text)
    except OSError as error:
        print(f"integrator_page: cannot write {argv[0]}: {error.strerror}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
