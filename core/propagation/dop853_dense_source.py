"""Template of the dense-output driver appended to every generated kernel module.

``dense_kernel(state, params, t1, rtol, atol, body_pos, body_rad, max_steps, rec_t, rec_h, rec_y,
rec_c, ctl)`` integrates ONE particle from ``ctl[0]`` towards ``t1`` and records every accepted
step: its start time ``rec_t[r]``, signed size ``rec_h[r]``, start state ``rec_y[r]`` (DIM,) and
dense-output coefficients ``rec_c[r]`` (7, DIM) (see :data:`.dop853_tableau.D` for the
interpolant). It takes steps exactly as ``propagate_kernel`` does with the single output time
``t1`` (same step-size control, same impact location), so its final state equals
``propagate_kernel``'s to the last bit.

The integration can be resumed: ``ctl`` (float64, length 10) carries ``t, h, err_old, rejected,
nsteps, status, nrec, impact_body, impact_time, t_start`` and ``state`` (DIM,) the current state. On the
first call ``ctl[1]`` (h) is 0 (the starting step is chosen then); the kernel returns when the
particle reaches ``t1`` (status -1), hits a body (1: the last record ends at the located impact
point), reaches ``max_steps`` (2), has its step underflow (3), or fills the record arrays (4: the
caller appends more room and calls again; the records continue bit-identically).
"""
from __future__ import annotations

__all__ = ["DENSE_BODY", "CTL_SIZE"]

CTL_SIZE = 10

DENSE_BODY = '''


@njit(cache=CACHE, nogil=True, fastmath=FASTMATH)
def dense_kernel(state, params, t1, rtol, atol, body_pos, body_rad, max_steps, rec_t, rec_h,
                 rec_y, rec_c, ctl):
    cap = rec_t.shape[0]
    nrec = int(ctl[6])
    t = ctl[0]
    direction = 1.0
    if t1 < t:
        direction = -1.0
    y = np.empty(DIM)
    k0 = np.empty(DIM)
    ynew = np.empty(DIM)
    f = np.empty(DIM)
    ytmp = np.empty(DIM)
    coef = np.empty((7, DIM))
    for j in range(DIM):
        y[j] = state[j]
    if ctl[1] == 0.0:  # first call
        b = _inside(t, y, params, body_pos, body_rad)
        if b >= 0:
            ctl[5] = 1.0
            ctl[7] = b
            ctl[8] = t
            return
        if t == t1:
            ctl[5] = -1.0
            return
    rhs(t, y, params, k0)
    span = abs(t1 - t)
    if ctl[1] == 0.0:
        h = _initial_step(t, y, k0, direction, params, rtol, atol, ytmp, f, span)
        err_old = 1e-4
        rejected = False
        nsteps = 0
        ctl[9] = t
    else:
        h = ctl[1]
        err_old = ctl[2]
        rejected = ctl[3] != 0.0
        nsteps = int(ctl[4])
    hmin = 1e-14 * max(1.0, abs(ctl[9]), abs(t1))
    while True:
        if nrec >= cap:
            ctl[5] = 4.0
            break
        remaining = abs(t1 - t)
        hstep = h
        last = False
        if hstep * 1.01 >= remaining:
            hstep = remaining
            last = True
        hs = direction * hstep
        err = _rk_step_dense(t, hs, y, k0, params, ytmp, ynew, f, rtol, atol, coef)
        nsteps += 1
        if err <= 1.0:
            if err == 0.0 or err <= GROWTH_CAP_ERR:  # growth capped whatever the factor rounds to
                fac = MAX_GROWTH
            else:
                fac = min(MAX_GROWTH, _step_factor(err, err_old))
            err_old = max(err, 1e-4)
            if rejected:
                fac = min(1.0, fac)
            rejected = False
            b = _inside(t + hs, ynew, params, body_pos, body_rad)
            if b >= 0:
                s = _locate_impact(t, hs, y, k0, params, ytmp, ynew, f, body_pos, body_rad, b)
                # the last record: the partial step from t to the impact point
                _rk_step_dense(t, s * hs, y, k0, params, ytmp, ynew, f, 1.0, 1.0, coef)
                rec_t[nrec] = t
                rec_h[nrec] = s * hs
                for j in range(DIM):
                    rec_y[nrec, j] = y[j]
                    for m in range(7):
                        rec_c[nrec, m, j] = coef[m, j]
                    y[j] = ynew[j]
                nrec += 1
                t = t + s * hs
                ctl[5] = 1.0
                ctl[7] = b
                ctl[8] = t
                break
            rec_t[nrec] = t
            rec_h[nrec] = hs
            for j in range(DIM):
                rec_y[nrec, j] = y[j]
                for m in range(7):
                    rec_c[nrec, m, j] = coef[m, j]
            nrec += 1
            if last:
                t = t1
            else:
                t = t + hs
            for j in range(DIM):
                y[j] = ynew[j]
                k0[j] = f[j]
            if last:
                ctl[5] = -1.0
                break
            h = hstep * fac
        else:
            if err > 0.0:
                fac = max(MIN_SHRINK, _step_factor(err, 1.0))
            else:
                fac = 0.2
            h = hstep * fac
            rejected = True
            if h < hmin:
                ctl[5] = 3.0
                break
        if nsteps >= max_steps:
            ctl[5] = 2.0
            break
    ctl[0] = t
    ctl[1] = h
    ctl[2] = err_old
    ctl[3] = 1.0 if rejected else 0.0
    ctl[4] = nsteps
    ctl[6] = nrec
    for j in range(DIM):
        state[j] = y[j]
'''
