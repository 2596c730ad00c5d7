"""Verdicts: what became of a run of ``compare`` or ``stability``, in one word.

Every run gets exactly one of

- ``accurate``: finished, and within its reference tolerance;
- ``inaccurate``: finished, but its error exceeds the tolerance (or its state
  is not finite); the detail gives the error;
- ``refused``: the integrator refused a step (a ``RuntimeError``, such as
  pfvi's "pfvi: ..." messages); the detail is the message;
- ``crashed``: the run's process died, or it raised an error other than a
  refusal;
- ``over budget``: stopped by its wall-time budget, or killed when it did not
  stop.

The tolerance (:class:`Tolerance`) has two parts, and a finished run must meet
both: the largest relative energy error over the run, and the relative
position error, i.e. the largest error of a body's position relative to
particle 0 divided by that body's reference distance from particle 0 (the
size of its orbit where it is at the end; for a single body, its distance
from the origin; a scene's moons about their planets instead). Relative measures make one tolerance mean the same for an
orbit of 0.01 AU and one of 10 AU. The default, 1e-2 in both, marks a run
whose orbit is wrong by more than a percent, so an O(1) error can never be
called "accurate"; the error itself is in the tables, so the verdict is a
floor, not a ranking.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Dict, Iterable, List, Mapping, Optional, Sequence, Tuple

ACCURATE = "accurate"
INACCURATE = "inaccurate"
REFUSED = "refused"
CRASHED = "crashed"
OVER_BUDGET = "over budget"
#: Every verdict, in the order tables list them.
VERDICTS = (ACCURATE, INACCURATE, REFUSED, CRASHED, OVER_BUDGET)
#: What each verdict means, for reports.
MEANING = {
    ACCURATE: "finished, within its reference tolerance",
    INACCURATE: "finished, but its error exceeds the tolerance (or its state is not finite)",
    REFUSED: "the integrator refused a step (its message is given)",
    CRASHED: "the run's process died, or it raised an error other than a refusal",
    OVER_BUDGET: "stopped by its wall-time budget (or killed when it did not stop)",
}

Vector = Sequence[float]


@dataclass(frozen=True)
class Tolerance:
    """The largest errors a finished run may have and still be ``accurate``."""

    energy: float = 1e-2  # largest relative energy error over the run
    position: float = 1e-2  # relative position error (see the module docstring)

    def describe(self) -> str:
        return (f"largest relative energy error <= {self.energy:g} and position error <= {self.position:g} "
                "of each body's distance from particle 0 (a moon's from its planet)")


DEFAULT = Tolerance()


def relative_position_error(positions: Sequence[Vector], reference: Sequence[Vector],
                            primaries: Optional[Mapping[int, int]] = None) -> float:
    """Largest error of a body's position relative to body 0, over its reference distance from body 0.

    primaries: {body: the body it orbits} for bodies measured about another
    than body 0 (a moon about its planet: 1% of its distance from the Sun
    would let it stand on the wrong side of the planet). With one body, its
    error over its reference distance from the origin."""
    if len(positions) != len(reference):
        raise ValueError(f"positions: {len(positions)} bodies against {len(reference)} in the reference")
    if len(positions) == 1:
        return _ratio(math.dist(positions[0], reference[0]), math.hypot(*reference[0]))
    primaries = primaries or {}
    worst = 0.0
    for i in range(1, len(positions)):
        c = primaries.get(i, 0)
        if not (0 <= c < len(positions) and c != i):
            raise ValueError(f"primaries: body {i}'s primary {c} is not another of the {len(positions)} bodies")
        d = [positions[i][k] - positions[c][k] for k in range(3)]
        r = [reference[i][k] - reference[c][k] for k in range(3)]
        worst = max(worst, _ratio(math.dist(d, r), math.hypot(*r)))
    return worst


def relative_vector_error(vector: Vector, reference: Vector) -> float:
    """|vector - reference| / |reference|: a two-body run's relative position against the exact one."""
    return _ratio(math.dist(vector, reference), math.hypot(*reference))


def _ratio(error: float, size: float) -> float:
    if size > 0.0:
        return error / size
    return 0.0 if error == 0.0 else math.inf


def judge(energy_error_max: Optional[float], position_error: Optional[float],
          tolerance: Tolerance = DEFAULT, finite: bool = True) -> Tuple[str, str]:
    """The verdict of a finished run, ``accurate`` or ``inaccurate``, and its detail.

    position_error is the relative one (:func:`relative_position_error`);
    None means it could not be measured, and then energy alone decides."""
    values = [v for v in (energy_error_max, position_error) if v is not None]
    if not finite or not all(math.isfinite(v) for v in values):
        return INACCURATE, "non-finite state or error"
    errors = []
    if energy_error_max is not None:
        errors.append(f"energy error {energy_error_max:.3g}"
                      + (f" > {tolerance.energy:g}" if energy_error_max > tolerance.energy else ""))
    if position_error is not None:
        errors.append(f"position error {position_error:.3g} of the distance"
                      + (f" > {tolerance.position:g}" if position_error > tolerance.position else ""))
    bad = ((energy_error_max is not None and energy_error_max > tolerance.energy)
           or (position_error is not None and position_error > tolerance.position))
    return (INACCURATE if bad else ACCURATE), ", ".join(errors)


def of_exception(error_text: str) -> str:
    """``refused`` for a RuntimeError (an integrator refusing a step), else ``crashed``."""
    return REFUSED if error_text.startswith("RuntimeError") else CRASHED


def count(rows: Iterable[Mapping[str, Any]], key: str) -> Dict[str, Dict[str, int]]:
    """{row[key]: {verdict: number of rows}}, in the order the keys first appear."""
    counts: Dict[str, Dict[str, int]] = {}
    for row in rows:
        per = counts.setdefault(str(row[key]), {v: 0 for v in VERDICTS})
        per[row["verdict"]] += 1
    return counts


def markdown_counts(counts: Mapping[str, Mapping[str, int]], what: str = "integrator") -> str:
    """The counts as a markdown table, a row per integrator and a total."""
    lines = [f"| {what} | " + " | ".join(VERDICTS) + " |", "|---|" + "---|" * len(VERDICTS)]
    for name, per in counts.items():
        lines.append(f"| {name} | " + " | ".join(str(per[v]) for v in VERDICTS) + " |")
    total = {v: sum(per[v] for per in counts.values()) for v in VERDICTS}
    lines.append("| **all** | " + " | ".join(str(total[v]) for v in VERDICTS) + " |")
    return "\n".join(lines)


def text_counts(counts: Mapping[str, Mapping[str, int]]) -> List[str]:
    """The counts as aligned plain-text lines, for the command line."""
    width = max([len(n) for n in counts] + [10])
    lines = [f"{'':{width}s}  " + "  ".join(f"{v:>11s}" for v in VERDICTS)]
    for name, per in counts.items():
        lines.append(f"{name:{width}s}  " + "  ".join(f"{per[v]:11d}" for v in VERDICTS))
    return lines
