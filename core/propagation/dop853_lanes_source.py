"""Source generator of the SIMD-lockstep DOP853 ensemble integrator (issue 15).

``propagate_lanes_kernel`` takes the arguments of ``propagate_kernel`` (:mod:`.dop853_source`)
and gives its results bit for bit, but integrates ``LANES`` particles side by side (the idea of
heyoka's batch mode): every state, stage and trial vector of every lane lives in one flat work
array ``w`` (row ``r`` of lane ``l`` at ``w[r * LANES + l]``), and each stage is one loop over the
lanes whose body is the stage formula followed by the model's right-hand side rewritten into
straight-line lane code (:mod:`.lane_rhs`). With every access at a constant offset from one base,
LLVM vectorises those loops (packed adds, multiplies, divisions and square roots) without any
fast-math flag: lane ``l`` computes exactly the operations, in exactly the order, that the
one-particle kernel computes for its particle (no cross-lane arithmetic, no contraction into
fused multiply-adds), so results depend neither on the lane width nor on which particles share
a batch, nor on the thread count.

Each lane has its own time, step size, error control, output index and step count: the lanes
step together, a lane whose step is rejected retries with its smaller step, and a lane whose
particle has finished (last output time, impact, step limit, underflow) is refilled at once with
the next particle of ``i0:i1``. Step-size control, impact search and output are scalar code per
lane, run once per step against twelve vectorised right-hand-side evaluations. Idle lanes (fewer
particles left than lanes) repeat an active lane's state; their results are discarded.
"""
from __future__ import annotations

from cistrack.propagation import dop853_tableau as _tab
from cistrack.propagation.dop853_lanes_driver import driver_source

__all__ = ["lanes_source", "lanes_for", "DEFAULT_LANES", "KEYED_LANES", "RESERVED"]

DEFAULT_LANES = 16
"""Particles per batch. Measured on an AMD EPYC (AVX-512), 9:2 NRHO at rtol 1e-10 / atol 1e-9:
8 lanes are not vectorised by LLVM (the constant 8-trip loop stays scalar: 14.6 us CPU per
particle-period, against 19.7 for the one-particle kernel), 16 lanes are (packed square roots and
divisions: 6.4 us), 32 lanes too (4.5 us, on a machine loaded enough that the two differ within
its noise). Fewer particles than lanes go to the one-particle kernel."""

KEYED_LANES = 32
"""Particles per batch for a right-hand side with a :class:`~.lane_rhs.LaneUniform` key: each
keyed stage call computes every lane's record and loads the record's coefficients once for all
lanes, so a wider batch shares that work. Measured 2026-11-26 on the development AMD EPYC, one
thread, ephemeris model: 17.08 against 14.72 us per particle-period over one NRHO period
(10,000 particles), 0.99 against 0.80 us per particle for a 0.05 TU call; calls of 5-40
particles cost the same within 3 % (their time is the call's fixed cost), and so does the first
compilation (41 s either way). The CR3BP (no key) stays at :data:`DEFAULT_LANES`: 32 lanes made
Example 1's propagation 3-6 % slower."""


def lanes_for(body) -> int:
    """Particles per batch for a rewritten right-hand side ``body`` (:func:`.lane_rhs.lane_body`)."""
    return KEYED_LANES if body.key is not None else DEFAULT_LANES

RESERVED = {"np", "njit", "rhs", "body_position", "DIM", "CACHE", "SAFETY", "MAX_GROWTH", "MIN_SHRINK",
            "BETA", "EXPO1", "GROWTH_CAP_ERR", "FASTMATH", "LANES", "ROWS", "N_STAGES",
            "HALF_SQRT3", "GRID_STEP", "MAX_GRID", "GRID_SLACK"}
"""Module-level names of a generated kernel module other than the underscored ones."""


def _rows(dim: int, keyed: bool = False) -> dict[str, int]:
    n = _tab.N_STAGES
    r = {"Y": 0, "K0": dim}
    r["KS"] = 2 * dim                      # stage s (1..12) at KS + (s - 1) * dim; stage 12 = f(t+h, ynew)
    r["YN"] = r["KS"] + n * dim
    r["T"] = r["YN"] + dim
    r["H"] = r["T"] + 1
    r["ERR"] = r["H"] + 1
    r["ROWS"] = r["ERR"] + 1
    if keyed:  # a body with a LaneUniform key: each lane's key, and whether its lane is done
        r["KEY"] = r["ROWS"]
        r["DONE"] = r["KEY"] + 1
        r["ROWS"] = r["DONE"] + 1
    return r


def _w(row: int, lanes: int) -> str:
    return f"_w[{row * lanes} + _l]"


def _stage_sum(coefs, j: int, rows: dict, dim: int, lanes: int) -> str:
    terms = []
    for m, c in enumerate(coefs):
        if c == 0.0:
            continue
        row = rows["K0"] + j if m == 0 else rows["KS"] + (m - 1) * dim + j
        terms.append(f"{float(c)!r} * {_w(row, lanes)}")
    return " + ".join(terms) if terms else "0.0"


def _stage_point(s: int, rows: dict, dim: int, lanes: int, indent: str) -> list[str]:
    """Lines of stage ``s`` that set the lane's ``_h``, stage state ``_y0..`` (stored in YN at
    stage 12) and stage time ``_t``; ``s == 0`` is the step's start (the lane's state and time)."""
    if s == 0:
        return ([f"{indent}_y{j} = {_w(rows['Y'] + j, lanes)}" for j in range(dim)]
                + [f"{indent}_t = {_w(rows['T'], lanes)}"])
    new = s == _tab.N_STAGES
    coefs = _tab.B if new else _tab.stage_matrix()[s, :s]
    tnode = "" if new else f"{float(_tab.C[s])!r} * "
    L = [f"{indent}_h = {_w(rows['H'], lanes)}"]
    for j in range(dim):
        L.append(f"{indent}_y{j} = {_w(rows['Y'] + j, lanes)} + _h * ({_stage_sum(coefs, j, rows, dim, lanes)})")
        if new:
            L.append(f"{indent}{_w(rows['YN'] + j, lanes)} = _y{j}")
    L.append(f"{indent}_t = {_w(rows['T'], lanes)} + {tnode}_h")
    return L


def _out_row(s: int, rows: dict, dim: int) -> int:
    """First row stage ``s`` writes: k_s's rows; stage 0 (the derivative at a lane's start) writes
    stage 1's rows, free between steps, from which the driver copies it to K0 for the lanes that
    need it (the others keep the k0 their last step left, evaluated at t + h, not at the rounded
    output time)."""
    return rows["KS"] + (max(s, 1) - 1) * dim


def _stage_function(s: int, body, dim: int, lanes: int) -> str:
    """Stage ``s`` (1..12): ytmp = y + h * sum(a_sm k_m), then k_s = rhs(t + c_s h, ytmp) per lane;
    ``s == 12`` is the new state (weights B, stored in YN) and its derivative (next step's k0);
    ``s == 0`` is rhs(t, y) of every lane (see :func:`_out_row`)."""
    if body.key is not None:
        return _keyed_stage_function(s, body, dim, lanes)
    rows = _rows(dim)
    L = ["@njit(cache=CACHE, fastmath=FASTMATH, error_model='numpy')",
         f"def _lanes_stage{s}(_w, _p):",
         "    for _l in range(LANES):"] + _stage_point(s, rows, dim, lanes, "        ")
    out0 = _out_row(s, rows, dim)
    text = body.render(lambda k: _w(out0 + k, lanes))
    L += ["        " + line for line in text.splitlines()]
    return "\n".join(L) + "\n\n\n"


def _keyed_stage_function(s: int, body, dim: int, lanes: int) -> str:
    """Stage ``s`` for a body with a :class:`~.lane_rhs.LaneUniform` key: a scalar pass computes
    every lane's key; when all lanes have the same key (the usual case: the lanes step together,
    and a 6-hour record holds several steps) one lane loop runs with it and stores every lane's
    result; otherwise, once per distinct key ``_K``, the lane loop runs with the key fixed to
    ``_K`` (uniform loads: vectorised) and keeps the results of the lanes whose key is ``_K``.
    Each lane computes the same operations either way (same numbers)."""
    rows = _rows(dim, keyed=True)
    key, done = _w(rows["KEY"], lanes), _w(rows["DONE"], lanes)
    if s == 0:
        time = [f"        _t = {_w(rows['T'], lanes)}"]
    else:
        tnode = "" if s == _tab.N_STAGES else f"{float(_tab.C[s])!r} * "
        time = [f"        _h = {_w(rows['H'], lanes)}", f"        _t = {_w(rows['T'], lanes)} + {tnode}_h"]
    L = ["@njit(cache=CACHE, fastmath=FASTMATH, error_model='numpy')",
         f"def _lanes_stage{s}(_w, _p):"]
    L += ["    " + line for line in body.key.invariant.splitlines()]
    L += ["    for _l in range(LANES):"] + time
    L += ["        " + line for line in body.key.prefix.splitlines()]
    L += [f"        {key} = {body.key.expr}", f"        {done} = 0.0"]
    # every lane in the same record (nearly always: lanes step together): one pass, no masks
    out0 = _out_row(s, rows, dim)
    L += [f"    _K = _w[{rows['KEY'] * lanes}]", "    _same = True", "    for _l in range(1, LANES):",
          f"        if {key} != _K:", "            _same = False", "    if _same:"]
    L += ["        " + line for line in body.key.per_key.splitlines()]
    L += ["        for _l in range(LANES):"] + _stage_point(s, rows, dim, lanes, "            ")
    L += [f"            _uo{k} = {_w(out0 + k, lanes)}" for k in range(dim)]
    L += ["            " + line for line in body.render(lambda k: f"_uo{k}").splitlines()]
    L += [f"            {_w(out0 + k, lanes)} = _uo{k}" for k in range(dim)]
    L += ["        return", "    _first = 0", "    while _first < LANES:",
          f"        _K = _w[{rows['KEY'] * lanes} + _first]"]
    L += ["        " + line for line in body.key.per_key.splitlines()]
    L += ["        for _l in range(LANES):"] + _stage_point(s, rows, dim, lanes, "            ")
    L += [f"            _uo{k} = {_w(out0 + k, lanes)}" for k in range(dim)]
    L += ["            " + line for line in body.render(lambda k: f"_uo{k}").splitlines()]
    L.append(f"            _m = {key} == _K")
    L += [f"            {_w(out0 + k, lanes)} = _uo{k} if _m else {_w(out0 + k, lanes)}" for k in range(dim)]
    L += ["        for _l in range(LANES):", f"            if {key} == _K:", f"                {done} = 1.0",
          f"        while _first < LANES and _w[{rows['DONE'] * lanes} + _first] != 0.0:",
          "            _first += 1"]
    return "\n".join(L) + "\n\n\n"


def _error_function(dim: int, lanes: int) -> str:
    rows = _rows(dim)
    L = ["@njit(cache=CACHE, fastmath=FASTMATH, error_model='numpy')",
         "def _lanes_error(_w, rtol, atol):",
         "    for _l in range(LANES):",
         "        s5 = 0.0", "        s3 = 0.0"]
    for j in range(dim):
        L += [f"        isc = 1.0 / (atol + rtol * max(abs({_w(rows['Y'] + j, lanes)}), abs({_w(rows['YN'] + j, lanes)})))",
              f"        d5 = ({_stage_sum(_tab.E5, j, rows, dim, lanes)}) * isc",
              f"        d3 = ({_stage_sum(_tab.E3, j, rows, dim, lanes)}) * isc",
              "        s5 += d5 * d5",
              "        s3 += d3 * d3"]
    L += ["        if s5 == 0.0 and s3 == 0.0:",
          f"            {_w(rows['ERR'], lanes)} = 0.0",
          "        else:",
          f"            {_w(rows['ERR'], lanes)} = abs({_w(rows['H'], lanes)}) * s5 / np.sqrt((s5 + 0.01 * s3) * DIM)"]
    return "\n".join(L) + "\n\n\n"




def lanes_source(dim: int, body, lanes: int | None = None) -> str:
    """Text appended to a generated kernel module (after :mod:`.dop853_source`'s, whose helpers
    ``_inside``, ``_locate_impact``, ``_initial_step`` and ``_freeze`` it reuses) for a right-hand
    side rewritten by :func:`.lane_rhs.lane_body`: the stage functions, ``_lanes_step`` and the
    entry point ``propagate_lanes_kernel``; ``lanes`` particles per batch (default
    :func:`lanes_for` the body)."""
    lanes = lanes_for(body) if lanes is None else int(lanes)
    rows = _rows(dim, keyed=body.key is not None)
    n = _tab.N_STAGES
    head = [f"\n\nLANES = {int(lanes)}", f"ROWS = {rows['ROWS']}", f"ROW_Y = {rows['Y']}",
            f"ROW_K0 = {rows['K0']}", f"ROW_F = {rows['KS'] + (n - 1) * dim}", f"ROW_YN = {rows['YN']}",
            f"ROW_T = {rows['T']}", f"ROW_H = {rows['H']}", f"ROW_ERR = {rows['ERR']}",
            f"ROW_START_F = {_out_row(0, rows, dim)}", "", ""]
    stages = "".join(_stage_function(s, body, dim, lanes) for s in range(0, n + 1))
    calls = "".join(f"    _lanes_stage{s}(w, params)\n" for s in range(1, n + 1))
    return "\n".join(head) + stages + _error_function(dim, lanes) + driver_source(calls)
