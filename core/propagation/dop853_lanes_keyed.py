"""Stage functions of the SIMD-lockstep kernel for a right-hand side with a table key.

A right-hand side marked ``k: LaneUniform = ...`` (:mod:`.lane_rhs`) reads a table entry chosen by
time, such as the ephemeris model's 6-hour Chebyshev record. Its lanes are evaluated together
when they share the key, the key's loads (``_ucN = _p[...]``, :mod:`.lane_hoist`) done once for
all lanes. Three things made that fixed work cost about a quarter of the ephemeris model's stage
on AVX-512 (69 against 50 ns per lane-step, ``benchmarks/bench_stage_cost.py``, session 18):

- each stage computed every lane's key, stored it, and read one back to address its loads;
  ``_lanes_keys`` now computes every lane's key at every stage time once before the step's
  stages, and when all are equal the stages skip their own pass;
- LLVM broadcast each hoisted load to a full vector register and, with some fifty of them and
  32 registers, spilled them all to the stack at every stage call. The loads used in the lane
  loop are now copied once per key into scratch rows of the work array, replicated across the
  lanes (``w[(SCRATCH + r) * LANES + l]``), and the lane loop reads them there like any other
  row: refilled when the key changes (every few steps), not at every stage, by one
  ``_lanes_fill`` that the stages call (a copy in each cost 6 s of first compilation);
- the per-key passes for lanes in different records sat in the stage function and slowed the
  common case by 3-8 %: they are ``_lanes_stage<s>_masked`` now, called only when needed.

Every lane computes the same operations on the same operands in the same order either way:
the results are bit for bit those of the one-particle kernel.
"""
from __future__ import annotations

import ast

from cistrack.propagation import dop853_tableau as _tab
from cistrack.propagation.dop853_lanes_rows import out_row, rows, stage_point, stage_time, w_at

__all__ = ["scratch_plan", "keyed_stage_function", "keys_function", "fill_function"]

_HEAD = "@njit(cache=CACHE, fastmath=FASTMATH, error_model='numpy')"


def _target_and_value(stmt: ast.stmt) -> tuple[str, ast.expr] | None:
    if isinstance(stmt, ast.Assign) and len(stmt.targets) == 1 and isinstance(stmt.targets[0], ast.Name):
        return stmt.targets[0].id, stmt.value
    return None


def _is_load(value: ast.expr) -> bool:
    return isinstance(value, ast.Subscript) and isinstance(value.value, ast.Name) and value.value.id == "_p"


def _read(node: ast.AST) -> set[str]:
    return {n.id for n in ast.walk(node) if isinstance(n, ast.Name) and isinstance(n.ctx, ast.Load)}


def scratch_plan(body) -> tuple[list[str], list[str]]:
    """(names of the per-key loads the lane loop reads, which go to scratch rows; the per-key
    statements still run before the loop when the scratch rows are valid): the index arithmetic
    and the loads and tests that other statements before the loop need (a lane-invariant test
    stays a branch around the vectorised loop)."""
    stmts = ast.parse(body.key.per_key).body
    in_loop = _read(ast.parse(body.render(lambda k: f"_uo{k}")))
    loads = [tv[0] for tv in map(_target_and_value, stmts) if tv is not None and _is_load(tv[1])]
    replicated = [name for name in loads if name in in_loop]
    needed: set[str] = set()
    kept: list[ast.stmt] = []
    for stmt in reversed(stmts):
        tv = _target_and_value(stmt)
        if tv is not None and tv[0] in replicated and tv[0] not in needed:
            continue
        kept.append(stmt)
        needed |= _read(stmt)
    return replicated, [ast.unparse(stmt) for stmt in reversed(kept)]


def keys_function(body, dim: int, lanes: int) -> str:
    """``_lanes_keys``: before a step's stages, every lane's key at every stage time (the stage
    functions' own expressions, so the same values); when all are equal, the step's key row holds
    1.0 and the key, and stages 1-12 use it without a pass of their own."""
    r = rows(dim, keyed=True)
    key = w_at(r["KEY"], lanes)
    step_key = r["STEP_KEY"] * lanes
    prefix = body.key.prefix.splitlines()
    L = [_HEAD, "def _lanes_keys(_w, _p):"]
    L += ["    " + line for line in body.key.invariant.splitlines()]
    L += ["    for _l in range(LANES):", f"        _t = {stage_time(1, r, lanes, w_at(r['H'], lanes))}"]
    L += ["        " + line for line in prefix] + [f"        {key} = {body.key.expr}"]
    L += [f"    _K = _w[{r['KEY'] * lanes}]", "    _nd = 0", "    for _l in range(LANES):",
          f"        _h = {w_at(r['H'], lanes)}", f"        _nd += {key} != _K"]
    for s in range(2, _tab.N_STAGES + 1):
        L += [f"        _t = {stage_time(s, r, lanes)}"] + ["        " + line for line in prefix]
        L += [f"        _nd += ({body.key.expr}) != _K"]
    L += [f"    _w[{step_key}] = 1.0 if _nd == 0 else 0.0", f"    _w[{step_key + 1}] = _K"]
    return "\n".join(L) + "\n\n\n"


def fill_function(body, dim: int, lanes: int) -> str:
    """``_lanes_fill(_w, _p, _K)``: the per-key loads of key ``_K`` copied into the scratch rows,
    each across the lanes, and the scratch key row set. One function that every stage calls (when
    the key changed: every few steps), not a copy in each: the kernel compiles faster."""
    replicated, _ = scratch_plan(body)
    r = rows(dim, keyed=True, scratch=len(replicated))
    scratch_key = r["SCRATCH_KEY"] * lanes
    L = [_HEAD, "def _lanes_fill(_w, _p, _K):"]
    L += ["    " + line for line in body.key.invariant.splitlines()]
    L += ["    " + line for line in body.key.per_key.splitlines()]
    if replicated:
        L += ["    for _l in range(LANES):"]
        L += [f"        {w_at(r['SCRATCH'] + i, lanes)} = {name}" for i, name in enumerate(replicated)]
    L += [f"    _w[{scratch_key}] = 1.0", f"    _w[{scratch_key + 1}] = _K"]
    return "\n".join(L) + "\n\n\n"


def keyed_stage_function(s: int, body, dim: int, lanes: int) -> str:
    """Stage ``s`` for a body with a :class:`~.lane_rhs.LaneUniform` key. The lanes' keys come
    from ``_lanes_keys`` when the whole step has one (stages 1-12), else from a pass of the
    stage's own. When all lanes have the same key (the usual case: the lanes step together, and a
    6-hour record holds several steps) one lane loop runs with it, reading the key's loads from
    the scratch rows (filled first if they hold another key), and stores every lane's result;
    otherwise ``_lanes_stage{s}_masked`` runs, once per distinct key ``_K``, the lane loop with
    the key fixed to ``_K`` and its loads hoisted before the loop, and keeps the results of the
    lanes whose key is ``_K``."""
    replicated, kept = scratch_plan(body)
    r = rows(dim, keyed=True, scratch=len(replicated))
    key, done = w_at(r["KEY"], lanes), w_at(r["DONE"], lanes)
    time = ([f"_h = {w_at(r['H'], lanes)}"] if s > 0 else []) + [f"_t = {stage_time(s, r, lanes)}"]
    L = [_HEAD, f"def _lanes_stage{s}(_w, _p):"]
    L += ["    " + line for line in body.key.invariant.splitlines()]
    ind = "    "
    if s > 0:
        step_key = r["STEP_KEY"] * lanes
        L += [f"    if _w[{step_key}] != 0.0:", f"        _K = _w[{step_key + 1}]", "        _same = True",
              "    else:"]
        ind = "        "
    L += [ind + "for _l in range(LANES):"] + [ind + "    " + line for line in time]
    L += [ind + "    " + line for line in body.key.prefix.splitlines()]
    L += [f"{ind}    {key} = {body.key.expr}", f"{ind}    {done} = 0.0"]
    L += [f"{ind}_K = _w[{r['KEY'] * lanes}]", f"{ind}_same = True", f"{ind}for _l in range(1, LANES):",
          f"{ind}    if {key} != _K:", f"{ind}        _same = False"]
    scratch_key = r["SCRATCH_KEY"] * lanes
    L += ["    if _same:", f"        if _w[{scratch_key}] == 0.0 or _w[{scratch_key + 1}] != _K:",
          "            _lanes_fill(_w, _p, _K)"]
    L += ["        " + line for line in kept]
    loads = [f"{name} = {w_at(r['SCRATCH'] + i, lanes)}" for i, name in enumerate(replicated)]
    L += _lane_loop(s, body, r, dim, lanes, loads)
    out0 = out_row(s, r, dim)
    L += [f"            {w_at(out0 + k, lanes)} = _uo{k}" for k in range(dim)]
    L += ["        return", f"    _lanes_stage{s}_masked(_w, _p)"]
    return _masked_function(s, body, r, dim, lanes) + "\n".join(L) + "\n\n\n"


def _lane_loop(s: int, body, r: dict, dim: int, lanes: int, loads: list[str]) -> list[str]:
    """The lane loop of stage ``s`` up to its outputs ``_uo0..``, at indent 8: the stage point,
    ``loads`` (per-lane statements before the body), the previous outputs, the body."""
    out0 = out_row(s, r, dim)
    L = ["        for _l in range(LANES):"] + stage_point(s, r, dim, lanes, "            ")
    L += ["            " + line for line in loads]
    L += [f"            _uo{k} = {w_at(out0 + k, lanes)}" for k in range(dim)]
    return L + ["            " + line for line in body.render(lambda k: f"_uo{k}").splitlines()]


def _masked_function(s: int, body, r: dict, dim: int, lanes: int) -> str:
    """``_lanes_stage<s>_masked``: lanes in different records, once per distinct key ``_K`` the
    lane loop with the key's loads hoisted before it, keeping the results of the lanes whose key
    is ``_K``. A function of its own, which the one-record case never enters (in the stage
    function its code made that case 3-8 % slower, ``bench_stage_cost.py``)."""
    key, done = w_at(r["KEY"], lanes), w_at(r["DONE"], lanes)
    out0 = out_row(s, r, dim)
    L = [_HEAD, f"def _lanes_stage{s}_masked(_w, _p):"]
    L += ["    " + line for line in body.key.invariant.splitlines()]
    L += ["    _first = 0", "    while _first < LANES:", f"        _K = _w[{r['KEY'] * lanes} + _first]"]
    L += ["        " + line for line in body.key.per_key.splitlines()]
    L += _lane_loop(s, body, r, dim, lanes, [])
    L.append(f"            _m = {key} == _K")
    L += [f"            {w_at(out0 + k, lanes)} = _uo{k} if _m else {w_at(out0 + k, lanes)}" for k in range(dim)]
    L += ["        for _l in range(LANES):", f"            if {key} == _K:", f"                {done} = 1.0",
          f"        while _first < LANES and _w[{r['DONE'] * lanes} + _first] != 0.0:",
          "            _first += 1"]
    return "\n".join(L) + "\n\n\n"
