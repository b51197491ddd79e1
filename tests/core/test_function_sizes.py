"""Functions are short and take few parameters: every function and method in core/ and plugins/
is at most :data:`MAX_LINES` lines long (``def`` line to last line, docstring included, decorators
not) and takes at most :data:`MAX_PARAMS` parameters (``self`` and ``cls`` not counted; ``*args``
and ``**kwargs`` count one each), unless a rule below or an entry of :data:`EXCEPTIONS` says why.

Complexity (ruff's mccabe, C901) is set in pyproject.toml and checked by test_code_habits.py.

Two rules instead of entries:

* **Compiled kernels** (decorated with ``njit``, ``lazy_njit``, ``vectorize`` ...): numba's
  nopython mode takes plain arrays and scalars, not objects, so the arrays a kernel works on are
  its parameters; and a kernel's straight-line arithmetic is the equations of motion or an
  integrator stage written in the equations' own layout, which splitting would scatter without
  making it easier to check against the formulas. Exempt from both limits.
* **Component constructors** (``__init__`` of a class deriving from cistrack's ``Component``):
  the parameters are the component's declared settings, scikit-learn style (the settings ARE the
  API, validated and documented one by one). Exempt from the parameter count, not from length.
"""
from __future__ import annotations

import ast
from dataclasses import dataclass
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
MAX_LINES = 60
MAX_PARAMS = 8
FOLDERS = ("core", "plugins")
KERNEL_DECORATORS = {"njit", "lazy_njit", "jit", "vectorize", "guvectorize", "cfunc"}
TEMPORARY = "owner refactoring (issue 48)"

#: "path::qualname" -> one-line reason. An entry whose reason starts with TEMPORARY marks a
#: function whose owner is refactoring it now; the others are real reasons and must stay needed.
EXCEPTIONS: dict[str, str] = {
    "core/api.py::run": "the Python twin of `cistrack run`: one keyword-only argument per option of "
                        "the command (overwrite is --overwrite), as a user reads them in the docs",
    "core/api.py::study": "the Python twin of `cistrack study run`: one keyword-only argument per option "
                          "of the command (overwrite is --overwrite), as docs/python-api.md lists them",
    "core/least_squares/differential_correction.py::fit_orbit": "the least-squares entry point: the model, "
        "the data, the start and its epoch, then one keyword-only argument per option of the fit (prior, "
        "options, solve-for parameters, the first pass's left-out rows), as its docstring lists them",
    "core/runs/export.py::export_run": "the Python twin of `cistrack export` on a run: one argument per "
                                       "option of the command (path is --out), as docs/export.md shows them, "
                                       "with the registry, the stage log and the words its refusals use",
}


@dataclass(frozen=True)
class Function:
    path: str
    qualname: str
    lines: int
    params: int
    kernel: bool
    constructor: bool

    @property
    def key(self) -> str:
        return f"{self.path}::{self.qualname}"


def _decorator_name(node: ast.expr) -> str:
    if isinstance(node, ast.Call):
        node = node.func
    if isinstance(node, ast.Attribute):
        return node.attr
    return node.id if isinstance(node, ast.Name) else ""


def _n_params(fn: ast.FunctionDef | ast.AsyncFunctionDef, method: bool) -> int:
    a = fn.args
    names = [x.arg for x in a.posonlyargs + a.args + a.kwonlyargs]
    if method and names and names[0] in ("self", "cls"):
        names = names[1:]
    return len(names) + (a.vararg is not None) + (a.kwarg is not None)


def _trees() -> dict[str, ast.Module]:
    return {str(p.relative_to(ROOT)): ast.parse(p.read_text())
            for folder in FOLDERS for p in sorted((ROOT / folder).rglob("*.py")) if "__pycache__" not in p.parts}


def _component_classes(trees: dict[str, ast.Module]) -> set[str]:
    """Names of the classes deriving from Component, through any chain of bases in the tree."""
    bases: dict[str, set[str]] = {}
    for tree in trees.values():
        for node in ast.walk(tree):
            if isinstance(node, ast.ClassDef):
                bases.setdefault(node.name, set()).update(_decorator_name(b) for b in node.bases)
    found = {"Component"}
    while True:
        more = {name for name, b in bases.items() if b & found} - found
        if not more:
            return found
        found |= more


def _functions() -> list[Function]:
    trees = _trees()
    components = _component_classes(trees)
    out: list[Function] = []

    def visit(node: ast.AST, path: str, prefix: str, cls: str | None) -> None:
        for child in ast.iter_child_nodes(node):
            if isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef)):
                kernel = any(_decorator_name(d) in KERNEL_DECORATORS for d in child.decorator_list)
                out.append(Function(path, prefix + child.name, child.end_lineno - child.lineno + 1,
                                    _n_params(child, cls is not None), kernel,
                                    child.name == "__init__" and cls in components))
                visit(child, path, prefix + child.name + ".", None)
            elif isinstance(child, ast.ClassDef):
                visit(child, path, prefix + child.name + ".", child.name)
            else:
                visit(child, path, prefix, cls)

    for path, tree in trees.items():
        visit(tree, path, "", None)
    return out


FUNCTIONS = _functions()


def _problems(f: Function) -> list[str]:
    if f.kernel:
        return []
    out = []
    if f.lines > MAX_LINES:
        out.append(f"{f.lines} lines (at most {MAX_LINES})")
    if f.params > MAX_PARAMS and not f.constructor:
        out.append(f"{f.params} parameters (at most {MAX_PARAMS})")
    return out


def test_functions_are_short_and_take_few_parameters():
    bad = [f"{f.key}: {', '.join(p)}" for f in FUNCTIONS if (p := _problems(f)) and f.key not in EXCEPTIONS]
    assert not bad, ("split these into functions named for what they do, group parameters that travel "
                     "together, or list them in EXCEPTIONS with the reason:\n" + "\n".join(bad))


def test_every_exception_has_a_reason_and_is_still_needed():
    by_key = {f.key: f for f in FUNCTIONS}
    stale = []
    for key, reason in EXCEPTIONS.items():
        assert reason.strip(), f"{key}: give the reason on its line"
        if reason.startswith(TEMPORARY):
            continue  # its owner may have finished: the integrator prunes these
        if key not in by_key or not _problems(by_key[key]):
            stale.append(key)
    assert not stale, "these are within the limits now (or gone): remove them from EXCEPTIONS:\n" + "\n".join(stale)


@pytest.mark.parametrize("source, lines, params", [
    ("def f(a, b):\n    return a + b\n", 2, 2),
    ("class C:\n    def m(self, a, *args, k=1, **kw):\n        pass\n", 2, 4),
])
def test_the_measure_counts_what_it_says(source, lines, params):
    fn = next(n for n in ast.walk(ast.parse(source)) if isinstance(n, ast.FunctionDef))
    assert fn.end_lineno - fn.lineno + 1 == lines
    assert _n_params(fn, method=source.startswith("class")) == params


def test_the_rules_find_kernels_and_component_constructors():
    by_key = {f.key: f for f in FUNCTIONS}
    assert any(f.kernel for f in FUNCTIONS) and any(f.constructor for f in FUNCTIONS)
    assert by_key["core/astro/frame_kernels.py::synodic_to_gcrs_into"].kernel
    assert not by_key["core/propagation/compiled.py::CompiledDynamics.propagate"].kernel
    assert not any(f.constructor for f in FUNCTIONS if f.qualname.startswith("_Phase."))  # not a Component
