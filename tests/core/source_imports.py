"""Reading the project's imports from its source (for the layering tests): module names of files
under core/ and plugins/, and every import statement with relative imports resolved."""
from __future__ import annotations

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
CORE, PLUGINS = ROOT / "core", ROOT / "plugins"


def module_name(path: Path) -> str:
    """``core/runs/pipeline.py`` -> ``cistrack.runs.pipeline``; plugins/ under ``cistrack.plugins``."""
    if path.is_relative_to(CORE):
        parts = ("cistrack",) + path.relative_to(CORE).with_suffix("").parts
    else:
        parts = ("cistrack", "plugins") + path.relative_to(PLUGINS).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def sources(root: Path) -> list[Path]:
    return sorted(p for p in root.rglob("*.py") if "__pycache__" not in p.parts)


def import_statements(path: Path) -> list[tuple[str, list[str]]]:
    """Every import of ``path``, anywhere in it, as (module, names): ``import a.b`` gives
    ("a.b", []), ``from .x import y, z`` ("<package>.x", ["y", "z"]) with the package resolved."""
    mod = module_name(path)
    package = mod if path.name == "__init__.py" else mod.rsplit(".", 1)[0]
    out: list[tuple[str, list[str]]] = []
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            out += [(a.name, []) for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")
                target = ".".join(base[: len(base) - (node.level - 1)] + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            out.append((target, [a.name for a in node.names]))
    return out
