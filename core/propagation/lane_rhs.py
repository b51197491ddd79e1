"""The right-hand side of a model rewritten as straight-line code for one SIMD lane.

LLVM vectorises a loop over particles only if every memory access in it is an affine function of
the loop index that it can prove independent of the others; a loop that hands each particle's
state to the model's ``rhs(t, y, params, out)`` as an array view is not vectorised (LLVM's
remark: "unsafe indirect dependence"). :func:`lane_body` therefore rewrites the model's source:
``y[k]`` (an integer literal ``k``) becomes a local scalar, ``out[k]`` a named slot of the lane
kernels' work array, ``t`` the lane's stage time and ``params`` stays the parameter array. The
arithmetic itself is untouched (same expression trees, so the same IEEE results as the
one-particle kernel).

A right-hand side it cannot rewrite (an index that is not an integer literal, ``y`` or ``out``
used other than indexed, passed to another function, a ``return`` with a value or before the end,
a name the generated module defines itself) gets ``None`` and a reason, and is integrated by the
one-particle kernels instead: every model keeps working, only straight-line ones go faster.
"""
from __future__ import annotations

import ast
import inspect
import textwrap
from typing import Any

__all__ = ["LaneBody", "lane_body"]


class LaneBody:
    """A rewritten right-hand side.

    Attributes
    ----------
    text : str                 the body's lines, unindented, with ``_yK`` for y[K], ``_t`` for t,
                               ``_p`` for params and ``__OUT__[K]`` placeholders for out[K]
    free_names : set of str    global names the body reads (from the model's module or builtins)
    module : str               the module of the model's right-hand side
    """

    def __init__(self, text: str, free_names: set[str], module: str) -> None:
        self.text, self.free_names, self.module = text, free_names, module

    def render(self, out_slot) -> str:
        """The body with ``out[K]`` replaced by ``out_slot(K)`` (a string expression)."""
        import re
        return re.sub(r"__OUT__\[(\d+)\]", lambda m: out_slot(int(m.group(1))), self.text)


class _Rewrite(ast.NodeTransformer):
    def __init__(self, t: str, y: str, p: str, out: str) -> None:
        self.t, self.y, self.p, self.out = t, y, p, out
        self.problem: str | None = None
        self.locals: set[str] = set()
        self.loads: set[str] = set()

    def _literal(self, node: ast.Subscript) -> int | None:
        sl = node.slice
        if isinstance(sl, ast.Constant) and isinstance(sl.value, int) and not isinstance(sl.value, bool) and sl.value >= 0:
            return sl.value
        return None

    def visit_Subscript(self, node: ast.Subscript):
        if isinstance(node.value, ast.Name) and node.value.id in (self.y, self.out):
            k = self._literal(node)
            if k is None:
                self.problem = f"{node.value.id}[...] indexed with something other than an integer literal"
                return node
            if node.value.id == self.y:
                if not isinstance(node.ctx, ast.Load):
                    self.problem = "the state argument is written to"
                return ast.copy_location(ast.Name(id=f"_y{k}", ctx=ast.Load()), node)
            return ast.copy_location(ast.Subscript(value=ast.Name(id="__OUT__", ctx=ast.Load()),
                                                   slice=ast.Constant(k), ctx=node.ctx), node)
        return self.generic_visit(node)

    def visit_Name(self, node: ast.Name):
        if node.id in (self.y, self.out):
            self.problem = f"'{node.id}' used other than indexed by an integer literal"
            return node
        if node.id == self.t:
            if not isinstance(node.ctx, ast.Load):
                self.problem = "the time argument is assigned"
            return ast.copy_location(ast.Name(id="_t", ctx=node.ctx), node)
        if node.id == self.p:
            if not isinstance(node.ctx, ast.Load):
                self.problem = "the parameter argument is assigned"
            return ast.copy_location(ast.Name(id="_p", ctx=node.ctx), node)
        if isinstance(node.ctx, ast.Store):
            self.locals.add(node.id)
        else:
            self.loads.add(node.id)
        return node

    def visit_Return(self, node: ast.Return):
        self.problem = "a return statement inside the body"
        return node

    def generic_visit(self, node):
        if isinstance(node, (ast.FunctionDef, ast.Lambda, ast.ClassDef, ast.Global, ast.Nonlocal,
                             ast.Yield, ast.YieldFrom, ast.Await)):
            self.problem = f"a {type(node).__name__} inside the body"
            return node
        return super().generic_visit(node)


def lane_body(rhs: Any, reserved: set[str]) -> tuple[LaneBody | None, str]:
    """Rewrite the ``@njit`` right-hand side ``rhs(t, y, params, out)``; returns (body, "") or
    (None, why not). ``reserved``: names the generated module defines (a body that reads one of
    them, or assigns a local starting with ``_``, is refused)."""
    func = getattr(rhs, "py_func", rhs)
    try:
        src = textwrap.dedent(inspect.getsource(func))
        tree = ast.parse(src)
    except (OSError, TypeError, SyntaxError) as exc:
        return None, f"source not readable ({exc})"
    fn = tree.body[0] if tree.body else None
    if not isinstance(fn, ast.FunctionDef):
        return None, "not a plain function definition"
    args = fn.args
    if (len(args.args) != 4 or args.vararg or args.kwarg or args.kwonlyargs or args.defaults
            or getattr(args, "posonlyargs", [])):
        return None, "the signature is not rhs(t, y, params, out)"
    t, y, p, out = (a.arg for a in args.args)
    body = list(fn.body)
    if body and isinstance(body[0], ast.Expr) and isinstance(getattr(body[0], "value", None), ast.Constant) \
            and isinstance(body[0].value.value, str):
        body = body[1:]  # docstring
    if body and isinstance(body[-1], ast.Return) and body[-1].value is None:
        body = body[:-1]
    rw = _Rewrite(t, y, p, out)
    new = [rw.visit(stmt) for stmt in body]
    if rw.problem:
        return None, rw.problem
    bad = sorted(n for n in rw.locals if n.startswith("_"))
    if bad:
        return None, f"local names starting with '_' ({', '.join(bad)})"
    free = rw.loads - rw.locals - {"_t", "_p"} - {n for n in rw.loads if n.startswith("_y")}
    clash = sorted((free & (reserved - {"np"})) | {n for n in free if n in ("_l", "_h", "_t", "_p", "_w")
                                                      or n.startswith("_y")})
    if clash:
        return None, f"reads names the kernel module defines ({', '.join(clash)})"
    text = "\n".join(ast.unparse(s) for s in new)
    return LaneBody(text, free, func.__module__), ""
