"""The Python modules of rebound_pfvi call only downward, as the C core's
layers do (issue 37): no module imports one that imports it back, directly
or through others. Every import counts, at the top, in a function or under
TYPE_CHECKING: each is a dependency of the module."""
import ast
from pathlib import Path

import rebound_pfvi

PACKAGE = Path(rebound_pfvi.__file__).resolve().parent
MODULES = {p.stem: p for p in PACKAGE.glob("*.py")}


def imported_modules(path):
    """The modules of rebound_pfvi that the file imports (``from . import NAME``
    of a name that is not a module imports the package, __init__)."""
    found = set()
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.ImportFrom):
            if node.level == 1 or (node.level == 0 and (node.module or "").split(".")[0] == "rebound_pfvi"):
                parts = (node.module or "").split(".")
                inner = parts[0] if node.level == 1 else (parts[1] if len(parts) > 1 else "")
                if inner:
                    found.add(inner)
                else:
                    found |= {a.name if a.name in MODULES else "__init__" for a in node.names}
        elif isinstance(node, ast.Import):
            for alias in node.names:
                parts = alias.name.split(".")
                if parts[0] == "rebound_pfvi":
                    found.add(parts[1] if len(parts) > 1 else "__init__")
    return found - {path.stem}


def graph():
    return {name: imported_modules(path) for name, path in MODULES.items()}


def cycles(edges):
    """Every strongly connected group of more than one module (Tarjan)."""
    index, low, stack, on_stack, groups = {}, {}, [], set(), []

    def visit(v):
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in edges.get(v, ()):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            group = set()
            while True:
                w = stack.pop()
                on_stack.discard(w)
                group.add(w)
                if w == v:
                    break
            if len(group) > 1:
                groups.append(sorted(group))

    for v in sorted(edges):
        if v not in index:
            visit(v)
    return groups


def test_the_parser_sees_every_form_of_import(tmp_path):
    source = tmp_path / "probe.py"
    source.write_text("from __future__ import annotations\nimport os\nfrom typing import TYPE_CHECKING\n"
                      "from . import DEFAULTS, runs\nfrom .units import REBOUND_UNITS\n"
                      "import rebound_pfvi.verdict\nif TYPE_CHECKING:\n    from .scenes import Scene\n"
                      "def f():\n    from rebound_pfvi.report import write\n")
    assert imported_modules(source) == {"__init__", "runs", "units", "verdict", "scenes", "report"}
    # A circle of two and one of three are found, an edge down is not.
    assert cycles({"a": {"b"}, "b": {"a"}, "c": {"d"}, "d": {"e"}, "e": {"c"}, "f": {"a"}}) == [
        ["a", "b"], ["c", "d", "e"]]


def test_no_module_imports_one_that_imports_it_back():
    edges = graph()
    assert {"compare", "report", "runs", "_core", "__init__"} <= set(edges)
    back = sorted((a, b) for a in edges for b in edges[a] if a < b and a in edges.get(b, ()))
    assert back == [], f"modules that import each other: {back}"
    assert cycles(edges) == [], f"import circles: {cycles(edges)}"
    # The former circle (issue 37): report reads compare's Results, compare never reads report.
    assert "report" not in edges["compare"]
    # (_reboundx: the wrapper of REBOUNDx's add_operator, installed at import; it imports nothing of ours.)
    assert edges["__init__"] == {"_core", "_reboundx"}
    assert not edges.get("_reboundx")
