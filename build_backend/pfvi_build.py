"""The build backend of rebound_pfvi: setuptools', asking for the rebound the
environment already has.

The C core must be compiled against the headers of the rebound it will run
with. pip builds in an isolated environment into which it installs the build
requirements afresh: asked for the supported range (``rebound>=5.0,<5.3``)
it would fetch the newest rebound in it, while the environment being
installed into keeps its own (5.1.1, say), which the range allows; the core
would then be compiled against 5.2.2 and refused at import. So the build asks
for exactly the rebound installed in the environment of the interpreter that
runs the build (the one pip installs into) when that version is in the range,
and for the range otherwise (no rebound, or one outside it: pip then installs
the newest in the range for the build and for running alike).

The range has one place: the ``rebound`` entry of ``[project] dependencies``
in pyproject.toml, which is also the runtime requirement. setup.py refuses
to compile against a rebound outside it (a build without isolation takes
whatever rebound is importable).
"""
import os
import sys
import sysconfig
from importlib import metadata

from setuptools import build_meta as _setuptools
from setuptools.build_meta import *  # noqa: F401,F403  (every hook not redefined below)

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def rebound_requirement(pyproject=os.path.join(ROOT, "pyproject.toml")):
    """The ``rebound`` requirement of ``[project] dependencies`` (a packaging Requirement)."""
    from packaging.requirements import Requirement

    if sys.version_info >= (3, 11):
        import tomllib
    else:
        import tomli as tomllib
    with open(pyproject, "rb") as f:
        dependencies = tomllib.load(f)["project"]["dependencies"]
    found = [Requirement(d) for d in dependencies if Requirement(d).name == "rebound"]
    if len(found) != 1:
        raise RuntimeError(f"{pyproject}: [project] dependencies must name rebound once, not {len(found)} times")
    return found[0]


def installed_rebound(paths=None):
    """The version of rebound installed in this interpreter's environment, or None.

    Inside pip's isolated build, sys.path hides that environment's
    site-packages, but sysconfig still names them (sys.prefix is unchanged).
    """
    if paths is None:
        scheme = sysconfig.get_paths()
        paths = sorted({scheme["purelib"], scheme["platlib"]})
    found = [d.version for d in metadata.distributions(name="rebound", path=list(paths))]
    return found[0] if found else None


def build_requirement(installed=None, requirement=None):
    """What the build needs: ``rebound==<installed>`` when the installed
    rebound is in the range, the range otherwise."""
    requirement = requirement or rebound_requirement()
    if installed is not None and requirement.specifier.contains(installed, prereleases=True):
        return f"rebound=={installed}"
    return str(requirement)


def get_requires_for_build_wheel(config_settings=None):
    return _setuptools.get_requires_for_build_wheel(config_settings) + [build_requirement(installed_rebound())]


def get_requires_for_build_editable(config_settings=None):
    return _setuptools.get_requires_for_build_editable(config_settings) + [build_requirement(installed_rebound())]
