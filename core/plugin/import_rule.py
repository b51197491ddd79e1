"""What a plugin may import from cistrack, built-in or third-party alike.

A plugin module imports the public namespace (``cistrack`` and :mod:`cistrack.api`) and the
lower packages it names (:data:`ALLOWED`), plus modules of its own plugin family (for a
built-in, ``cistrack.plugins.<family>``); a plugin's tests may also import :mod:`cistrack.testing`.
Never the pipeline's own floors (runs, the fit workflow, scenario, results, evaluation, studies,
cli), never the plugin machinery (:mod:`cistrack.plugin`: ``hookimpl`` and the registry come
from :mod:`cistrack.api`), and never another plugin family.

    imports = imports_in_source(path.read_text(), "my_package.my_filter")
    forbidden_imports("my_package.my_filter", imports)   # -> ["cistrack.runs.pipeline", ...]

``tests/core/test_plugin_imports.py`` applies this rule to every built-in plugin and to the
plugin template.
"""
from __future__ import annotations

import ast
from collections.abc import Iterable
from importlib import import_module

__all__ = ["ALLOWED", "TESTS_ALSO", "PLUGINS", "plugin_family", "imports_in_source", "forbidden_imports"]

ALLOWED: tuple[str, ...] = (
    "cistrack.api", "cistrack.errors", "cistrack.units", "cistrack.lazy", "cistrack.threads",
    "cistrack.numerics", "cistrack.model", "cistrack.interfaces", "cistrack.propagation", "cistrack.astro",
    "cistrack.least_squares", "cistrack.interrupts",
)
"""The packages and modules (with everything below them) any plugin module may import
(:mod:`cistrack.interrupts` for ``plugin_fault``: a plugin that calls another plugin, as the PGM
calls its clusterer, names that plugin's failure the way the pipeline does)."""

TESTS_ALSO: tuple[str, ...] = ("cistrack.testing",)
"""Allowed in a plugin's tests only: the conformance suite and reference systems."""

PLUGINS = "cistrack.plugins"
"""The namespace of the built-in plugins; ``cistrack.plugins.<family>`` is one family."""

Imports = Iterable[tuple[str, Iterable[str]]]
"""(module, names) per import statement: ``import a.b`` is ("a.b", ()), ``from a import b, c``
is ("a", ("b", "c")), relative imports resolved."""


def plugin_family(module: str) -> str | None:
    """``cistrack.plugins.sensors.frames`` -> ``cistrack.plugins.sensors``; None for a module
    outside the built-in plugins (a third party's)."""
    parts = module.split(".")
    if parts[:2] != PLUGINS.split(".") or len(parts) < 3:
        return None
    return ".".join(parts[:3])


def imports_in_source(source: str, module: str, is_package: bool = False) -> list[tuple[str, list[str]]]:
    """Every import statement anywhere in ``source`` (the text of ``module``; ``is_package`` for
    an ``__init__.py``), as (module, names) with relative imports resolved."""
    package = module if is_package else module.rpartition(".")[0]
    out: list[tuple[str, list[str]]] = []
    for node in ast.walk(ast.parse(source, module)):
        if isinstance(node, ast.Import):
            out += [(a.name, []) for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            target = node.module or ""
            if node.level:
                base = package.split(".")[: len(package.split(".")) - (node.level - 1)]
                target = ".".join(base + ([node.module] if node.module else []))
            out.append((target, [a.name for a in node.names]))
    return out


def forbidden_imports(module: str, imports: Imports, tests: bool = False) -> list[str]:
    """The cistrack modules ``module`` imports against the rule, sorted, each once.

    ``module`` is the importing module's dotted name (it decides the plugin family);
    ``imports`` as :func:`imports_in_source` gives them; ``tests``: ``module`` is a plugin's
    test, which may also import :data:`TESTS_ALSO`."""
    allowed = ALLOWED + (TESTS_ALSO if tests else ())
    family = plugin_family(module)
    bad = {name for name in _imported_modules(imports)
           if not _allowed(name, allowed, family)}
    return sorted(bad)


def _imported_modules(imports: Imports) -> set[str]:
    """The cistrack modules named: ``from cistrack import hookimpl`` is the top-level namespace,
    ``from cistrack import runs`` (not a public top-level name) the package ``cistrack.runs``."""
    out: set[str] = set()
    for target, names in imports:
        if target != "cistrack" and not target.startswith("cistrack."):
            continue
        names = list(names)
        if target in ("cistrack", PLUGINS) and names:
            public = _top_level_names() if target == "cistrack" else set()
            out |= {target if n in public else f"{target}.{n}" for n in names}
        else:
            out.add(target)
    return out


def _top_level_names() -> set[str]:
    """The public names of the package ``cistrack`` (the root package, already imported)."""
    return set(import_module("cistrack").__all__)


def _allowed(name: str, allowed: tuple[str, ...], family: str | None) -> bool:
    if name == "cistrack":
        return True
    within = allowed + ((family,) if family else ())
    return any(name == p or name.startswith(p + ".") for p in within)
