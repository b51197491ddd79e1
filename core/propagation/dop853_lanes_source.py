"""Source generator of the SIMD-lockstep DOP853 ensemble integrator.

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
from cistrack.propagation.dop853_lanes_keyed import fill_function, keyed_stage_function, keys_function, scratch_plan
from cistrack.propagation.dop853_lanes_rows import out_row, rows, stage_point, stage_sum, w_at

__all__ = ["lanes_source", "lanes_for", "DEFAULT_LANES", "KEYED_LANES", "RESERVED"]

DEFAULT_LANES = 16
"""Particles per batch: the fewest that LLVM vectorises (a constant 8-trip loop stays scalar; 16
lanes give packed square roots and divisions). Fewer particles than lanes go to the one-particle
kernel (see :data:`~.compiled.LOCKSTEP_MIN_PARTICLES`)."""

KEYED_LANES = 32
"""Particles per batch for a right-hand side with a :class:`~.lane_rhs.LaneUniform` key: each
keyed stage call computes every lane's record and loads the record's coefficients once for all
lanes, so a wider batch shares that work; wider still (64) gains on large clouds but loses on
calls of few particles, whose idle lanes compute too (the UKF's sigma points). The CR3BP (no
key) stays at :data:`DEFAULT_LANES`, where 32 lanes are slower. Comparisons:
docs/history/propagation.md."""


def lanes_for(body) -> int:
    """Particles per batch for a rewritten right-hand side ``body`` (:func:`.lane_rhs.lane_body`)."""
    return KEYED_LANES if body.key is not None else DEFAULT_LANES

RESERVED = {"np", "njit", "rhs", "body_position", "DIM", "CACHE", "SAFETY", "MAX_GROWTH", "MIN_SHRINK",
            "BETA", "EXPO1", "GROWTH_CAP_ERR", "FASTMATH", "LANES", "ROWS", "N_STAGES",
            "HALF_SQRT3", "GRID_STEP", "MAX_GRID", "GRID_SLACK", "ROW_Y", "ROW_K0", "ROW_F", "ROW_YN",
            "ROW_T", "ROW_H", "ROW_ERR", "ROW_START_F", "ROW_KEY", "ROW_STEP_KEY", "ROW_SCRATCH_KEY",
            "ROW_SCRATCH", "borrowed_view", "propagate_kernel", "propagate_lanes_kernel", "derivatives_kernel", "dense_kernel"}
"""Module-level names of a generated kernel module other than the underscored ones."""


STAGE_HEAD = "@njit(inline='always', cache=CACHE, fastmath=FASTMATH, error_model='numpy')"
"""Decorator of the stage and error functions: inlined into ``_lanes_step`` by numba, so that the
step compiles as one function instead of fourteen (about a third less compile time of the
step, the same operations in the same order: the same numbers)."""


def _stage_function(s: int, body, dim: int, lanes: int) -> str:
    """Stage ``s`` (1..12): ytmp = y + h * sum(a_sm k_m), then k_s = rhs(t + c_s h, ytmp) per lane;
    ``s == 12`` is the new state (weights B, stored in YN) and its derivative (next step's k0);
    ``s == 0`` is rhs(t, y) of every lane (see :func:`.dop853_lanes_rows.out_row`)."""
    if body.key is not None:
        return keyed_stage_function(s, body, dim, lanes)
    r = rows(dim)
    L = [STAGE_HEAD,
         f"def _lanes_stage{s}(_w, _p):",
         "    for _l in range(LANES):"] + stage_point(s, r, dim, lanes, "        ")
    out0 = out_row(s, r, dim)
    text = body.render(lambda k: w_at(out0 + k, lanes))
    L += ["        " + line for line in text.splitlines()]
    return "\n".join(L) + "\n\n\n"


def _error_function(dim: int, lanes: int) -> str:
    r = rows(dim)
    L = [STAGE_HEAD,
         "def _lanes_error(_w, rtol, atol):",
         "    for _l in range(LANES):",
         "        s5 = 0.0", "        s3 = 0.0"]
    for j in range(dim):
        L += [f"        isc = 1.0 / (atol + rtol * max(abs({w_at(r['Y'] + j, lanes)}), abs({w_at(r['YN'] + j, lanes)})))",
              f"        d5 = ({stage_sum(_tab.E5, j, r, dim, lanes)}) * isc",
              f"        d3 = ({stage_sum(_tab.E3, j, r, dim, lanes)}) * isc",
              "        s5 += d5 * d5",
              "        s3 += d3 * d3"]
    L += ["        if s5 == 0.0 and s3 == 0.0:",
          f"            {w_at(r['ERR'], lanes)} = 0.0",
          "        else:",
          f"            {w_at(r['ERR'], lanes)} = abs({w_at(r['H'], lanes)}) * s5 / np.sqrt((s5 + 0.01 * s3) * DIM)"]
    return "\n".join(L) + "\n\n\n"


def lanes_source(dim: int, body, lanes: int | None = None) -> str:
    """Text appended to a generated kernel module (after :mod:`.dop853_source`'s, whose helpers
    ``_inside``, ``_locate_impact``, ``_initial_step`` and ``_freeze`` it reuses) for a right-hand
    side rewritten by :func:`.lane_rhs.lane_body`: the stage functions, ``_lanes_step`` and the
    entry point ``propagate_lanes_kernel``; ``lanes`` particles per batch (default
    :func:`lanes_for` the body)."""
    lanes = lanes_for(body) if lanes is None else int(lanes)
    keyed = body.key is not None
    r = rows(dim, keyed=keyed, scratch=len(scratch_plan(body)[0]) if keyed else 0, lanes=lanes)
    n = _tab.N_STAGES
    head = [f"\n\nLANES = {int(lanes)}", f"ROWS = {r['ROWS']}", f"ROW_Y = {r['Y']}",
            f"ROW_K0 = {r['K0']}", f"ROW_F = {r['KS'] + (n - 1) * dim}", f"ROW_YN = {r['YN']}",
            f"ROW_T = {r['T']}", f"ROW_H = {r['H']}", f"ROW_ERR = {r['ERR']}",
            f"ROW_START_F = {out_row(0, r, dim)}"]
    if keyed:
        head += [f"ROW_{name} = {r[name]}" for name in ("KEY", "STEP_KEY", "SCRATCH_KEY", "SCRATCH")]
    head += ["", ""]
    stages = "".join(_stage_function(s, body, dim, lanes) for s in range(0, n + 1))
    calls = "".join(f"    _lanes_stage{s}(w, params)\n" for s in range(1, n + 1))
    if keyed:
        stages = fill_function(body, dim, lanes) + stages + keys_function(body, dim, lanes)
        calls = "    _lanes_keys(w, params)\n" + calls
    return "\n".join(head) + stages + _error_function(dim, lanes) + driver_source(calls)
