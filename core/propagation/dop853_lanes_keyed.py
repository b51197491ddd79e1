"""Stage functions of the SIMD-lockstep kernel for a right-hand side with a table key.

A right-hand side marked ``k: LaneUniform = ...`` (:mod:`.lane_rhs`) reads a table entry chosen by
time, such as the ephemeris model's 6-hour Chebyshev record. Its lanes are evaluated together
when they share the key, the key's loads (``_ucN = _p[...]``, :mod:`.lane_hoist`) done once for
all lanes:

- ``_lanes_keys`` computes every lane's key at every stage time once before the step's stages,
  and when all are equal the stages skip their own pass;
- the loads used in the lane loop are copied once per key into scratch rows of the work array,
  replicated across the lanes (``w[(SCRATCH + r) * LANES + l]``), and the lane loop reads them
  there like any other row (a hoisted load held in a vector register would be spilled to the
  stack at every stage call): refilled when the key changes (every few steps), not at every
  stage, by one ``_lanes_fill`` that the stages call;
- the passes for lanes in different records are ``_lanes_stage<s>_lanes``, called only when
  needed. They are not run once per record: each lane's column of the scratch rows holds its own
  record's loads (refilled for a lane when its record changes), so one lane loop serves them
  all; and ``_lanes_keys`` says for each stage whether its lanes share a record (a tight cloud
  propagated to one output keeps its lanes in step; many output times or a wide cloud do not).

Every lane computes the same operations on the same operands in the same order either way:
the results are bit for bit those of the one-particle kernel.
"""
from __future__ import annotations

import ast

from cistrack.propagation import dop853_tableau as _tab
from cistrack.propagation.dop853_lanes_rows import out_row, rows, stage_c, stage_point, stage_time, w_at

__all__ = ["scratch_plan", "keyed_stage_function", "keys_function", "fill_function"]

_HEAD = "@njit(cache=CACHE, fastmath=FASTMATH, error_model='numpy')"
_INLINE_HEAD = "@njit(inline='always', cache=CACHE, fastmath=FASTMATH, error_model='numpy')"
"""A keyed stage is inlined into ``_lanes_step`` like the plain stages (:mod:`.dop853_lanes_source`);
its per-lane variant, which the one-record case never enters, stays a function of its own."""


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
    functions' own expressions, so the same values); for each stage s, the step key rows hold
    1.0 and the key when all lanes have the same (stage s then uses it without a pass of its
    own), else 0.0 (stage s runs ``_lanes_stage<s>_lanes``). For a :class:`~.lane_rhs.LaneRecord`
    key, :func:`_one_key_exit` first."""
    r = rows(dim, keyed=True, lanes=lanes)
    step_key = r["STEP_KEY"] * lanes
    prefix = body.key.prefix.splitlines()
    stages = range(1, _tab.N_STAGES + 1)
    L = [_HEAD, "def _lanes_keys(_w, _p):"]
    L += ["    " + line for line in body.key.invariant.splitlines()]
    if body.key.monotonic:
        L += _one_key_exit(body, r, lanes)
    L += ["    _l = 0", f"    _h = {w_at(r['H'], lanes)}"]
    for s in stages:
        L += [f"    _t = {stage_time(s, r, lanes)}"] + ["    " + line for line in prefix]
        L += [f"    _K{s} = {body.key.expr}", f"    _nd{s} = 0"]
    L += ["    for _l in range(1, LANES):", f"        _h = {w_at(r['H'], lanes)}"]
    for s in stages:
        L += [f"        _t = {stage_time(s, r, lanes)}"] + ["        " + line for line in prefix]
        L += [f"        _nd{s} += ({body.key.expr}) != _K{s}"]
    for s in stages:
        L += [f"    _w[{step_key + 2 * s}] = 1.0 if _nd{s} == 0 else 0.0", f"    _w[{step_key + 2 * s + 1}] = _K{s}"]
    return "\n".join(L) + "\n\n\n"


def _one_key_exit(body, r: dict, lanes: int) -> list[str]:
    """Lines of ``_lanes_keys`` for a monotonic key: every lane's key at its earliest and its
    latest stage time; when they are all one key, every stage's flag is set and the function
    returns (two key evaluations per lane instead of twelve). Sound because the stage times t + c h, rounded, are monotonic in c for a given
    t and h, so each lies between the two, and so does a monotonic key of it."""
    stages = range(1, _tab.N_STAGES + 1)
    first, last = min(stages, key=stage_c), max(stages, key=stage_c)
    prefix = body.key.prefix.splitlines()
    step_key = r["STEP_KEY"] * lanes
    L = ["    _l = 0", f"    _h = {w_at(r['H'], lanes)}", f"    _t = {stage_time(first, r, lanes)}"]
    L += ["    " + line for line in prefix] + [f"    _K = {body.key.expr}", "    _nd = 0"]
    L += ["    for _l in range(LANES):", f"        _h = {w_at(r['H'], lanes)}"]
    for s in (first, last):
        L += [f"        _t = {stage_time(s, r, lanes)}"] + ["        " + line for line in prefix]
        L += [f"        _nd += ({body.key.expr}) != _K"]
    L += ["    if _nd == 0:"]
    for s in stages:
        L += [f"        _w[{step_key + 2 * s}] = 1.0", f"        _w[{step_key + 2 * s + 1}] = _K"]
    return L + ["        return"]


def fill_function(body, dim: int, lanes: int) -> str:
    """``_lanes_fill(_w, _p, _K, _lane)``: the per-key loads of key ``_K`` copied into the scratch
    rows' column of lane ``_lane``, or (``_lane`` < 0) of every lane that does not hold them yet,
    and the HELD rows set; the scratch key row says 1.0 and ``_K`` after a fill of every lane,
    0.0 after a fill of one. The loop over every lane has the constant trip count ``LANES``, and
    one lane is filled without a loop (bounds given at run time cost CPU). One function that every stage calls (when a key changed: every few steps), not a copy in
    each: the kernel compiles faster."""
    replicated, _ = scratch_plan(body)
    r = rows(dim, keyed=True, scratch=len(replicated), lanes=lanes)
    scratch_key = r["SCRATCH_KEY"] * lanes
    held, held_ok = w_at(r["HELD"], lanes), w_at(r["HELD_OK"], lanes)
    stores = [f"{w_at(r['SCRATCH'] + i, lanes)} = {name}" for i, name in enumerate(replicated)]
    stores += [f"{held} = _K", f"{held_ok} = 1.0"]
    L = [_HEAD, "def _lanes_fill(_w, _p, _K, _lane):"]
    L += ["    " + line for line in body.key.invariant.splitlines()]
    L += ["    " + line for line in body.key.per_key.splitlines()]
    L += ["    if _lane < 0:", "        for _l in range(LANES):", f"            if {held_ok} == 0.0 or {held} != _K:"]
    L += ["                " + line for line in stores]
    L += [f"        _w[{scratch_key}] = 1.0", f"        _w[{scratch_key + 1}] = _K", "        return", "    _l = _lane"]
    L += ["    " + line for line in stores] + [f"    _w[{scratch_key}] = 0.0"]
    return "\n".join(L) + "\n\n\n"


def keyed_stage_function(s: int, body, dim: int, lanes: int) -> str:
    """Stage ``s`` for a body with a :class:`~.lane_rhs.LaneUniform` key. Whether all lanes have
    the same key at the stage comes from ``_lanes_keys`` (stages 1-12) or, for stage 0, from a pass
    of its own. When they do (the lanes step together, and a 6-hour record holds several steps)
    one lane loop runs with the key, reading its loads from the scratch rows (filled first where
    they hold another key), and stores every lane's result; otherwise ``_lanes_stage{s}_lanes``
    runs the lane loop with each lane's own key and loads."""
    replicated, kept = scratch_plan(body)
    r = rows(dim, keyed=True, scratch=len(replicated), lanes=lanes)
    key = w_at(r["KEY"], lanes)
    L = [_INLINE_HEAD, f"def _lanes_stage{s}(_w, _p):"]
    L += ["    " + line for line in body.key.invariant.splitlines()]
    if s > 0:
        step_key = r["STEP_KEY"] * lanes + 2 * s
        L += [f"    if _w[{step_key}] == 0.0:", f"        _lanes_stage{s}_lanes(_w, _p)", "        return",
              f"    _K = _w[{step_key + 1}]"]
    else:
        L += ["    for _l in range(LANES):", f"        _t = {stage_time(0, r, lanes)}"]
        L += ["        " + line for line in body.key.prefix.splitlines()] + [f"        {key} = {body.key.expr}"]
        L += [f"    _K = _w[{r['KEY'] * lanes}]", "    for _l in range(1, LANES):", f"        if {key} != _K:",
              "            _lanes_stage0_lanes(_w, _p)", "            return"]
    scratch_key = r["SCRATCH_KEY"] * lanes
    L += [f"    if _w[{scratch_key}] == 0.0 or _w[{scratch_key + 1}] != _K:", "        _lanes_fill(_w, _p, _K, -1)"]
    L += ["    " + line for line in kept]
    loads = [f"{name} = {w_at(r['SCRATCH'] + i, lanes)}" for i, name in enumerate(replicated)]
    L += _lane_loop(s, body, r, dim, lanes, loads)
    return _lanes_function(s, body, r, dim, lanes) + "\n".join(L) + "\n\n\n"


def _lane_loop(s: int, body, r: dict, dim: int, lanes: int, loads: list[str]) -> list[str]:
    """The lane loop of stage ``s``, at indent 4: the stage point, ``loads`` (per-lane statements
    before the body), the previous outputs ``_uo0..``, the body, the outputs stored."""
    out0 = out_row(s, r, dim)
    L = ["    for _l in range(LANES):"] + stage_point(s, r, dim, lanes, "        ")
    L += ["        " + line for line in loads]
    L += [f"        _uo{k} = {w_at(out0 + k, lanes)}" for k in range(dim)]
    L += ["        " + line for line in body.render(lambda k: f"_uo{k}").splitlines()]
    return L + [f"        {w_at(out0 + k, lanes)} = _uo{k}" for k in range(dim)]


def _key_dependent(kept: list[str]) -> tuple[list[str], list[str]]:
    """``kept`` split in (statements that read ``_K``, directly or through an earlier one of them;
    the others), each in order."""
    tainted, inside, before = {"_K"}, [], []
    for line in kept:
        stmt = ast.parse(line).body[0]
        if _read(stmt) & tainted:
            inside.append(line)
            tainted |= {n.id for n in ast.walk(stmt) if isinstance(n, ast.Name) and isinstance(n.ctx, ast.Store)}
        else:
            before.append(line)
    return inside, before


def _lanes_function(s: int, body, r: dict, dim: int, lanes: int) -> str:
    """``_lanes_stage<s>_lanes``: lanes in different records (their keys set in the KEY row). Each
    lane's column of the scratch rows is refilled with its own key's loads where it holds
    another's, then one lane loop runs in which each lane reads its key and the per-key values
    from its own column: the same operations on the same operands as when all lanes share a key.
    (Before, one masked pass ran per distinct key, each as dear as the whole stage: the ephemeris
    model's step cost 141-150 ns per lane with its 32 lanes in two records and 254-269 in four,
    against 46-52 in one; now 63-64.) A function of its own, which the one-record case never
    enters."""
    replicated, kept = scratch_plan(body)
    key, held, held_ok = w_at(r["KEY"], lanes), w_at(r["HELD"], lanes), w_at(r["HELD_OK"], lanes)
    inside, before = _key_dependent(kept)
    time = ([f"_h = {w_at(r['H'], lanes)}"] if s > 0 else []) + [f"_t = {stage_time(s, r, lanes)}"]
    L = [_HEAD, f"def _lanes_stage{s}_lanes(_w, _p):"]
    L += ["    " + line for line in body.key.invariant.splitlines()]
    L += ["    _stale = 0", "    for _l in range(LANES):"] + ["        " + line for line in time]
    L += ["        " + line for line in body.key.prefix.splitlines()] + [f"        {key} = {body.key.expr}"]
    L += [f"        _stale += ({held_ok} == 0.0) + ({held} != {key})"]
    L += ["    if _stale:  # lanes whose column holds another key's loads (a scalar loop: it calls the fill)",
          "        for _l in range(LANES):", f"            if {held_ok} == 0.0 or {held} != {key}:",
          f"                _lanes_fill(_w, _p, {key}, _l)"]
    L += ["    " + line for line in before]
    loads = [f"_K = {key}"] + inside + [f"{name} = {w_at(r['SCRATCH'] + i, lanes)}" for i, name in enumerate(replicated)]
    L += _lane_loop(s, body, r, dim, lanes, loads)
    return "\n".join(L) + "\n\n\n"
