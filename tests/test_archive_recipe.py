"""Loading a Simulationarchive written with pfvi (issue 37): without
``import rebound_pfvi`` REBOUND fails as the docs say, and the recipe they
show (rebound_pfvi.ARCHIVE_RECIPE, in README.md, docs/integrator.md and
help(rebound_pfvi)) runs."""
import subprocess
import sys
import textwrap
from pathlib import Path

import rebound_pfvi
from rebound_pfvi import ARCHIVE_FAILURE, ARCHIVE_RECIPE, integrator_page

ROOT = Path(__file__).resolve().parent.parent


def run(code, folder):
    return subprocess.run([sys.executable, "-P", "-c", code], cwd=folder, capture_output=True, text=True,
                          timeout=120)


def words(text):
    return " ".join(text.split())


def test_the_recipe_runs_in_an_empty_folder(tmp_path):
    done = run(ARCHIVE_RECIPE, tmp_path)
    assert done.returncode == 0, done.stderr
    assert done.stdout.split() == ["pfvi", "3.0", "True"]  # what its comment says it prints
    assert [p.name for p in tmp_path.iterdir()] == ["pfvi-archive.bin"]


def test_every_page_shows_the_failure_and_the_recipe():
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    assert "```python\n" + ARCHIVE_RECIPE + "```" in readme
    assert words(ARCHIVE_FAILURE) in words(readme)
    page = integrator_page.page()
    assert "## Simulationarchives\n\n" + ARCHIVE_FAILURE + "\n\n```python\n" + ARCHIVE_RECIPE + "```" in page
    help_text = rebound_pfvi.__doc__
    assert words(ARCHIVE_FAILURE) in words(help_text)
    assert textwrap.indent(ARCHIVE_RECIPE, "    ").replace("    \n", "\n") in help_text


def test_without_the_import_rebound_fails_as_documented(tmp_path):
    assert run(ARCHIVE_RECIPE, tmp_path).returncode == 0
    done = run(textwrap.dedent("""
        import warnings
        import rebound
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            sim = rebound.Simulation("pfvi-archive.bin")
        print([str(w.message).split(".")[0] for w in caught])
        print(sim.integrator)
        try:
            sim.integrate(4.0)
        except RuntimeError as error:
            print("RuntimeError:", error)
    """), tmp_path)
    assert done.returncode == 0, done.stderr
    assert done.stdout.splitlines() == ["['The binary file seems to be corrupted']", "ias15",
                                        "RuntimeError: Integrator not found."]
    # Simulationarchive(path)[-1], the other way users load: it raises at load.
    done = run(textwrap.dedent("""
        import warnings
        import rebound
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            try:
                rebound.Simulationarchive("pfvi-archive.bin")[-1]
            except RuntimeError as error:
                print("RuntimeError:", error)
        print([str(w.message).split(".")[0] for w in caught])
    """), tmp_path)
    assert done.returncode == 0, done.stderr
    assert done.stdout.splitlines() == ["RuntimeError: Integrator not found.",
                                        "['The binary file seems to be corrupted']"]
    for said in ('"The binary file seems to be corrupted"', 'sim.integrator reads "ias15"',
                 'rebound.Simulationarchive(path)[-1] gives a RuntimeWarning',
                 'raises "RuntimeError: Integrator not found." at load',
                 '"RuntimeError: Integrator not found."', "import rebound_pfvi before loading"):
        assert said in ARCHIVE_FAILURE, said
