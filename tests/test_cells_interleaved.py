"""benchmarks/cells_interleaved.py: which settings of a page it retimes
(docs/results.md, "Interleaved"), and that a retimed run is judged by its
own error, not the page's."""
import sys
from pathlib import Path

from rebound_pfvi import scenes
from rebound_pfvi.runs import COMPARE, Run

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "benchmarks"))
import cells_interleaved  # noqa: E402


def row(label, family, value, wall, error, options=None):
    knob = {"pfvi": "epsilon", "ias15": "epsilon", "bs": "eps"}.get(family, "steps/period")
    return Run(COMPARE, "kepler", family, label, options=options or {}, knob=knob, value=value, status="ok",
               wall_s=wall, position_error=error)


ROWS = [
    row("pfvi s=8", "pfvi", 1e-6, 3e-3, 5e-7),
    row("pfvi s=8", "pfvi", 1e-7, 2e-3, 5e-8),  # least recorded time
    row("pfvi s=8", "pfvi", 1e-5, 1e-3, 2e-6),  # does not reach 1e-6
    row("pfvi s=6", "pfvi", 1e-6, 9e-3, 5e-7, {"stages": 6}),  # far behind: left out
    row("BS", "bs", 1e-8, 1.5e-3, 9e-7),
    row("BS", "bs", 1e-9, 1.2e-3, 1e-7),
    row("WHFast", "whfast", 300, 2.3e-3, 1e-7),
    row("WHFast", "whfast", 100, 2.0e-3, 8e-7),
    row("LEAPFROG", "leapfrog", 1000, 3.0e-3, 8e-7),  # beyond 2x the fastest: left out
]


def test_candidates_are_the_loosest_and_the_recorded_fastest_knob_of_each_line_near_the_fastest():
    chosen = {(c.run.label, c.run.value) for c in cells_interleaved.candidates_of(ROWS, 1e-6, 2.0)}
    # pfvi s=8: loosest reaching 1e-6 (1e-6) and recorded fastest (1e-7); BS:
    # loosest (1e-8) and fastest (1e-9); WHFast: fewest steps per period (100),
    # which is also its fastest; pfvi s=6 and LEAPFROG (beyond 2 x 1.2 ms) are not retimed.
    assert chosen == {("pfvi s=8", 1e-6), ("pfvi s=8", 1e-7), ("BS", 1e-8), ("BS", 1e-9), ("WHFast", 100)}


def test_the_default_line_and_the_fastest_other_line_are_always_candidates():
    rows = [row("pfvi s=8", "pfvi", 1e-6, 9e-3, 5e-7), row("pfvi s=6", "pfvi", 1e-6, 1e-3, 5e-7, {"stages": 6}),
            row("BS", "bs", 1e-8, 5e-3, 9e-7)]
    labels = {c.run.label for c in cells_interleaved.candidates_of(rows, 1e-6, 2.0)}
    assert labels == {"pfvi s=8", "pfvi s=6", "BS"}
    assert cells_interleaved.candidates_of(rows, 1e-12, 2.0) == []


def test_a_candidate_is_dropped_when_its_run_here_misses_the_target():
    scene = scenes.make("kepler", e=0.5, periods=2.0)
    reference = scene.reference()
    # (The target is far above the exact reference's own error before
    # rebound 5.2, up to 5e-9 AU: README.md.)
    loose = cells_interleaved.Candidate(row("pfvi s=2", "pfvi", 1e-3, 1e-3, 1e-12, {"stages": 2}))  # the page lies
    tight = cells_interleaved.Candidate(row("pfvi s=8", "pfvi", 1e-12, 1e-3, 1e-12))
    cands = [loose, tight]
    dropped = cells_interleaved.measure(scene, reference, cands, 1e-6, rounds=1, sample=0.0)
    assert cands == [tight] and len(dropped) == 1 and "epsilon 0.001" in dropped[0]
    assert loose.error > 1e-6 >= tight.error
    assert 0.0 < tight.best < 1.0
