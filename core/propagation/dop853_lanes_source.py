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

__all__ = ["lanes_source", "DEFAULT_LANES", "RESERVED"]

DEFAULT_LANES = 16
"""Particles per batch. Measured on an AMD EPYC (AVX-512), 9:2 NRHO at rtol 1e-10 / atol 1e-9:
8 lanes are not vectorised by LLVM (the constant 8-trip loop stays scalar: 14.6 us CPU per
particle-period, against 19.7 for the one-particle kernel), 16 lanes are (packed square roots and
divisions: 6.4 us), 32 lanes too (4.5 us, on a machine loaded enough that the two differ within
its noise). Fewer particles than lanes go to the one-particle kernel."""

RESERVED = {"np", "njit", "rhs", "body_position", "DIM", "CACHE", "SAFETY", "MAX_GROWTH", "MIN_SHRINK",
            "BETA", "EXPO1", "FASTMATH", "LANES", "ROWS", "N_STAGES"}
"""Module-level names of a generated kernel module other than the underscored ones."""


def _rows(dim: int) -> dict[str, int]:
    n = _tab.N_STAGES
    r = {"Y": 0, "K0": dim}
    r["KS"] = 2 * dim                      # stage s (1..12) at KS + (s - 1) * dim; stage 12 = f(t+h, ynew)
    r["YN"] = r["KS"] + n * dim
    r["T"] = r["YN"] + dim
    r["H"] = r["T"] + 1
    r["ERR"] = r["H"] + 1
    r["ROWS"] = r["ERR"] + 1
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


def _stage_function(s: int, body, dim: int, lanes: int) -> str:
    """Stage ``s`` (1..12): ytmp = y + h * sum(a_sm k_m), then k_s = rhs(t + c_s h, ytmp) per lane;
    ``s == 12`` is the new state (weights B, stored in YN) and its derivative (next step's k0)."""
    rows = _rows(dim)
    a = _tab.stage_matrix()
    new = s == _tab.N_STAGES
    coefs = _tab.B if new else a[s, :s]
    tnode = "" if new else f"{float(_tab.C[s])!r} * "
    L = ["@njit(cache=CACHE, fastmath=FASTMATH, error_model='numpy')",
         f"def _lanes_stage{s}(_w, _p):",
         "    for _l in range(LANES):",
         f"        _h = {_w(rows['H'], lanes)}"]
    for j in range(dim):
        L.append(f"        _y{j} = {_w(rows['Y'] + j, lanes)} + _h * ({_stage_sum(coefs, j, rows, dim, lanes)})")
        if new:
            L.append(f"        {_w(rows['YN'] + j, lanes)} = _y{j}")
    L.append(f"        _t = {_w(rows['T'], lanes)} + {tnode}_h")
    out0 = rows["KS"] + (s - 1) * dim
    text = body.render(lambda k: _w(out0 + k, lanes))
    L += ["        " + line for line in text.splitlines()]
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


_DRIVER = '''
@njit(cache=CACHE, fastmath=FASTMATH)
def _lanes_step(w, params, rtol, atol):
{STAGES}    _lanes_error(w, rtol, atol)


@njit(cache=CACHE, fastmath=FASTMATH)
def _lane_get(w, row, l, col):
    for j in range(DIM):
        col[j] = w[(row + j) * LANES + l]


@njit(cache=CACHE, fastmath=FASTMATH)
def _lane_put(w, row, l, col):
    for j in range(DIM):
        w[(row + j) * LANES + l] = col[j]


@njit(cache=CACHE, fastmath=FASTMATH)
def _lane_start(l, i, y0, params, t0, times, direction, rtol, atol, body_pos, body_rad, h_init,
                out, impact_body, impact_time, status, w, tl, hl, iout, nsteps, rejected,
                err_old, col, col2, col3, col4):
    """Load particle i into lane l; False if it needs no step (done at t0)."""
    nt = times.shape[0]
    for j in range(DIM):
        col[j] = y0[i, j]
    b = _inside(t0, col, params, body_pos, body_rad)
    if b >= 0:
        impact_body[i] = b
        impact_time[i] = t0
        status[i] = 1
        _freeze(i, 0, col, out, nt)
        return False
    io = 0
    while io < nt and times[io] == t0:
        for j in range(DIM):
            out[io, i, j] = col[j]
        io += 1
    if io == nt:
        return False
    rhs(t0, col, params, col2)
    _lane_put(w, ROW_Y, l, col)
    _lane_put(w, ROW_K0, l, col2)
    span = abs(times[nt - 1] - t0)
    if h_init > 0.0:
        hl[l] = min(h_init, span)
    else:
        hl[l] = _initial_step(t0, col, col2, direction, params, rtol, atol, col3, col4, span)
    tl[l] = t0
    iout[l] = io
    nsteps[l] = 0
    rejected[l] = False
    err_old[l] = 1e-4
    return True


@njit(cache=CACHE, nogil=True, fastmath=FASTMATH)
def propagate_lanes_kernel(i0, i1, y0, params, t0, times, rtol, atol, body_pos, body_rad,
                           max_steps, h_init, out, impact_body, impact_time, status):
    nt = times.shape[0]
    direction = 1.0
    if times[nt - 1] < t0:
        direction = -1.0
    hmin = 1e-14 * max(1.0, abs(t0), abs(times[nt - 1]))
    w = np.zeros(ROWS * LANES)
    tl = np.empty(LANES)
    hl = np.empty(LANES)
    hstep = np.empty(LANES)
    err_old = np.empty(LANES)
    last = np.zeros(LANES, dtype=np.bool_)
    rejected = np.zeros(LANES, dtype=np.bool_)
    iout = np.zeros(LANES, dtype=np.int64)
    nsteps = np.zeros(LANES, dtype=np.int64)
    who = np.full(LANES, -1, dtype=np.int64)
    col = np.empty(DIM)
    col2 = np.empty(DIM)
    col3 = np.empty(DIM)
    col4 = np.empty(DIM)
    nxt = i0
    active = 0
    for l in range(LANES):
        while nxt < i1:
            i = nxt
            nxt += 1
            if _lane_start(l, i, y0, params, t0, times, direction, rtol, atol, body_pos, body_rad,
                           h_init, out, impact_body, impact_time, status, w, tl, hl, iout,
                           nsteps, rejected, err_old, col, col2, col3, col4):
                who[l] = i
                active += 1
                break
    while active > 0:
        src = 0
        while who[src] < 0:
            src += 1
        for l in range(LANES):
            if who[l] < 0:  # idle: repeat an active lane (finite arithmetic, result discarded)
                tl[l] = tl[src]
                hl[l] = hl[src]
                iout[l] = iout[src]
                _lane_get(w, ROW_Y, src, col)
                _lane_put(w, ROW_Y, l, col)
                _lane_get(w, ROW_K0, src, col)
                _lane_put(w, ROW_K0, l, col)
        for l in range(LANES):
            tout = times[iout[l]]
            remaining = abs(tout - tl[l])
            hst = hl[l]
            lst = False
            if hst * 1.01 >= remaining:
                hst = remaining
                lst = True
            hstep[l] = hst
            last[l] = lst
            w[ROW_T * LANES + l] = tl[l]
            w[ROW_H * LANES + l] = direction * hst
        _lanes_step(w, params, rtol, atol)
        for l in range(LANES):
            i = who[l]
            if i < 0:
                continue
            nsteps[l] += 1
            e = w[ROW_ERR * LANES + l]
            hs = w[ROW_H * LANES + l]
            done = False
            if e <= 1.0:
                if e == 0.0:
                    fac = MAX_GROWTH
                else:
                    fac = min(MAX_GROWTH, SAFETY * e ** -EXPO1 * err_old[l] ** BETA)
                err_old[l] = max(e, 1e-4)
                if rejected[l]:
                    fac = min(1.0, fac)
                rejected[l] = False
                _lane_get(w, ROW_YN, l, col)
                b = _inside(tl[l] + hs, col, params, body_pos, body_rad)
                if b >= 0:
                    _lane_get(w, ROW_Y, l, col2)
                    _lane_get(w, ROW_K0, l, col3)
                    s = _locate_impact(tl[l], hs, col2, col3, params, col4, col, np.empty(DIM),
                                       body_pos, body_rad, b)
                    impact_body[i] = b
                    impact_time[i] = tl[l] + s * hs
                    status[i] = 1
                    _freeze(i, iout[l], col, out, nt)
                    done = True
                else:
                    tout = times[iout[l]]
                    if last[l]:
                        tl[l] = tout
                    else:
                        tl[l] = tl[l] + hs
                    _lane_put(w, ROW_Y, l, col)
                    _lane_get(w, ROW_F, l, col2)
                    _lane_put(w, ROW_K0, l, col2)
                    if last[l]:
                        io = iout[l]
                        while io < nt and times[io] == tout:
                            for j in range(DIM):
                                out[io, i, j] = col[j]
                            io += 1
                        iout[l] = io
                        hl[l] = max(hl[l], hstep[l] * fac)
                        if io >= nt:
                            done = True
                    else:
                        hl[l] = hstep[l] * fac
            else:
                if e > 0.0:
                    fac = max(MIN_SHRINK, SAFETY * e ** -EXPO1)
                else:
                    fac = 0.2
                hl[l] = hstep[l] * fac
                rejected[l] = True
                if hl[l] < hmin:
                    status[i] = 3
                    _lane_get(w, ROW_Y, l, col)
                    _freeze(i, iout[l], col, out, nt)
                    done = True
            if not done and nsteps[l] >= max_steps and iout[l] < nt:
                status[i] = 2
                _lane_get(w, ROW_Y, l, col)
                _freeze(i, iout[l], col, out, nt)
                done = True
            if done:
                who[l] = -1
                active -= 1
                while nxt < i1:
                    i = nxt
                    nxt += 1
                    if _lane_start(l, i, y0, params, t0, times, direction, rtol, atol, body_pos,
                                   body_rad, h_init, out, impact_body, impact_time, status, w,
                                   tl, hl, iout, nsteps, rejected, err_old, col, col2, col3, col4):
                        who[l] = i
                        active += 1
                        break
'''


def lanes_source(dim: int, body, lanes: int = DEFAULT_LANES) -> str:
    """Text appended to a generated kernel module (after :mod:`.dop853_source`'s, whose helpers
    ``_inside``, ``_locate_impact``, ``_initial_step`` and ``_freeze`` it reuses) for a right-hand
    side rewritten by :func:`.lane_rhs.lane_body`: the stage functions, ``_lanes_step`` and the
    entry point ``propagate_lanes_kernel``."""
    rows = _rows(dim)
    n = _tab.N_STAGES
    head = [f"\n\nLANES = {int(lanes)}", f"ROWS = {rows['ROWS']}", f"ROW_Y = {rows['Y']}",
            f"ROW_K0 = {rows['K0']}", f"ROW_F = {rows['KS'] + (n - 1) * dim}", f"ROW_YN = {rows['YN']}",
            f"ROW_T = {rows['T']}", f"ROW_H = {rows['H']}", f"ROW_ERR = {rows['ERR']}", "", ""]
    stages = "".join(_stage_function(s, body, dim, lanes) for s in range(1, n + 1))
    calls = "".join(f"    _lanes_stage{s}(w, params)\n" for s in range(1, n + 1))
    return "\n".join(head) + stages + _error_function(dim, lanes) + _DRIVER.replace("{STAGES}", calls)
