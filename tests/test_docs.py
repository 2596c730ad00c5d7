"""The docs as a user meets them: every Python snippet of README.md and docs/
runs when saved as a script, and docs/integrator.md is what the C core says."""
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
PAGES = [ROOT / "README.md"] + sorted((ROOT / "docs").rglob("*.md"))


def _snippets():
    for page in PAGES:
        text = page.read_text(encoding="utf-8")
        for k, match in enumerate(re.finditer(r"```python\n(.*?)```", text, re.S)):
            yield pytest.param(match.group(1), id=f"{page.relative_to(ROOT)}#{k + 1}")


SNIPPETS = list(_snippets())


def test_there_are_snippets_to_run():
    names = {p.id.split("#")[0] for p in SNIPPETS}
    assert {"README.md", "docs/integrator.md"} <= names, names


@pytest.mark.slow
@pytest.mark.parametrize("code", SNIPPETS)
def test_every_python_snippet_runs_saved_as_a_script(code, tmp_path):
    """Saved as a file and run with python, in an empty folder (what a
    reader who copies it does): it must finish without an error. A snippet
    that starts worker processes needs its `if __name__ == "__main__":`."""
    script = tmp_path / "snippet.py"
    script.write_text(code, encoding="utf-8")
    done = subprocess.run([sys.executable, "-P", str(script)], cwd=tmp_path, capture_output=True, text=True,
                          timeout=600)
    assert done.returncode == 0, done.stderr[-3000:]


def test_integrator_page_is_what_the_core_says():
    from rebound_pfvi import integrator_page

    page = (ROOT / "docs" / "integrator.md").read_text(encoding="utf-8")
    assert page == integrator_page.page(), (
        "docs/integrator.md differs from the core: python3 -P -m rebound_pfvi.integrator_page docs/integrator.md")


def test_integrator_page_has_every_field_with_type_default_and_help_text():
    import rebound

    import rebound_pfvi
    from rebound_pfvi import integrator_page

    page = integrator_page.page()
    sim = rebound.Simulation()
    sim.integrator = "pfvi"
    names = set()
    for fd in sim.integrator.callbacks.field_descriptor_list:
        if fd.documentation:
            name = fd.name.decode()
            names.add(name)
            row = next(line for line in page.splitlines() if line.startswith(f"| `{name}` |"))
            doc = fd.documentation.decode().removeprefix("Statistic:").strip()
            assert doc.replace("|", "\\|") in row, name
            if name in rebound_pfvi.DEFAULTS:
                assert f"| `{rebound_pfvi.DEFAULTS[name]!r}` |" in row, name
    assert names == {f.name for f in integrator_page.fields()}
    assert set(rebound_pfvi.DEFAULTS) < names
    # The description is help(sim.integrator)'s first part, word for word.
    assert sim.integrator.callbacks.documentation.decode() in page
    for part in ("## What it is", "## When to use it", "## References", "## Options", "## Statistics",
                 "## Example"):
        assert part in page


def test_readme_reads_in_a_users_order():
    """What pfvi is (the paper by title and authors), Install with the two
    commands CI runs, the example (the integrator page's), when to use it,
    then the details; no placeholder left unfilled."""
    from rebound_pfvi import integrator_page

    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    first = readme.split("\n## ")[0]
    assert '"Phase-fitted\nDiscrete Lagrangian Integrators"' in first or \
        "Phase-fitted Discrete Lagrangian Integrators" in " ".join(first.split())
    assert "Kosmas" in first and "Vlachos" in first
    heads = [line[3:] for line in readme.splitlines() if line.startswith("## ")]
    assert heads[:4] == ["Install", "Example", "When to use it, and when not", "Details"], heads
    install = readme.split("## Install")[1].split("\n## ")[0]
    commands = [line.strip() for line in install.splitlines() if line.startswith("    python3 -m pip")]
    assert commands == ['python3 -m pip install ".[plot]" && python3 -P -m rebound_pfvi compare --output results',
                        'python3 -m pip install ".[test]" && python3 -P -m pytest tests']
    assert commands[1] in (ROOT / ".ci" / "run").read_text()
    assert f"```python\n{integrator_page.EXAMPLE}```" in readme
    assert "@T_" not in readme and "@WHEN" not in readme
