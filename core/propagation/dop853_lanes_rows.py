"""Layout of the SIMD-lockstep kernel's work array ``w`` and the stage formula's text.

Row ``r`` of lane ``l`` lives at ``w[r * LANES + l]`` (:mod:`.dop853_lanes_source`). Shared by the
generator of the plain stages (:mod:`.dop853_lanes_source`) and of the keyed ones
(:mod:`.dop853_lanes_keyed`).
"""
from __future__ import annotations

from cistrack.propagation import dop853_tableau as _tab

__all__ = ["rows", "w_at", "stage_sum", "stage_point", "stage_c", "stage_time", "out_row"]


def rows(dim: int, keyed: bool = False, scratch: int = 0, lanes: int | None = None) -> dict[str, int]:
    """First row of each block: Y, K0, KS (stage s, 1..12, at KS + (s - 1) * dim; stage 12 is
    f(t + h, ynew)), YN, T, H, ERR, and ROWS the row count. With ``keyed`` (a right-hand side with
    a :class:`~.lane_rhs.LaneUniform` key): KEY (each lane's key), HELD and HELD_OK (the key whose
    per-key loads each lane's column of the ``scratch`` rows from SCRATCH holds, and 1.0 where it
    holds one), STEP_KEY (slots 2 s and 2 s + 1, over as many rows of ``lanes`` slots as that
    takes: 1.0 when every lane has the same key at stage s of the step, and that key),
    SCRATCH_KEY (slot 0: 1.0 when every lane's column holds the key in slot 1)."""
    n = _tab.N_STAGES
    r = {"Y": 0, "K0": dim}
    r["KS"] = 2 * dim
    r["YN"] = r["KS"] + n * dim
    r["T"] = r["YN"] + dim
    r["H"] = r["T"] + 1
    r["ERR"] = r["H"] + 1
    r["ROWS"] = r["ERR"] + 1
    if keyed:
        if lanes is None:
            raise ValueError("rows: a keyed layout needs the lane count (its step key rows hold 26 slots)")
        r["KEY"] = r["ROWS"]
        r["HELD"] = r["KEY"] + 1
        r["HELD_OK"] = r["HELD"] + 1
        r["STEP_KEY"] = r["HELD_OK"] + 1
        r["SCRATCH_KEY"] = r["STEP_KEY"] + -(-2 * (n + 1) // int(lanes))
        r["SCRATCH"] = r["SCRATCH_KEY"] + 1
        r["ROWS"] = r["SCRATCH"] + int(scratch)
    return r


def w_at(row: int, lanes: int) -> str:
    """Text of row ``row`` of the current lane ``_l``."""
    return f"_w[{row * lanes} + _l]"


def stage_sum(coefs, j: int, r: dict, dim: int, lanes: int) -> str:
    """Text of sum(coefs[m] * k_m[j]) over the nonzero coefficients, in order."""
    terms = []
    for m, c in enumerate(coefs):
        if c == 0.0:
            continue
        row = r["K0"] + j if m == 0 else r["KS"] + (m - 1) * dim + j
        terms.append(f"{float(c)!r} * {w_at(row, lanes)}")
    return " + ".join(terms) if terms else "0.0"


def stage_point(s: int, r: dict, dim: int, lanes: int, indent: str) -> list[str]:
    """Lines of stage ``s`` that set the lane's ``_h``, stage state ``_y0..`` (stored in YN at
    stage 12) and stage time ``_t``; ``s == 0`` is the step's start (the lane's state and time)."""
    if s == 0:
        return ([f"{indent}_y{j} = {w_at(r['Y'] + j, lanes)}" for j in range(dim)]
                + [f"{indent}_t = {w_at(r['T'], lanes)}"])
    new = s == _tab.N_STAGES
    coefs = _tab.B if new else _tab.stage_matrix()[s, :s]
    L = [f"{indent}_h = {w_at(r['H'], lanes)}"]
    for j in range(dim):
        L.append(f"{indent}_y{j} = {w_at(r['Y'] + j, lanes)} + _h * ({stage_sum(coefs, j, r, dim, lanes)})")
        if new:
            L.append(f"{indent}{w_at(r['YN'] + j, lanes)} = _y{j}")
    L.append(f"{indent}_t = {stage_time(s, r, lanes)}")
    return L


def stage_c(s: int) -> float:
    """c_s of stage ``s`` (1..12): its time is t + c_s h; the last stage's is t + h (c = 1)."""
    return 1.0 if s == _tab.N_STAGES else float(_tab.C[s])


def stage_time(s: int, r: dict, lanes: int, h: str = "_h") -> str:
    """Text of stage ``s``'s time: t + c_s h (t + h at the last stage, t at stage 0)."""
    if s == 0:
        return w_at(r["T"], lanes)
    tnode = "" if s == _tab.N_STAGES else f"{stage_c(s)!r} * "
    return f"{w_at(r['T'], lanes)} + {tnode}{h}"


def out_row(s: int, r: dict, dim: int) -> int:
    """First row stage ``s`` writes: k_s's rows; stage 0 (the derivative at a lane's start) writes
    stage 1's rows, free between steps, from which the driver copies it to K0 for the lanes that
    need it (the others keep the k0 their last step left, evaluated at t + h, not at the rounded
    output time)."""
    return r["KS"] + (max(s, 1) - 1) * dim
