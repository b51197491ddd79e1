"""Lane-invariant code motion for the keyed lane loop of :mod:`.dop853_lanes_source`.

Inside the loop over lanes with a fixed :class:`~.lane_rhs.LaneUniform` key ``_K``, a statement
such as ``j = off + (k * 8 + 7) * 6`` or a load ``params[j + 1]`` has the same value in every lane.
LLVM would have to prove that such a load (at an address computed at run time) does not alias
the stores into the work array before it can vectorise the loop, and it does not; so these are
computed once before the loop instead, in order, each assignment under a fresh name
(``_uc0``, ``_uc1``, ...; single assignment, so a later reassignment of ``j`` cannot change what
an earlier use read). The remaining loop reads only the work array at lane-affine offsets and
these loop-invariant scalars: LLVM vectorises it. The operations and their operands are the same,
only evaluated earlier, so the results are bit-identical.

Only top-level assignments are moved, and only loads of ``params`` whose index is invariant are
taken out of top-level statements (never out of an ``if`` or a loop, where a load may be guarded).
"""
from __future__ import annotations

import ast

__all__ = ["hoist_invariants", "invariant_expression"]

_PURE_CALLS = {"int", "float", "abs", "min", "max"}


class _Names(ast.NodeTransformer):
    """Replace loads of renamed names by their current single-assignment name."""

    def __init__(self, current: dict[str, str]) -> None:
        self.current = current

    def visit_Name(self, node: ast.Name):
        if isinstance(node.ctx, ast.Load) and node.id in self.current:
            return ast.copy_location(ast.Name(id=self.current[node.id], ctx=ast.Load()), node)
        return node


def invariant_expression(node: ast.AST, known: set[str]) -> bool:
    """Whether ``node`` reads only ``known`` names and calls only pure functions (int, float, abs,
    min, max, ``np.*``): the same value in every lane."""
    for n in ast.walk(node):
        if isinstance(n, ast.Name) and n.id not in known and n.id not in _PURE_CALLS:
            return False
        if isinstance(n, ast.Call) and not (
                (isinstance(n.func, ast.Name) and n.func.id in _PURE_CALLS)
                or (isinstance(n.func, ast.Attribute) and isinstance(n.func.value, ast.Name)
                    and n.func.value.id == "np")):
            return False
        if isinstance(n, (ast.NamedExpr, ast.Await, ast.Yield, ast.Lambda)):
            return False
    return True


class _Loads(ast.NodeTransformer):
    """Take ``_p[<invariant>]`` loads out into fresh names (appended to ``hoisted``); a load at an
    index already taken out (same text: its names are single-assignment or never reassigned)
    reuses that name, so the loop reads each parameter once (the ephemeris model names GM_M and
    GM_S twice each)."""

    def __init__(self, known: set[str], hoisted: list[ast.stmt], fresh, seen: dict[str, str]) -> None:
        self.known, self.hoisted, self.fresh, self.seen = known, hoisted, fresh, seen

    def visit_Subscript(self, node: ast.Subscript):
        node = self.generic_visit(node)
        if (isinstance(node.value, ast.Name) and node.value.id == "_p" and isinstance(node.ctx, ast.Load)
                and invariant_expression(node.slice, self.known)):
            text = ast.unparse(node.slice)
            name = self.seen.get(text)
            if name is None:
                name = self.seen[text] = self.fresh()
                self.hoisted.append(ast.Assign(targets=[ast.Name(id=name, ctx=ast.Store())], value=node))
            return ast.copy_location(ast.Name(id=name, ctx=ast.Load()), node)
        return node


class _Tests(ast.NodeTransformer):
    """Inside compound statements: take ``_p[<constant>]`` loads and invariant ``if`` tests out into
    fresh names (a lane-invariant condition then branches the whole vector loop, instead of
    every lane computing both sides)."""

    def __init__(self, known: set[str], consts: set[str], hoisted: list[ast.stmt], fresh,
                 loads: dict[str, str]) -> None:
        self.known, self.consts, self.hoisted, self.fresh = known, consts, hoisted, fresh
        self.loads = loads  # shared with _Loads: one name per parameter index

    def _out(self, value: ast.expr, node: ast.AST) -> ast.Name:
        name = self.fresh()
        self.hoisted.append(ast.Assign(targets=[ast.Name(id=name, ctx=ast.Store())], value=value))
        self.known.add(name)
        return ast.copy_location(ast.Name(id=name, ctx=ast.Load()), node)

    def visit_Subscript(self, node: ast.Subscript):
        node = self.generic_visit(node)
        if (isinstance(node.value, ast.Name) and node.value.id == "_p" and isinstance(node.ctx, ast.Load)
                and invariant_expression(node.slice, self.consts)):
            text = ast.unparse(node.slice)
            if text not in self.loads:
                self.loads[text] = self._out(node, node).id
            return ast.copy_location(ast.Name(id=self.loads[text], ctx=ast.Load()), node)
        return node

    def visit_If(self, node: ast.If):
        node = self.generic_visit(node)
        if invariant_expression(node.test, self.known):
            node.test = self._out(node.test, node.test)
        return node


def _stored(node: ast.AST) -> set[str]:
    return {n.id for n in ast.walk(node) if isinstance(n, ast.Name) and isinstance(n.ctx, ast.Store)}


def hoist_invariants(body: list[ast.stmt], invariant: set[str],
                     constants: set[str]) -> tuple[list[ast.stmt], list[ast.stmt]]:
    """Split ``body`` (top-level statements of the lane loop) into (statements to run once before
    the loop, the loop's statements). ``invariant``: names with the same value in every lane
    (module globals, ``_p``, ``_K``, locals computed before the loop); ``constants``: the
    module's integer constants (``params`` loads at indices made of them and literals are taken
    out of ``if`` blocks too: a model's parameter vector holds every index its equations name)."""
    count = [0]

    def fresh() -> str:
        count[0] += 1
        return f"_uc{count[0] - 1}"

    current: dict[str, str] = {}
    seen: dict[str, str] = {}
    known = set(invariant)
    before: list[ast.stmt] = []
    loop: list[ast.stmt] = []
    for stmt in body:
        value = None
        if isinstance(stmt, ast.Assign) and len(stmt.targets) == 1 and isinstance(stmt.targets[0], ast.Name):
            target, value = stmt.targets[0].id, stmt.value
        elif isinstance(stmt, ast.AugAssign) and isinstance(stmt.target, ast.Name):
            target = stmt.target.id
            value = ast.BinOp(left=ast.Name(id=target, ctx=ast.Load()), op=stmt.op, right=stmt.value)
        if value is not None:
            value = _Names(current).visit(value)
            if invariant_expression(value, known):
                name = fresh()
                before.append(ast.Assign(targets=[ast.Name(id=name, ctx=ast.Store())], value=value))
                current[target] = name
                known.add(name)
                continue
            value = _Loads(known, before, fresh, seen).visit(value)
            current.pop(target, None)
            loop.append(ast.Assign(targets=[ast.Name(id=target, ctx=ast.Store())], value=value))
            continue
        assigned = _stored(stmt)
        for name in sorted(assigned & set(current)):  # materialise what the statement may reassign
            loop.append(ast.Assign(targets=[ast.Name(id=name, ctx=ast.Store())],
                                   value=ast.Name(id=current.pop(name), ctx=ast.Load())))
        loop.append(_Tests(known, constants, before, fresh, seen).visit(_Names(current).visit(stmt)))
    return ([ast.fix_missing_locations(s) for s in before], [ast.fix_missing_locations(s) for s in loop])
