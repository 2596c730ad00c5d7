"""Figures the prose states, tied to where they come from (issue 37): every
run time README.md and docs/*.md state names the command that produced it
beside it, and the ratio to IAS15 that README.md, docs/results.md,
docs/adaptive.md and the demo state is the one the pages' JSON give."""
import re
import sys
from pathlib import Path

import pytest

from rebound_pfvi import demo

ROOT = Path(__file__).resolve().parent.parent
PAGES = [ROOT / "README.md"] + sorted((ROOT / "docs").glob("*.md"))

_DURATION = r"(?:about\s|in\s)?\d+(?:\.\d+)?(?:(?:\sto\s|-)\d+(?:\.\d+)?)?\s?(?:s|min|minutes|seconds|h|hours)\b"
#: A stated run time: a duration "on N cores / workers", one in a comment of
#: a command line, "about N s", or "N min".
RUN_TIME = re.compile(
    _DURATION + r"(?=[^.;|]{0,40}?\bon\s\d+\s(?:cores?|workers?|worker\sprocess(?:es)?|worker\(s\))\b)"
    r"|# [^#\n]*?\b\d+(?:\.\d+)? ?(?:s|min)\b"
    r"|\babout\s\d+(?:\.\d+)?\s?(?:s|min|minutes)\b"
    r"|\b\d+\smin(?:\s\d+\ss)?\b")
COMMAND = re.compile(r"\b(?:python3?|rebound-pfvi|bash|pytest|jupyter|pip) ")


def units(text):
    """Paragraphs, each with the code block that follows it (the command a
    sentence like "Install and run the tests (about 100 s ...):" introduces)."""
    out = []
    for block in re.split(r"\n\s*\n", text):
        lines = [line for line in block.splitlines() if line.strip()]
        code = block.lstrip("\n").startswith("```") or (lines and all(line.startswith("    ") for line in lines))
        if code and out:
            out[-1] += "\n" + block
        else:
            out.append(block)
    return out


def stated_run_times(text):
    """(statement, has a command beside it) for each stated run time."""
    found = []
    for unit in units(text):
        for match in RUN_TIME.finditer(unit):
            found.append((" ".join(match.group(0).split()), bool(COMMAND.search(unit))))
    return found


def test_the_check_finds_run_times_and_their_commands():
    text = ("Install and run the tests (about 100 s on 2\ncores):\n\n    python3 -m pytest tests\n\n"
            "    rebound-pfvi compare --scene kepler   # 17 s\n\n"
            "The sweep took 58\ns on 2 cores.\n\n"
            "Errors of 1e-10 AU in 0.0073 s per run.\n")
    assert stated_run_times(text) == [("about 100 s", True), ("# 17 s", True), ("58 s", False)]


@pytest.mark.parametrize("page", PAGES, ids=lambda p: str(p.relative_to(ROOT)))
def test_every_stated_run_time_names_its_command(page):
    bare = [said for said, named in stated_run_times(page.read_text(encoding="utf-8")) if not named]
    assert bare == [], f"{page.name}: run times without the command that produced them: {bare}"


def test_readme_states_run_times():
    assert len(stated_run_times((ROOT / "README.md").read_text(encoding="utf-8"))) >= 8


def test_the_ratio_to_ias15_is_the_pages_one_everywhere():
    sys.path.insert(0, str(ROOT / "benchmarks"))
    try:
        import pages_summary
    finally:
        sys.path.remove(str(ROOT / "benchmarks"))
    low, high = pages_summary.ias15_ratio_range(ROOT / "docs" / "results")
    stated = f"{low:.2f}-{high:.2f}"
    assert f"{demo.PAGES_IAS15_RATIO[0]:.2f}-{demo.PAGES_IAS15_RATIO[1]:.2f}" == stated, (
        f"the pages give {stated}: update rebound_pfvi.demo.PAGES_IAS15_RATIO, README.md and docs")
    assert f"{stated} times IAS15's wall time on all 13 pages with gravity" in (ROOT / "README.md").read_text()
    assert f"takes {stated} times IAS15's wall time" in (ROOT / "docs" / "results.md").read_text()
    assert f"{stated}x IAS15's wall time" in " ".join((ROOT / "docs" / "adaptive.md").read_text().split())
    lines = []
    demo.run_demo(orbits=1, write=lines.append)
    assert f"took {stated} of IAS15's wall time" in lines[-1]


def test_the_epsilon_that_matches_ias15_is_the_measured_one_everywhere():
    """The figures README.md and help(sim.integrator) give for pfvi's default
    and for epsilon 1e-12 against IAS15's default are docs/epsilon-match.md's
    (benchmarks/epsilon_match.py); rerun the page and they must follow."""
    import rebound

    import rebound_pfvi  # noqa: F401

    page = (ROOT / "docs" / "epsilon-match.md").read_text(encoding="utf-8")
    default = re.search(r"pfvi's default \(epsilon 1e-6\) ends (\S+) to (\S+) times IAS15's default error on "
                        r"these (\d+) pages, at (\S+)-(\S+) times its wall time", page)
    tight = re.search(r"pfvi at epsilon 1e-12 ends within a factor (\S+) of IAS15's default error on all (\d+) "
                      r"pages \((\d+) at or below it\), at (\S+)-(\S+) times its wall time", page)
    assert default and tight, "docs/epsilon-match.md lacks its summary: rerun benchmarks/epsilon_match.py"
    sim = rebound.Simulation()
    sim.integrator = "pfvi"
    texts = {"README.md": (ROOT / "README.md").read_text(encoding="utf-8"),
             "help(sim.integrator)": sim.integrator.__doc__}
    wanted = [f"default ends {default[1]} to {default[2]} times IAS15's default error",
              f"at {default[4]}-{default[5]} times its wall time",
              f"within a factor {tight[1]} of IAS15's default error on all {tight[2]} pages ({tight[3]} at or "
              f"below it), at {tight[4]}-{tight[5]} times its wall time",
              f"{default[3]} "]
    for name, text in texts.items():
        flat = " ".join(text.split())
        missing = [w for w in wanted if w not in flat]
        assert not missing, f"{name} does not state docs/epsilon-match.md's figures: {missing}"


def _recorder():
    sys.path.insert(0, str(ROOT / "benchmarks"))
    try:
        import stated_times
    finally:
        sys.path.remove(str(ROOT / "benchmarks"))
    return stated_times


def _records():
    import json

    return json.loads((ROOT / "docs" / "stated-times.json").read_text(encoding="utf-8"))


def test_every_run_time_readme_states_is_a_recorded_run():
    """Issue 41: README's times had gone stale (17 s stated, 50 s measured).
    Each one is a phrase that benchmarks/stated_times.py wrote from a run of
    the command beside it (docs/stated-times.json), copied or not."""
    recorder = _recorder()
    records = _records()
    assert set(records) == set(recorder.COMMANDS), "rerun python3 -P benchmarks/stated_times.py"
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    readme = " ".join(text.split())
    phrases = [p for r in records.values() for p in r["phrases"]]
    missing = [p for p in phrases if p not in readme]
    assert not missing, f"README.md does not state the recorded runs: {missing}"
    for said, _ in stated_run_times(text):
        figure = re.search(r"\d+(?:\.\d+)?\s?(?:s|min)\b", said).group(0)
        assert any(figure in p for p in phrases), f"README.md states {said!r}, which no recorded run gives"
    for name, r in records.items():
        assert r["wall_s"] > 0 and r["cpu_s"] > 0 and r["load_before"] >= 0, name
        assert f"{r['wall_s']:.0f} s" in r["phrases"][0], name


def test_no_stated_time_outlives_a_change_of_the_code_it_measured():
    """A recorded time holds for the sources it ran: the files each command
    runs must hash as they did at the recording (rerun the script after a
    change, then copy its phrases into README.md)."""
    recorder = _recorder()
    stale = [name for name, r in _records().items()
             if recorder.fingerprint(r["sources"]) != r["fingerprint"] or r["sources"] != recorder.COMMANDS[name][2]]
    assert not stale, (f"the code changed since these stated times were recorded: {stale}; rerun "
                       f"python3 -P benchmarks/stated_times.py --only {','.join(stale)} and update README.md")


def test_the_fingerprint_sees_a_change(tmp_path, monkeypatch):
    recorder = _recorder()
    (tmp_path / "a.py").write_text("x = 1\n")
    monkeypatch.setattr(recorder, "ROOT", tmp_path)
    before = recorder.fingerprint(["*.py"])
    (tmp_path / "a.py").write_text("x = 2\n")
    assert recorder.fingerprint(["*.py"]) != before
