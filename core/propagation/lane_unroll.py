"""Unrolling of constant-range ``for`` loops in a right-hand side's syntax tree (for :mod:`.lane_rhs`).

``for i in range(a, b, c)`` whose bounds are integer literals or integer constants of the model's
module (numba freezes those at compile time too), with at most :data:`MAX_UNROLL` iterations, no
``break``/``continue``/``else`` and no assignment to ``i`` in its body, becomes one copy of the
body per iteration with ``i`` replaced by its value (and ``i`` left at its last value, as Python
does). Copies are the same statements in the same order, so the arithmetic is unchanged.
"""
from __future__ import annotations

import ast
import copy
import operator

__all__ = ["MAX_UNROLL", "Unroll", "const_int"]

MAX_UNROLL = 64
"""Most iterations of a constant-range ``for`` loop that is unrolled."""

_INT_OPS = {ast.Add: operator.add, ast.Sub: operator.sub, ast.Mult: operator.mul,
            ast.FloorDiv: operator.floordiv, ast.Mod: operator.mod}


def const_int(node: ast.AST, consts: dict[str, int]) -> int | None:
    """The value of an integer expression of literals and ``consts`` (+ - * // %), else None."""
    if isinstance(node, ast.Constant):
        v = node.value
        return v if isinstance(v, int) and not isinstance(v, bool) else None
    if isinstance(node, ast.Name) and isinstance(node.ctx, ast.Load):
        return consts.get(node.id)
    if isinstance(node, ast.UnaryOp) and isinstance(node.op, ast.USub):
        v = const_int(node.operand, consts)
        return None if v is None else -v
    if isinstance(node, ast.BinOp) and type(node.op) in _INT_OPS:
        a, b = const_int(node.left, consts), const_int(node.right, consts)
        if a is None or b is None or (isinstance(node.op, (ast.FloorDiv, ast.Mod)) and b == 0):
            return None
        return _INT_OPS[type(node.op)](a, b)
    return None


class _Substitute(ast.NodeTransformer):
    """Replace loads of one name by an integer constant."""

    def __init__(self, name: str, value: int) -> None:
        self.name, self.value = name, value

    def visit_Name(self, node: ast.Name):
        if node.id == self.name and isinstance(node.ctx, ast.Load):
            return ast.copy_location(ast.Constant(self.value), node)
        return node


class Unroll(ast.NodeTransformer):
    """Unroll ``for NAME in range(<constants>)`` loops (innermost first)."""

    def __init__(self, consts: dict[str, int]) -> None:
        self.consts = consts

    def _trip(self, node: ast.For) -> list[int] | None:
        it = node.iter
        if not (isinstance(node.target, ast.Name) and isinstance(it, ast.Call)
                and isinstance(it.func, ast.Name) and it.func.id == "range" and not it.keywords
                and 1 <= len(it.args) <= 3 and not node.orelse):
            return None
        args = [const_int(a, self.consts) for a in it.args]
        if any(a is None for a in args) or (len(args) == 3 and args[2] == 0):
            return None
        values = list(range(*args))
        if len(values) > MAX_UNROLL:
            return None
        for sub in ast.walk(ast.Module(body=node.body, type_ignores=[])):
            if isinstance(sub, (ast.Break, ast.Continue)):
                return None
            if isinstance(sub, ast.Name) and sub.id == node.target.id and not isinstance(sub.ctx, ast.Load):
                return None
        return values

    def visit_For(self, node: ast.For):
        node = self.generic_visit(node)
        values = self._trip(node)
        if values is None:
            return node
        name = node.target.id
        out: list[ast.stmt] = []
        for v in values:
            out += [_Substitute(name, v).visit(copy.deepcopy(s)) for s in node.body]
        if values:  # Python leaves the loop variable at its last value
            out.append(ast.Assign(targets=[ast.Name(id=name, ctx=ast.Store())], value=ast.Constant(values[-1])))
        return [ast.fix_missing_locations(ast.copy_location(s, node)) for s in out] or ast.Pass()


