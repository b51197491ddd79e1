"""The framework's packages and their order, checked on the source.

Each package of ``cistrack`` (core/) imports only the packages below it in :data:`LAYERS`, no
module imports itself back through a chain of imports, every package says in its docstring what
it holds, and no module of the project uses an import path that only the deprecation aliases keep
alive.
"""
from __future__ import annotations

import ast
from pathlib import Path

import pytest

from cistrack._moved import MOVED

from source_imports import CORE, PLUGINS, ROOT, import_statements, module_name, sources

#: Lowest first. A module may import its own layer and the layers before it.
LAYERS: list[tuple[str, ...]] = [
    ("cistrack.errors", "cistrack.units", "cistrack.lazy", "cistrack.threads", "cistrack.numerics", "cistrack._moved", "cistrack.env_flags",
     "cistrack.interrupts",
     "cistrack.scenarios", "cistrack.data"),  # the last two hold data files only
    ("cistrack.model",),
    ("cistrack.interfaces",),
    ("cistrack.plugin",),
    ("cistrack.propagation",),
    ("cistrack.astro",),
    ("cistrack.least_squares",),
    ("cistrack.results",),
    ("cistrack.testing",),
    ("cistrack.evaluation",),
    ("cistrack.scenario",),
    ("cistrack.runs",),
    ("cistrack.fitting",),
    ("cistrack.studies",),
    ("cistrack.cli",),
    ("cistrack.api", "cistrack.console"),
]


_module_name, _sources = module_name, sources


MODULES = {_module_name(p): p for p in _sources(CORE) + _sources(PLUGINS)}


def _imports(path: Path) -> set[str]:
    """The project modules ``path`` imports, anywhere in the file (``from a import b`` is an import
    of ``a.b`` when that is a module, else of ``a``)."""
    out: set[str] = set()
    for target, names in import_statements(path):
        if not names:
            out.add(target)
        for n in names:
            if target == "cistrack" and n == "__version__":
                continue  # the version is the root package's own
            out.add(f"{target}.{n}" if f"{target}.{n}" in MODULES else target)
    return {n for n in out if n == "cistrack" or n.startswith("cistrack.")}


def _layer(name: str) -> int | None:
    for i, members in enumerate(LAYERS):
        if any(name == m or name.startswith(m + ".") for m in members):
            return i
    return None


CORE_MODULES = sorted(n for n in MODULES if not n.startswith("cistrack.plugins"))


def test_every_framework_module_belongs_to_a_layer():
    assert [n for n in CORE_MODULES if n != "cistrack" and _layer(n) is None] == []


@pytest.mark.parametrize("name", [n for n in CORE_MODULES if n != "cistrack"])
def test_module_imports_only_its_own_and_lower_layers(name):
    own = _layer(name)
    above = sorted(n for n in _imports(MODULES[name]) if n != "cistrack" and (_layer(n) or 0) > own)
    assert not above, (f"{name} (layer {LAYERS[own][0]}) imports {above} from a higher layer; "
                       "move the shared part down or the importing module up")


@pytest.mark.parametrize("name", [n for n in CORE_MODULES if n != "cistrack"])
def test_framework_modules_import_names_from_where_they_are_defined(name):
    """``from cistrack import hookimpl`` is for plugins; inside the framework it hides a layer."""
    assert "cistrack" not in _imports(MODULES[name])


def _cycles() -> list[list[str]]:
    """Strongly connected components of more than one module (Tarjan)."""
    graph = {n: sorted(d for d in _imports(p) if d in MODULES and d != n) for n, p in MODULES.items()}
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on: set[str] = set()
    out: list[list[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in graph[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    for v in graph:
        if v not in index:
            visit(v)
    return out


def test_no_module_imports_itself_back_through_a_chain_of_imports():
    # A package's __init__ importing its own submodules is not a cycle of concern: leave it out.
    cycles = [c for c in _cycles() if not any(n + "." in m for n in c for m in c if n != m)]
    assert cycles == []


def test_at_most_a_dozen_modules_sit_directly_in_core():
    assert len([p for p in CORE.glob("*.py")]) <= 12


@pytest.mark.parametrize("package", sorted(p.parent for p in CORE.rglob("__init__.py") if "__pycache__" not in p.parts),
                         ids=lambda p: str(p.relative_to(ROOT)))
def test_every_framework_package_says_what_it_holds(package):
    doc = ast.get_docstring(ast.parse((package / "__init__.py").read_text()))
    assert doc and len(doc) > 40, f"{package.relative_to(ROOT)}/__init__.py needs a docstring saying what it holds"


#: modules that became packages of the same name; their old names resolve with a warning
_REPLACED_MODULES = {"cistrack.results": "cistrack.results.store", "cistrack.scenario": "cistrack.scenario.loading"}


@pytest.mark.parametrize("path", _sources(CORE) + _sources(PLUGINS) + _sources(ROOT / "tests") + _sources(ROOT / "benchmarks"),
                         ids=lambda p: str(p.relative_to(ROOT)))
def test_project_code_uses_no_deprecated_import_path(path):
    if path.name in ("test_moved_modules.py", "_moved.py") or "plugin_packages" in path.parts:
        return  # the alias table, its test, and the plugin package written against the old paths on purpose
    used = []
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        names = []
        if isinstance(node, ast.Import):
            names = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom) and not node.level and node.module:
            names = [node.module] + [f"{node.module}.{a.name}" for a in node.names]
            if node.module in _REPLACED_MODULES:  # names of a module that became a package
                used += [f"{node.module}.{a.name}" for a in node.names if f"{node.module}.{a.name}" not in MODULES]
        used += [n for n in names if n in MOVED]
    assert not used, f"{path.relative_to(ROOT)} imports {used} through deprecated paths (see cistrack._moved)"
