"""Issue 42, the Python boundary (third hostile trial): the Python API checks
what the command line checks, with the same checks, and errors name the
argument or field and the value at fault."""
import warnings

import pytest

from rebound_pfvi import compare, report, scenes
from rebound_pfvi.__main__ import main

#: Sweeps in which no run gets to its end: every run crashes (an overflow) or is refused (a force that is not finite).
NOTHING_FINISHES = [
    (["--scene", "oscillator", "--omega", "1e300 1/yr", "--integrators", "ias15"], "oscillator.md", "4 crashed"),
    (["--scene", "kepler", "--m", "1e300 kg", "--integrators", "pfvi", "--periods", "1"], "kepler-e0.95.md",
     "16 refused"),
]


@pytest.mark.parametrize("argv, page, what", NOTHING_FINISHES)
def test_a_sweep_in_which_no_run_finished_writes_its_page_and_fails(argv, page, what, tmp_path, capsys):
    code = main(["compare", *argv, "--output", str(tmp_path), "--workers", "1", "--repeats", "1",
                 "--samples", "2"])
    assert code == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert err[-1] == (f"error: no run finished with finite errors ({what}); each run's verdict: "
                       f"{tmp_path / page}")
    text = (tmp_path / page).read_text()
    assert f"**Nothing measured**: no run finished with finite errors ({what})." in text
    assert "| crashed |" in text or "| refused |" in text


def test_compare_run_says_when_no_run_finished():
    scene = scenes.Oscillator(omega=1e300, periods=1)
    with pytest.warns(compare.NoRunFinished, match=r"oscillator: no run finished with finite errors \(2 crashed\)"):
        results = compare.run(scene, [compare.Setting("ias15", 1e-5), compare.Setting("pfvi", 1e-6)], repeats=1,
                              samples=2, workers=1)
    assert results.failure == "no run finished with finite errors (2 crashed)"
    assert [r.verdict for r in results.rows] == ["crashed", "crashed"]
    with warnings.catch_warnings():
        warnings.simplefilter("error", compare.NoRunFinished)
        fine = compare.run(scenes.Kepler(periods=1), [compare.Setting("ias15", 1e-5)], repeats=1, samples=2,
                           workers=1)
    assert fine.failure == ""
