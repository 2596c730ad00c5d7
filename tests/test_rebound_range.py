"""The supported range of rebound (issue 37): its one place is the rebound
entry of pyproject.toml's [project] dependencies; the build backend asks for
the installed rebound within it, and the import refuses a rebound outside it."""
import os
import re
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest
import rebound

import rebound_pfvi

ROOT = Path(__file__).resolve().parent.parent
tomllib = pytest.importorskip("tomllib")
requirements = pytest.importorskip("packaging.requirements")


def pyproject():
    return tomllib.loads((ROOT / "pyproject.toml").read_text())


def rebound_requirements(entries):
    return [requirements.Requirement(e) for e in entries if requirements.Requirement(e).name == "rebound"]


def backend():
    pytest.importorskip("setuptools")
    sys.path.insert(0, str(ROOT / "build_backend"))
    try:
        import pfvi_build
    finally:
        sys.path.remove(str(ROOT / "build_backend"))
    return pfvi_build


def test_the_range_has_one_place_and_the_running_rebound_is_in_it():
    project = pyproject()
    runtime = rebound_requirements(project["project"]["dependencies"])
    assert len(runtime) == 1, runtime
    # The build requirement is not written twice: the backend derives it.
    assert rebound_requirements(project["build-system"]["requires"]) == []
    assert project["build-system"]["build-backend"] == "pfvi_build"
    assert backend().rebound_requirement() == runtime[0]
    assert runtime[0].specifier.contains(rebound.__version__)
    # The installed package carries the same range (else: reinstall it).
    assert rebound_pfvi._core.supported_range() == str(runtime[0].specifier)
    # The core was compiled against the running rebound (the import checked it).
    assert rebound_pfvi._core.lib.pfvi_rebound_version_compiled().decode() == rebound.__version__


def test_the_range_covers_5_0_to_5_2_and_readme_states_it():
    spec = rebound_requirements(pyproject()["project"]["dependencies"])[0].specifier
    assert [v for v in ("4.4.11", "5.0.0", "5.0.1", "5.1.0", "5.1.1", "5.2.0", "5.2.2", "5.3.0")
            if spec.contains(v)] == ["5.0.0", "5.0.1", "5.1.0", "5.1.1", "5.2.0", "5.2.2"]
    readme = (ROOT / "README.md").read_text()
    assert "rebound>=5.0,<5.3" in readme and spec == requirements.Requirement("rebound>=5.0,<5.3").specifier


def test_the_build_asks_for_the_installed_rebound_when_in_range():
    build = backend()
    supported = build.rebound_requirement()
    assert build.build_requirement("5.1.1", supported) == "rebound==5.1.1"
    assert build.build_requirement("5.0.0", supported) == "rebound==5.0.0"
    for outside in ("4.4.11", "5.3.0", None):  # none installed, or one pip must replace
        assert build.build_requirement(outside, supported) == str(supported)
    site = os.path.dirname(os.path.dirname(os.path.abspath(rebound.__file__)))
    assert build.installed_rebound([site]) == rebound.__version__
    assert build.installed_rebound([str(ROOT / "docs")]) is None


@pytest.mark.parametrize("running", ["4.4.11", "5.3.0"])
def test_import_under_a_rebound_outside_the_range_is_refused_by_name(running):
    supported = rebound_pfvi._core.supported_range()
    if supported is None:
        pytest.skip("rebound_pfvi is not installed: no range in its metadata")
    result = subprocess.run([sys.executable, "-P", "-c", textwrap.dedent(f"""
        import rebound
        rebound.__version__ = {running!r}
        import rebound_pfvi
    """)], capture_output=True, text=True, timeout=60)
    assert result.returncode == 1
    last = result.stderr.strip().splitlines()[-1]
    # (The child names its interpreter as it resolved it: the path may differ in form from ours.)
    assert re.fullmatch(re.escape(
        f"ImportError: rebound_pfvi supports rebound{supported} (4.x has no integrator registry; a rebound newer "
        f"than the range is untested until its headers are checked), but rebound {running} is running. Install a "
        f"rebound in the range and rebuild rebound_pfvi against it: ") + r"\S*python\S* "
        + re.escape(f"-m pip install 'rebound{supported}' && ") + r"\S*python\S* "
        + re.escape("-m pip install --force-reinstall --no-deps ") + r".+", last), last
