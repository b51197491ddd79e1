"""Template of the SIMD-lockstep kernel's driver: ``propagate_lanes_kernel`` and its helpers.

Part of the module text that :mod:`.dop853_lanes_source` generates (:func:`driver_source` fills
``{STAGES}`` with the calls of the stage functions and ``{START:n}`` with the lane-loading block
at indent n): the per-lane scalar code that loads particles into lanes, controls each lane's step
size, locates impacts, writes outputs and refills finished lanes, around one vectorised
``_lanes_step`` per step of all lanes. See :mod:`.dop853_lanes_source`.
"""

__all__ = ["DRIVER", "driver_source"]

# Loading particle i into lane l (sets ``started``: False when it needs no step, done at t0).
# Written out where it is used, like the copies between a lane's rows below: a helper function
# taking the kernel's arrays has numba count references to each of them on every call
# (docs/history/propagation-code.md).
_START = """started = False
for j in range(DIM):
    col[j] = y0[i, j]
b = _inside(t0, col, params, body_pos, body_rad)
if b >= 0:
    impact_body[i] = b
    impact_time[i] = t0
    status[i] = 1
    _freeze(i, 0, col, out, nt)
else:
    io = 0
    while io < nt and times[io] == t0:
        for j in range(DIM):
            out[io, i, j] = col[j]
        io += 1
    if io < nt:
        for j in range(DIM):
            w[(ROW_Y + j) * LANES + l] = col[j]
        span = abs(times[nt - 1] - t0)
        if steps[i] > 0.0:  # the step this particle's previous integration proposed
            hl[l] = min(steps[i], span)
            # k0 = rhs(t0, y): evaluated for all such lanes at once before the next step
            w[ROW_T * LANES + l] = t0
            pending[l] = True
            npending += 1
        else:
            rhs(t0, col, params, col2)
            for j in range(DIM):
                w[(ROW_K0 + j) * LANES + l] = col2[j]
            hl[l] = _initial_step(t0, col, col2, direction, params, rtol, atol, col3, col4, span)
        tl[l] = t0
        iout[l] = io
        nsteps[l] = 0
        rejected[l] = False
        err_old[l] = 1e-4
        started = True
"""

# Whether the lane's new position ``col`` lies inside body ``bb`` at (bx, by, bz): then ``b = bb``
# and the loop over the bodies ends. Written out in both loops over the bodies (see _START).
_HIT = """dx = col[0] - bx
dy = col[1] - by
dz = col[2] - bz
if dx * dx + dy * dy + dz * dz < body_rad[bb] * body_rad[bb]:
    b = bb
    break
"""

_TEMPLATE = '''
from cistrack.propagation.borrowed_view import borrowed_view

GRID_STEP = 0.005  # TU between the moving bodies' grid times (fewer than MAX_GRID of them)
MAX_GRID = 4096
HALF_SQRT3 = 0.8660254037844387
GRID_SLACK = 1e-9  # LU (0.4 mm)

@njit(cache=CACHE, fastmath=FASTMATH, error_model='numpy')
def _lanes_step(w, params, rtol, atol):
{STAGES}    _lanes_error(w, rtol, atol)


@njit(cache=CACHE, nogil=True, fastmath=FASTMATH)
def propagate_lanes_kernel(i0, i1, y0, params, t0, times, rtol, atol, body_pos, body_rad,
                           max_steps, steps, out, impact_body, impact_time, status):
    nt = times.shape[0]
    direction = 1.0
    if times[nt - 1] < t0:
        direction = -1.0
    hmin = 1e-14 * max(1.0, abs(t0), abs(times[nt - 1]))
    w = np.zeros(ROWS * LANES)
    # the stage functions get views without reference counts (w and params outlive them)
    wv = borrowed_view(w)
    pv = borrowed_view(params)
    tl = np.empty(LANES)
    hl = np.empty(LANES)
    hstep = np.empty(LANES)
    err_old = np.empty(LANES)
    last = np.zeros(LANES, dtype=np.bool_)
    rejected = np.zeros(LANES, dtype=np.bool_)
    pending = np.zeros(LANES, dtype=np.bool_)
    npending = 0
    iout = np.zeros(LANES, dtype=np.int64)
    nsteps = np.zeros(LANES, dtype=np.int64)
    who = np.full(LANES, -1, dtype=np.int64)
    nb = body_rad.shape[0]
    speed = np.full(max(nb, 1), np.inf)  # bound on each body's speed, LU/TU
    accel = np.full(max(nb, 1), np.inf)  # and on its acceleration, LU/TU^2
    for bb in range(nb):
        if body_pos.shape[1] > 3 and body_pos[bb, 3] >= 0.0:  # NaN or negative: unknown
            speed[bb] = body_pos[bb, 3]
        if body_pos.shape[1] > 4 and body_pos[bb, 4] >= 0.0:
            accel[bb] = body_pos[bb, 4]
    anymoving = False
    for bb in range(nb):
        anymoving = anymoving or speed[bb] != 0.0
    # A body at rest (speed 0) is evaluated once. A moving body with a speed bound V or an
    # acceleration bound A is evaluated at ngrid times from t0 to the last output, dgrid apart:
    # between two of them it is within off[bb] (LU) of the straight line joining them, off =
    # min(V dgrid / 2, sqrt(3) A dgrid^2 / 8) (the chord's error; Lagrange's remainder per axis)
    # plus GRID_SLACK for rounding and the seams of a piecewise ephemeris. inf: no bound.
    rest = np.zeros((max(nb, 1), 3))
    off = np.full(max(nb, 1), np.inf)
    ngrid = int(min(MAX_GRID - 2.0, abs(times[nt - 1] - t0) / GRID_STEP)) + 2
    dgrid = abs(times[nt - 1] - t0) / (ngrid - 1)
    gridded = False
    for bb in range(nb):
        if speed[bb] == 0.0:
            rest[bb, 0], rest[bb, 1], rest[bb, 2] = body_position(t0, params, bb, body_pos)
        elif dgrid > 0.0:
            e = min(0.5 * speed[bb] * dgrid, HALF_SQRT3 * 0.25 * accel[bb] * dgrid * dgrid)
            if e < np.inf:  # False for NaN too
                off[bb] = e + GRID_SLACK
                gridded = True
    grid = np.empty((max(nb, 1), ngrid if gridded else 1, 3))
    for bb in range(nb):
        if off[bb] < np.inf:
            for kg in range(ngrid):
                grid[bb, kg, 0], grid[bb, kg, 1], grid[bb, kg, 2] = body_position(
                    t0 + direction * (kg * dgrid), params, bb, body_pos)
    inv_dgrid = 1.0 / dgrid if dgrid > 0.0 else 0.0
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
{START:12}
            if started:
                who[l] = i
                active += 1
                break
    while active > 0:
        if npending > 0:  # started lanes' k0, vectorised (the same numbers as rhs per lane)
            _lanes_stage0(wv, pv)
            for l in range(LANES):
                if pending[l]:
                    for j in range(DIM):
                        w[(ROW_K0 + j) * LANES + l] = w[(ROW_START_F + j) * LANES + l]
                    pending[l] = False
            npending = 0
        src = 0
        while who[src] < 0:
            src += 1
        for l in range(LANES):
            if who[l] < 0:  # idle: repeat an active lane (finite arithmetic, result discarded)
                tl[l] = tl[src]
                hl[l] = hl[src]
                iout[l] = iout[src]
                for j in range(DIM):
                    w[(ROW_Y + j) * LANES + l] = w[(ROW_Y + j) * LANES + src]
                    w[(ROW_K0 + j) * LANES + l] = w[(ROW_K0 + j) * LANES + src]
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
        _lanes_step(wv, pv, rtol, atol)
        for l in range(LANES):
            i = who[l]
            if i < 0:
                continue
            nsteps[l] += 1
            e = w[ROW_ERR * LANES + l]
            hs = w[ROW_H * LANES + l]
            done = False
            if e <= 1.0:
                if e == 0.0 or e <= GROWTH_CAP_ERR:  # growth capped whatever the factor rounds to
                    fac = MAX_GROWTH
                else:
                    fac = min(MAX_GROWTH, _step_factor(e, err_old[l]))
                err_old[l] = max(e, 1e-4)
                if rejected[l]:
                    fac = min(1.0, fac)
                rejected[l] = False
                for j in range(DIM):
                    col[j] = w[(ROW_YN + j) * LANES + l]
                # _inside written out (called, it cost the ephemeris model 23 ns a step), with
                # bodies at rest read from `rest` and a pre-test for moving ones: a particle farther
                # from the body's grid line than its radius plus off[bb] cannot be inside it, and
                # its position is then not evaluated. The decision is the exact test's.
                b = -1
                tb = tl[l] + hs
                # bodies at rest only (the CR3BP; the ephemeris model without the Moon): the plain
                # test, kept apart from the loop below (one loop with a per-body branch measured
                # 2-5 % slower for the CR3BP), positions read once per call
                if not anymoving:
                    for bb in range(nb):
                        bx = rest[bb, 0]
                        by = rest[bb, 1]
                        bz = rest[bb, 2]
{HIT:24}
                else:
                    for bb in range(nb):
                        if speed[bb] == 0.0:
                            bx = rest[bb, 0]
                            by = rest[bb, 1]
                            bz = rest[bb, 2]
                        else:
                            if off[bb] < np.inf:
                                g = (tb - t0) * direction * inv_dgrid
                                kg = min(max(int(g), 0), ngrid - 2)
                                sg = min(max(g - kg, 0.0), 1.0)
                                gx = col[0] - (grid[bb, kg, 0] + sg * (grid[bb, kg + 1, 0] - grid[bb, kg, 0]))
                                gy = col[1] - (grid[bb, kg, 1] + sg * (grid[bb, kg + 1, 1] - grid[bb, kg, 1]))
                                gz = col[2] - (grid[bb, kg, 2] + sg * (grid[bb, kg + 1, 2] - grid[bb, kg, 2]))
                                reach = body_rad[bb] + off[bb]
                                if gx * gx + gy * gy + gz * gz > reach * reach:
                                    continue
                            bx, by, bz = body_position(tb, params, bb, body_pos)
{HIT:24}
                if b >= 0:
                    for j in range(DIM):
                        col2[j] = w[(ROW_Y + j) * LANES + l]
                    for j in range(DIM):
                        col3[j] = w[(ROW_K0 + j) * LANES + l]
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
                    for j in range(DIM):
                        w[(ROW_Y + j) * LANES + l] = col[j]
                        w[(ROW_K0 + j) * LANES + l] = w[(ROW_F + j) * LANES + l]
                    if last[l]:
                        io = iout[l]
                        while io < nt and times[io] == tout:
                            for j in range(DIM):
                                out[io, i, j] = col[j]
                            io += 1
                        iout[l] = io
                        hl[l] = max(hl[l], hstep[l] * fac)
                        if io >= nt:
                            steps[i] = hl[l]
                            done = True
                    else:
                        hl[l] = hstep[l] * fac
            else:
                if e > 0.0:
                    fac = max(MIN_SHRINK, _step_factor(e, 1.0))
                else:
                    fac = 0.2
                hl[l] = hstep[l] * fac
                rejected[l] = True
                if hl[l] < hmin:
                    status[i] = 3
                    for j in range(DIM):
                        col[j] = w[(ROW_Y + j) * LANES + l]
                    _freeze(i, iout[l], col, out, nt)
                    done = True
            if not done and nsteps[l] >= max_steps and iout[l] < nt:
                status[i] = 2
                for j in range(DIM):
                    col[j] = w[(ROW_Y + j) * LANES + l]
                _freeze(i, iout[l], col, out, nt)
                done = True
            if done:
                who[l] = -1
                active -= 1
                while nxt < i1:
                    i = nxt
                    nxt += 1
{START:20}
                    if started:
                        who[l] = i
                        active += 1
                        break
'''


def driver_source(stages: str) -> str:
    """The driver's text with ``stages`` (the calls of the stage functions) in ``_lanes_step``,
    and the lane-loading and inside-a-body blocks written out at their two places each."""
    def block(text: str, indent: int) -> str:
        return "\n".join(" " * indent + line for line in text.splitlines())

    return (_TEMPLATE.replace("{STAGES}", stages).replace("{START:12}", block(_START, 12))
            .replace("{START:20}", block(_START, 20)).replace("{HIT:24}", block(_HIT, 24)))


DRIVER = _TEMPLATE
"""The template (placeholders ``{STAGES}``, ``{START:n}`` and ``{HIT:n}``); :func:`driver_source` fills it."""
