"""The core's house rules, checked on its source: every ``ocp`` module imports, its import graph (module level
imports, read with ``ast``) has no cycle, and no module is over the size limit of the style guide; and, run in a
process of its own, the server's app imports no SciPy (the numerical stack is the workers')."""

from __future__ import annotations

import ast
import importlib
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
OCP = ROOT / "ocp"
MAX_LINES = 450


def _modules() -> dict[str, Path]:
    out = {}
    for path in sorted(OCP.rglob("*.py")):
        parts = path.relative_to(ROOT).with_suffix("").parts
        out[".".join(parts[:-1] if parts[-1] == "__init__" else parts)] = path
    return out


def _imports(name: str, path: Path, known: set[str]) -> set[str]:
    """The ``ocp`` modules ``name`` imports at module level (``if TYPE_CHECKING`` blocks and function bodies
    excluded: they do not run on import); ``from pkg import mod`` counts as importing ``pkg.mod``."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    found: set[str] = set()
    for node in tree.body:
        if isinstance(node, ast.Import):
            found |= {a.name for a in node.names}
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                parts = package.split(".")
                base = ".".join(parts[: len(parts) - node.level + 1] + ([base] if base else []))
            found.add(base)
            found |= {f"{base}.{a.name}" for a in node.names}
    return {m for m in found if m in known and m != name}


def _graph() -> dict[str, set[str]]:
    mods = _modules()
    return {name: _imports(name, path, set(mods)) for name, path in mods.items()}


def _cycle(graph: dict[str, set[str]]) -> list[str]:
    """One cycle of ``graph`` (a list of modules, first repeated last), or [] when it is acyclic."""
    state: dict[str, int] = {}
    stack: list[str] = []

    def visit(node: str) -> list[str]:
        state[node] = 1
        stack.append(node)
        for nxt in sorted(graph[node]):
            if state.get(nxt) == 1:
                return [*stack[stack.index(nxt):], nxt]
            if nxt not in state and (found := visit(nxt)):
                return found
        stack.pop()
        state[node] = 2
        return []

    for node in sorted(graph):
        if node not in state and (found := visit(node)):
            return found
    return []


def test_the_cycle_finder_finds_a_cycle() -> None:
    assert _cycle({"a": {"b"}, "b": {"c"}, "c": {"a"}}) == ["a", "b", "c", "a"]
    assert _cycle({"a": {"b"}, "b": set(), "c": {"a", "b"}}) == []


def test_the_core_import_graph_is_acyclic() -> None:
    graph = _graph()
    assert "ocp.optimize.solve" in graph and "ocp.optimize.collocation" in graph["ocp.optimize.solve"]
    # a package's __init__ importing its own modules is the package, not a cycle
    inner = {name: {m for m in deps if not (name.startswith(m + ".") and m in graph)} for name, deps in graph.items()}
    assert _cycle(inner) == []


@pytest.mark.parametrize("name", sorted(_modules()))
def test_every_core_module_imports(name: str) -> None:
    importlib.import_module(name)


def test_no_core_module_is_over_the_size_limit() -> None:
    sizes = {name: len(path.read_text(encoding="utf-8").splitlines()) for name, path in _modules().items()}
    assert {name: n for name, n in sizes.items() if n > MAX_LINES} == {}


def _all_imports(path: Path) -> set[str]:
    """Every module ``path`` imports anywhere (function bodies included), as written."""
    found: set[str] = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            found |= {a.name for a in node.names}
        elif isinstance(node, ast.ImportFrom) and not node.level and node.module:
            found.add(node.module)
    return found


@pytest.mark.parametrize(("layer", "below"), [("ocp", ("service", "clients")), ("service", ("clients",))])
def test_dependencies_point_one_way(layer: str, below: tuple[str, ...]) -> None:
    """clients -> service -> ocp: a layer never imports the layers that depend on it, not even lazily."""
    wrong = {str(p.relative_to(ROOT)): sorted(m for m in _all_imports(p) if m.split(".")[0] in below)
             for p in sorted((ROOT / layer).rglob("*.py"))}
    assert {k: v for k, v in wrong.items() if v} == {}


def test_no_service_or_client_module_is_over_the_size_limit() -> None:
    sizes = {str(p.relative_to(ROOT)): len(p.read_text(encoding="utf-8").splitlines())
             for layer in ("service", "clients") for p in sorted((ROOT / layer).rglob("*.py"))}
    assert {name: n for name, n in sizes.items() if n > MAX_LINES} == {}


def test_the_server_process_does_not_import_scipy() -> None:
    """The server only validates and dispatches; SciPy (~1 s to import) belongs in the workers that compute.
    Every server start (``serve.sh``, a restart, each integration test's server) pays for what the app imports."""
    code = ("import sys\nfrom service.app import create_app\nfrom service.settings import Settings\n"
            "create_app(Settings())\nprint(sorted(m for m in sys.modules if m.split('.')[0] == 'scipy')[:3])")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, cwd=ROOT)
    assert out.stdout.strip() == "[]"
