"""Type hints on the public Python API, checked by mypy (issue 18, item 4)."""
import ast
import os
import pathlib
import subprocess
import sys

import pytest

import rebound_pfvi

pytestmark = pytest.mark.slow  # runners, CLI and pages: skipped by `pytest -m "not slow"`

ROOT = pathlib.Path(__file__).resolve().parent.parent


def _package_source():
    """The repository's sources if the tests run from a checkout, else the installed package's."""
    source = ROOT / "rebound_pfvi"
    return source if (source / "compare.py").exists() else pathlib.Path(rebound_pfvi.__file__).parent


def test_mypy_is_clean():
    pytest.importorskip("mypy")
    source = _package_source()
    config = ROOT / "pyproject.toml"
    command = [sys.executable, "-m", "mypy", "--no-incremental", "--cache-dir", os.devnull]
    if config.exists():
        command += ["--config-file", str(config)]
    done = subprocess.run(command + [str(source)], capture_output=True, text=True, timeout=600, cwd=source.parent)
    assert done.returncode == 0, done.stdout + done.stderr
    assert "Success: no issues found" in done.stdout


def _unannotated(path):
    """Public module-level functions and public methods of public classes lacking a hint."""
    tree = ast.parse(path.read_text())
    functions = [node for node in tree.body if isinstance(node, ast.FunctionDef)]
    for cls in tree.body:
        if isinstance(cls, ast.ClassDef) and not cls.name.startswith("_"):
            functions += [node for node in cls.body if isinstance(node, ast.FunctionDef)]
    missing = []
    for item in functions:
        if item.name.startswith("_") and item.name not in ("__init__", "__call__"):
            continue
        args = item.args.posonlyargs + item.args.args + item.args.kwonlyargs
        args += [a for a in (item.args.vararg, item.args.kwarg) if a is not None]
        unannotated = [a.arg for a in args if a.annotation is None and a.arg not in ("self", "cls")]
        if unannotated or item.returns is None:
            missing.append(f"{path.name}:{item.lineno} {item.name}")
    return missing


def test_public_functions_are_annotated():
    # mypy checks the bodies of annotated functions only: this makes sure the public ones are.
    source = _package_source()
    missing = [m for path in sorted(source.glob("*.py")) for m in _unannotated(path)]  # every module
    assert missing == []
