"""The right-hand side of a model rewritten as straight-line code for one SIMD lane.

LLVM vectorises a loop over particles only if every memory access in it is an affine function of
the loop index that it can prove independent of the others; a loop that hands each particle's
state to the model's ``rhs(t, y, params, out)`` as an array view is not vectorised (LLVM's
remark: "unsafe indirect dependence"). :func:`lane_body` therefore rewrites the model's source:
``y[k]`` (``k`` an integer known when the kernel is generated) becomes a local scalar, ``out[k]``
a named slot of the lane kernels' work array, ``t`` the lane's stage time and ``params`` stays
the parameter array. The arithmetic itself is untouched (same expression trees in the same
order, so the same IEEE results as the one-particle kernel).

Ordinary Python in the body is accepted:

- ``for i in range(...)`` whose bounds are integer literals or integer constants of the model's
  module (which numba also freezes at compile time), up to :data:`MAX_UNROLL` iterations and
  without ``break``/``continue``/``else``, is unrolled: each copy of the body has ``i`` replaced
  by its value, so ``y[i]``, ``out[i + 3]`` become fixed slots and the lane loop stays a loop
  LLVM can vectorise;
- any other loop (``for _ in range(n)`` with ``n`` read from ``params``, ``while``) stays a loop
  inside the lane code (correct and bit-identical, but LLVM vectorises only innermost loops, so
  the lanes of such a model run side by side without SIMD);
- local names starting with ``_`` (``for _ in ...``) are renamed ``_u<name>`` so that they cannot
  collide with the generated kernel's own names.

A right-hand side it cannot rewrite (``y`` or ``out`` indexed by something not known at
generation time, or used other than indexed, passed to another function, a ``return`` with a
value or before the end, a name the generated module defines itself) gets ``None`` and a reason,
and is integrated by the one-particle kernels instead: every model keeps working.
"""
from __future__ import annotations

import ast
import inspect
import textwrap
from typing import Any

from cistrack.propagation.lane_hoist import hoist_invariants, invariant_expression
from cistrack.propagation.lane_unroll import MAX_UNROLL, Unroll, const_int

__all__ = ["LaneBody", "LaneKey", "LaneUniform", "LaneRecord", "lane_body", "MAX_UNROLL", "LANE_LOCALS"]

LANE_LOCALS = frozenset({"_l", "_h", "_t", "_p", "_w", "_m", "_K", "_first"})
"""Local names of the generated lane loops (with ``_yK``, ``_uo K`` and the ``_u`` renames)."""


class LaneUniform:
    """Annotation that marks a right-hand side's table index: ``k: LaneUniform = <int expression>``.

    The annotation changes nothing in the one-particle kernel (Python does not evaluate local
    annotations; numba sees a plain assignment). In the lockstep kernel, lanes whose ``k`` is
    equal are evaluated together with ``k`` a loop-invariant value, so loads indexed by it
    (``params[j]`` with ``j`` computed from ``k``) are the same address in every lane and LLVM
    vectorises the lane loop; per-lane loads at unrelated addresses (gathers) would keep it scalar.
    Requirements: one such statement, at the top level of the body, an integer value, and it and
    every statement before it read only ``t``, ``params`` and constants (not ``y``, not ``out``).
    """


class LaneRecord(LaneUniform):
    """A :class:`LaneUniform` index that is monotonic in ``t``: ``k: LaneRecord = <int expression>``.

    For a record index on a time grid, such as the ephemeris model's 6-hour record
    ``min(max(int(np.floor((t - start) / length)), 0), nrec - 1)``. The lockstep kernel then
    decides whether a batch's lanes share one record over a whole step from the first and the last
    of its stage times (every other stage time lies between them, and so does its index): two
    index evaluations per lane instead of twelve. An index that can go up and then down as ``t``
    grows (a periodic table, say) must use :class:`LaneUniform`: under this annotation its lanes
    would read the wrong entries at the stages between.
    """


class LaneKey:
    """The ``k: LaneUniform = expr`` statement of a body, in the rewritten names: ``name``, the
    statements before it that are the same in every lane (``invariant``: they read only constants,
    ``params`` at fixed indices and each other, and assign a name assigned nowhere else), the other
    statements before it (``prefix``), the ``expr`` text, ``per_key``: what the lane loop with
    the key fixed computes once before the loop (:func:`.lane_hoist.hoist_invariants`), and
    ``monotonic``: marked :class:`LaneRecord`."""

    def __init__(self, name: str, invariant: str, prefix: str, per_key: str, expr: str,
                 monotonic: bool = False) -> None:
        self.name, self.invariant, self.prefix, self.expr = name, invariant, prefix, expr
        self.per_key, self.monotonic = per_key, monotonic


class LaneBody:
    """A rewritten right-hand side.

    Attributes
    ----------
    text : str                 the body's lines, unindented, with ``_yK`` for y[K], ``_t`` for t,
                               ``_p`` for params and ``__OUT__[K]`` placeholders for out[K]
                               (with a key: the lane loop for one key value, without what
                               runs once before it: ``key.invariant`` and ``key.per_key``)
    free_names : set of str    global names the body reads (from the model's module or builtins)
    module : str               the module of the model's right-hand side
    key : LaneKey or None      the body's :class:`LaneUniform` statement, if any
    """

    def __init__(self, text: str, free_names: set[str], module: str, key: LaneKey | None = None) -> None:
        self.text, self.free_names, self.module, self.key = text, free_names, module, key

    def render(self, out_slot) -> str:
        """The body with ``out[K]`` replaced by ``out_slot(K)`` (a string expression)."""
        import re
        return re.sub(r"__OUT__\[(\d+)\]", lambda m: out_slot(int(m.group(1))), self.text)


class _Rewrite(ast.NodeTransformer):
    def __init__(self, t: str, y: str, p: str, out: str, consts: dict[str, int], renamed: dict[str, str]) -> None:
        self.t, self.y, self.p, self.out = t, y, p, out
        self.consts, self.renamed = consts, renamed
        self.problem: str | None = None
        self.locals: set[str] = set()
        self.loads: set[str] = set()

    def visit_Subscript(self, node: ast.Subscript):
        if isinstance(node.value, ast.Name) and node.value.id in (self.y, self.out):
            k = const_int(node.slice, self.consts)
            if k is None or k < 0:
                self.problem = (f"{node.value.id}[...] indexed with something other than a non-negative "
                                "integer literal or constant-range loop variable")
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
        name = self.renamed.get(node.id, node.id)
        if isinstance(node.ctx, ast.Store):
            self.locals.add(name)
        else:
            self.loads.add(name)
        return ast.copy_location(ast.Name(id=name, ctx=node.ctx), node)

    def visit_Return(self, node: ast.Return):
        self.problem = "a return statement inside the body"
        return node

    def generic_visit(self, node):
        if isinstance(node, (ast.FunctionDef, ast.Lambda, ast.ClassDef, ast.Global, ast.Nonlocal,
                             ast.Yield, ast.YieldFrom, ast.Await)):
            self.problem = f"a {type(node).__name__} inside the body"
            return node
        return super().generic_visit(node)


def _module_int_constants(func: Any, shadowed: set[str]) -> dict[str, int]:
    """Integer globals of the function's module (numba freezes them at compile time)."""
    glob = getattr(func, "__globals__", {})
    return {k: v for k, v in glob.items()
            if type(v) is int and k not in shadowed}


def lane_body(rhs: Any, reserved: set[str]) -> tuple[LaneBody | None, str]:
    """Rewrite the ``@njit`` right-hand side ``rhs(t, y, params, out)``; returns (body, "") or
    (None, why not). ``reserved``: names the generated module defines (a body that reads one of
    them is refused)."""
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
    stored = {n.id for s in body for n in ast.walk(s) if isinstance(n, ast.Name) and isinstance(n.ctx, ast.Store)}
    consts = _module_int_constants(func, stored | {t, y, p, out})
    unrolled: list[ast.stmt] = []
    for stmt in body:
        res = Unroll(consts).visit(stmt)
        unrolled += res if isinstance(res, list) else [res]
    stored |= {n.id for s in unrolled for n in ast.walk(s)
               if isinstance(n, ast.Name) and isinstance(n.ctx, ast.Store)}
    renamed = {n: f"_u{n}" for n in stored if n.startswith("_")}
    at, why, monotonic = _key_statement(unrolled, func)
    if why:
        return None, why
    rw = _Rewrite(t, y, p, out, consts, renamed)
    new = [rw.visit(stmt) for stmt in unrolled]
    if rw.problem:
        return None, rw.problem
    free = rw.loads - rw.locals - {"_t", "_p"} - {n for n in rw.loads if n.startswith("_y")}
    clash = sorted((free & (reserved - {"np"})) | {n for n in free if n in LANE_LOCALS
                                                      or n.startswith(("_y", "_u"))})
    if clash:
        return None, f"reads names the kernel module defines ({', '.join(clash)})"
    key = None
    if at is not None:
        head = new[:at + 1]
        if any(isinstance(n, ast.Name) and (n.id.startswith("_y") or n.id == "__OUT__")
               for s in head for n in ast.walk(s)):
            return None, "the LaneUniform statement or one before it reads the state or writes out"
        name = new[at].targets[0].id
        fixed, varying = _split_invariant(new[:at], new, free)
        per_key, new = hoist_invariants(varying + ast.parse(f"{name} = int(_K)").body + new[at + 1:],
                                        free | {"_p", "_K"} | {s.targets[0].id for s in fixed}, set(consts))
        key = LaneKey(name, *("\n".join(ast.unparse(s) for s in part) for part in (fixed, varying, per_key)),
                      ast.unparse(head[-1].value), monotonic=monotonic)
    text = "\n".join(ast.unparse(s) for s in new)
    return LaneBody(text, free, func.__module__, key), ""


def _split_invariant(prefix: list[ast.stmt], body: list[ast.stmt], free: set[str]):
    """(statements of ``prefix`` that are the same in every lane, the others), order kept."""
    counts: dict[str, int] = {}
    for s in body:
        for n in ast.walk(s):
            if isinstance(n, ast.Name) and isinstance(n.ctx, ast.Store):
                counts[n.id] = counts.get(n.id, 0) + 1
    known = (set(free) - {"_t"}) | {"_p"}
    fixed, varying = [], []
    for s in prefix:
        if (isinstance(s, ast.Assign) and len(s.targets) == 1 and isinstance(s.targets[0], ast.Name)
                and counts.get(s.targets[0].id) == 1 and invariant_expression(s.value, known)):
            fixed.append(s)
            known.add(s.targets[0].id)
        else:
            varying.append(s)
    return fixed, varying


def _key_statement(body: list[ast.stmt], func: Any) -> tuple[int | None, str, bool]:
    """(index of the top-level ``name: LaneUniform = expr`` (or :class:`LaneRecord`) in ``body``
    or None, problem or "", whether it is a LaneRecord); the annotated statement is turned into a
    plain assignment in place."""
    glob = getattr(func, "__globals__", {})

    def marked(node) -> bool:
        return (isinstance(node, ast.AnnAssign) and isinstance(node.annotation, ast.Name)
                and glob.get(node.annotation.id) in (LaneUniform, LaneRecord))

    found = [i for i, s in enumerate(body) if marked(s)]
    nested = sum(1 for s in body for n in ast.walk(s) if marked(n)) - len(found)
    if nested or len(found) > 1:
        return None, "LaneUniform must mark one statement at the top level of the body", False
    if not found:
        return None, "", False
    node = body[found[0]]
    if not isinstance(node.target, ast.Name) or node.value is None:
        return None, "LaneUniform must annotate an assignment to a plain name", False
    body[found[0]] = ast.copy_location(ast.Assign(targets=[node.target], value=node.value), node)
    return found[0], "", glob.get(node.annotation.id) is LaneRecord
