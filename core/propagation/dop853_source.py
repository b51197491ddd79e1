"""Source generator for the per-particle DOP853 ensemble integrator.

The Dormand–Prince 8(5,3) pair (Hairer, Nørsett & Wanner, *Solving ODEs I*, sec. II.10) is
written out as straight-line code with only the non-zero Butcher coefficients, for one state
dimension known at compile time, around a model's right-hand side ``rhs(t, y, params, out)``.
The result is the text of a small Python module whose numba functions are compiled with
``cache=True``: :mod:`cistrack.propagation.kernels` writes it to a file once per model
(named by a hash of everything it depends on) and imports it, so numba's on-disk cache works
for third-party models too (a jitted function passed as an argument, or captured by a
closure, defeats numba's cache).

Generated entry points
----------------------
``propagate_kernel(i0, i1, y0, params, t0, times, rtol, atol, body_pos, body_rad, max_steps,
steps, out, impact_body, impact_time, status)``
    Integrates rows ``i0:i1`` of ``y0`` (N, DIM), one particle's whole integration after the
    other, to each of ``times`` (K,), writing ``out`` (K, N, DIM). It releases the GIL
    (``nogil=True``): the caller runs disjoint row ranges on several threads. Every
    particle has its own step size and its own error control (the RMS of the particle's DIM
    components, Hairer's combined 5th/3rd-order estimate). Steps are clipped to land exactly
    on output times. After each accepted step the position (first three components) is tested
    against every body; on entry the crossing of the surface is located to ~1e-13 of the step
    by re-stepping from the step start (Illinois iteration), the state there is frozen into all
    later outputs, ``impact_body``/``impact_time`` are set and ``status`` is 1. ``status`` 2 is
    "step limit reached", 3 "step size underflow" (state frozen where it stopped).
    ``steps`` (N,) is read and written: a particle whose entry is positive starts with that step
    size (clipped to the span) instead of choosing one (Hairer's initial-step estimate, about 40 %
    of a short call's cost), and a particle that reaches the last output time leaves there the
    step size its error control proposes next, so that a later call can carry on with it.
``derivatives_kernel(t, states, params, out)``
    ``out[i] = rhs(t, states[i])`` for every row.
``dense_kernel(...)``
    One particle's integration recording every step's dense output (see
    :mod:`.dop853_dense_source`).
``propagate_lanes_kernel(...)`` (only for a right-hand side that :mod:`.lane_rhs` can rewrite)
    ``propagate_kernel``'s arguments and bit-identical results, particles integrated in SIMD
    lockstep (:mod:`.dop853_lanes_source`).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from cistrack.propagation import dop853_tableau as _tab
from cistrack.propagation.dop853_dense_source import DENSE_BODY
from cistrack.propagation.dop853_lanes_source import lanes_source

__all__ = ["N_STAGES", "ERROR_EXPONENT", "TABLEAU", "generate_source", "StepControl", "LaneKernel", "DEFAULT_FASTMATH"]

N_STAGES = _tab.N_STAGES
"""Stages per step; the 13th evaluation (at the new point) is reused as the next step's first."""
ERROR_EXPONENT = -1.0 / 8.0
"""Step-size exponent: the embedded estimate behaves like h^8."""

TABLEAU = {
    "A": _tab.stage_matrix(),
    "B": np.array(_tab.B, dtype=float),
    "C": np.array(_tab.C, dtype=float),
    "E3": np.array(_tab.E3, dtype=float),
    "E5": np.array(_tab.E5, dtype=float),
}
"""The DOP853 coefficients (from :mod:`.dop853_tableau`), dense arrays keyed A, B, C, E3, E5."""

DEFAULT_FASTMATH = False
"""No LLVM fast-math flags in the generated kernels: results must not depend on how they were built.

With value-changing flags (``reassoc`` with ``nsz``) LLVM may re-associate arithmetic differently
depending on the optimisation context, and that context differs between a kernel compiled in the
running process (its callees linked from separately compiled libraries) and the same kernel
loaded from numba's on-disk cache (one self-contained object): states then differ in the last
bits between a cold and a warm cache, and a filter amplifies that to a different result.
Without the flags both paths give bit-identical states, at the same speed (straight-line scalar
code has nothing to vectorise).
"""


def _lin(coefs, name: str, j: int) -> str:
    """``c0*k0_j + c3*k3_j + ...`` over the non-zero coefficients (``0.0`` if none)."""
    terms = [f"{float(c)!r} * {name}{m}_{j}" for m, c in enumerate(coefs) if c != 0.0]
    return " + ".join(terms) if terms else "0.0"


def _rk_step_source(dim: int, dense: bool = False) -> str:
    """``_rk_step(t, h, y, k0, params, ytmp, ynew, f, rtol, atol) -> err``.

    One DOP853 step from (t, y) with f(t, y) = k0: writes the 8th-order solution to ``ynew`` and
    f(t + h, ynew) to ``f`` (the next step's k0), returns Hairer's error norm. Every stage
    derivative lives in a local scalar, so the only memory traffic is the rhs arguments.

    ``dense=True`` writes ``_rk_step_dense(..., coef)`` instead: the same step (bit-identical
    ``ynew``, ``f`` and error), plus three extra stages and the step's dense-output coefficients
    F0..F6 in ``coef`` (7, DIM) (see :data:`.dop853_tableau.D`).
    """
    A, B, C, E3, E5 = (TABLEAU[k] for k in ("A", "B", "C", "E3", "E5"))
    name = "_rk_step_dense" if dense else "_rk_step"
    extra_arg = ", coef" if dense else ""
    L = ["@njit(cache=CACHE, fastmath=FASTMATH)",
         f"def {name}(t, h, y, k0, params, ytmp, ynew, f, rtol, atol{extra_arg}):"]
    L += [f"    y_{j} = y[{j}]" for j in range(dim)]
    L += [f"    k0_{j} = k0[{j}]" for j in range(dim)]
    for s in range(1, N_STAGES):
        L += [f"    ytmp[{j}] = y_{j} + h * ({_lin(A[s, :s], 'k', j)})" for j in range(dim)]
        L.append(f"    rhs(t + {float(C[s])!r} * h, ytmp, params, f)")
        L += [f"    k{s}_{j} = f[{j}]" for j in range(dim)]
    L += [f"    yn_{j} = y_{j} + h * ({_lin(B, 'k', j)})" for j in range(dim)]
    L += [f"    ynew[{j}] = yn_{j}" for j in range(dim)]
    L.append("    rhs(t + h, ynew, params, f)")
    L += [f"    k12_{j} = f[{j}]" for j in range(dim)]
    L += ["    s5 = 0.0", "    s3 = 0.0"]
    for j in range(dim):
        L += [f"    isc = 1.0 / (atol + rtol * max(abs(y_{j}), abs(yn_{j})))",
              f"    d5 = ({_lin(E5, 'k', j)}) * isc",
              f"    d3 = ({_lin(E3, 'k', j)}) * isc",
              "    s5 += d5 * d5",
              "    s3 += d3 * d3"]
    L += ["    if s5 == 0.0 and s3 == 0.0:",
          "        err = 0.0",
          "    else:",
          "        err = abs(h) * s5 / np.sqrt((s5 + 0.01 * s3) * DIM)"]
    if dense:
        for e, row in enumerate(_tab.A_EXTRA_ROWS):
            s = N_STAGES + 1 + e
            L += [f"    ytmp[{j}] = y_{j} + h * ({_lin(row, 'k', j)})" for j in range(dim)]
            L.append(f"    rhs(t + {float(_tab.C_EXTRA[e])!r} * h, ytmp, params, f)")
            L += [f"    k{s}_{j} = f[{j}]" for j in range(dim)]
        for j in range(dim):
            L += [f"    f[{j}] = k12_{j}",
                  f"    dy = yn_{j} - y_{j}",
                  f"    coef[0, {j}] = dy",
                  f"    coef[1, {j}] = h * k0_{j} - dy",
                  f"    coef[2, {j}] = 2.0 * dy - h * (k12_{j} + k0_{j})"]
            L += [f"    coef[{3 + r}, {j}] = h * ({_lin(_tab.D[r], 'k', j)})" for r in range(4)]
    L.append("    return err")
    return "\n".join(L) + "\n"


_BODY = '''
@njit(cache=CACHE, fastmath=FASTMATH)
def _inside(t, y, params, body_pos, body_rad):
    """Index of the first body whose surface contains position y[:3] at t, -1 for none."""
    for b in range(body_rad.shape[0]):
        bx, by, bz = body_position(t, params, b, body_pos)
        dx = y[0] - bx
        dy = y[1] - by
        dz = y[2] - bz
        if dx * dx + dy * dy + dz * dz < body_rad[b] * body_rad[b]:
            return b
    return -1


@njit(cache=CACHE, fastmath=FASTMATH)
def _surface_gap(t, y, params, body_pos, body_rad, b):
    bx, by, bz = body_position(t, params, b, body_pos)
    dx = y[0] - bx
    dy = y[1] - by
    dz = y[2] - bz
    return np.sqrt(dx * dx + dy * dy + dz * dz) - body_rad[b]


@njit(cache=CACHE, fastmath=FASTMATH)
def _locate_impact(t, h, y, k0, params, ytmp, yout, f, body_pos, body_rad, b):
    """Fraction s of the step h at which y crosses body b's surface; yout = state there.

    The partial steps are the dense step's (the same ``yout`` as ``_rk_step``'s, bit for bit;
    its coefficients go to a scratch array): every kernel then shares the one step that the
    dense kernel compiles anyway, and a run compiles no ``_rk_step`` unless it integrates one
    particle at a time."""
    coef = np.empty((7, DIM))
    s_lo = 0.0
    g_lo = _surface_gap(t, y, params, body_pos, body_rad, b)
    s_hi = 1.0
    g_hi = _surface_gap(t + h, yout, params, body_pos, body_rad, b)  # yout: the full step on entry
    if not (g_lo > 0.0):
        for j in range(DIM):
            yout[j] = y[j]
        return 0.0
    side = 0
    s = 1.0
    for _ in range(80):
        s = (s_lo * g_hi - s_hi * g_lo) / (g_hi - g_lo)
        if not (s > s_lo and s < s_hi):
            s = 0.5 * (s_lo + s_hi)
        _rk_step_dense(t, s * h, y, k0, params, ytmp, yout, f, 1.0, 1.0, coef)
        g = _surface_gap(t + s * h, yout, params, body_pos, body_rad, b)
        if g > 0.0:
            s_lo = s
            g_lo = g
            if side == -1:
                g_hi *= 0.5
            side = -1
        else:
            s_hi = s
            g_hi = g
            if side == 1:
                g_lo *= 0.5
            side = 1
        if abs(g) <= 1e-14 * body_rad[b] or (s_hi - s_lo) <= 1e-14:
            break
    return s


@njit(cache=CACHE, fastmath=FASTMATH)
def _initial_step(t, y, f0, direction, params, rtol, atol, ytmp, f1, span):
    """Hairer's starting step-size heuristic for one particle."""
    d0 = 0.0
    d1 = 0.0
    for j in range(DIM):
        sc = atol + rtol * abs(y[j])
        d0 += (y[j] / sc) ** 2
        d1 += (f0[j] / sc) ** 2
    d0 = np.sqrt(d0 / DIM)
    d1 = np.sqrt(d1 / DIM)
    if d0 < 1e-5 or d1 < 1e-5:
        h0 = 1e-6
    else:
        h0 = 0.01 * d0 / d1
    h0 = min(h0, span)
    if not (h0 > 0.0):  # a derivative that overflows (d1 = inf): start small, the error control decides
        h0 = 1e-6 * span
    for j in range(DIM):
        ytmp[j] = y[j] + direction * h0 * f0[j]
    rhs(t + direction * h0, ytmp, params, f1)
    d2 = 0.0
    for j in range(DIM):
        sc = atol + rtol * abs(y[j])
        d2 += ((f1[j] - f0[j]) / sc) ** 2
    d2 = np.sqrt(d2 / DIM) / h0
    if d1 <= 1e-15 and d2 <= 1e-15:
        h1 = max(1e-6, h0 * 1e-3)
    else:
        h1 = (0.01 / max(d1, d2)) ** (1.0 / 8.0)
    h = min(100.0 * h0, h1)
    if not (h > 0.0):
        h = 1e-6
    return min(h, span)


@njit(cache=CACHE, fastmath=FASTMATH)
def _freeze(i, iout, y, out, nt):
    for m in range(iout, nt):
        for j in range(DIM):
            out[m, i, j] = y[j]


@njit(cache=CACHE, fastmath=FASTMATH)
def _integrate_one(i, y0, params, t0, times, direction, rtol, atol, body_pos, body_rad,
                   max_steps, steps, out, impact_body, impact_time, status, scratch):
    nt = times.shape[0]
    y = scratch[0]
    k0 = scratch[1]
    ynew = scratch[2]
    f = scratch[3]
    ytmp = scratch[4]
    for j in range(DIM):
        y[j] = y0[i, j]
    t = t0
    b = _inside(t, y, params, body_pos, body_rad)
    if b >= 0:
        impact_body[i] = b
        impact_time[i] = t0
        status[i] = 1
        _freeze(i, 0, y, out, nt)
        return
    iout = 0
    while iout < nt and times[iout] == t0:
        for j in range(DIM):
            out[iout, i, j] = y[j]
        iout += 1
    if iout == nt:
        return
    rhs(t, y, params, k0)
    span = abs(times[nt - 1] - t0)
    if steps[i] > 0.0:  # the step this particle's previous integration proposed
        h = min(steps[i], span)
    else:
        h = _initial_step(t, y, k0, direction, params, rtol, atol, ytmp, f, span)
    hmin = 1e-14 * max(1.0, abs(t0), abs(times[nt - 1]))
    nsteps = 0
    rejected = False
    err_old = 1e-4
    while iout < nt:
        tout = times[iout]
        remaining = abs(tout - t)
        hstep = h
        last = False
        if hstep * 1.01 >= remaining:
            hstep = remaining
            last = True
        hs = direction * hstep
        err = _rk_step(t, hs, y, k0, params, ytmp, ynew, f, rtol, atol)
        nsteps += 1
        if err <= 1.0:
            if err == 0.0 or err <= GROWTH_CAP_ERR:  # growth capped whatever the factor rounds to
                fac = MAX_GROWTH
            else:  # PI control (Gustafsson; Hairer's DOP853 with beta): damps step-size oscillation
                fac = min(MAX_GROWTH, _step_factor(err, err_old))
            err_old = max(err, 1e-4)
            if rejected:
                fac = min(1.0, fac)
            rejected = False
            b = _inside(t + hs, ynew, params, body_pos, body_rad)
            if b >= 0:
                s = _locate_impact(t, hs, y, k0, params, ytmp, ynew, f, body_pos, body_rad, b)
                impact_body[i] = b
                impact_time[i] = t + s * hs
                status[i] = 1
                _freeze(i, iout, ynew, out, nt)
                return
            if last:
                t = tout
            else:
                t = t + hs
            for j in range(DIM):
                y[j] = ynew[j]
                k0[j] = f[j]
            if last:
                while iout < nt and times[iout] == tout:
                    for j in range(DIM):
                        out[iout, i, j] = y[j]
                    iout += 1
                h = max(h, hstep * fac)
            else:
                h = hstep * fac
        else:
            if err > 0.0:
                fac = max(MIN_SHRINK, _step_factor(err, 1.0))
            else:  # NaN: a stage landed on a singularity
                fac = 0.2
            h = hstep * fac
            rejected = True
            if h < hmin:
                status[i] = 3
                _freeze(i, iout, y, out, nt)
                return
        if nsteps >= max_steps and iout < nt:
            status[i] = 2
            _freeze(i, iout, y, out, nt)
            return
    steps[i] = h


@njit(cache=CACHE, nogil=True, fastmath=FASTMATH)
def propagate_kernel(i0, i1, y0, params, t0, times, rtol, atol, body_pos, body_rad, max_steps,
                     steps, out, impact_body, impact_time, status):
    direction = 1.0
    if times[times.shape[0] - 1] < t0:
        direction = -1.0
    scratch = np.empty((5, DIM))  # state, stage and trial vectors, reused for every particle
    for i in range(i0, i1):
        _integrate_one(i, y0, params, t0, times, direction, rtol, atol, body_pos, body_rad,
                       max_steps, steps, out, impact_body, impact_time, status, scratch)


@njit(cache=CACHE, fastmath=FASTMATH)
def derivatives_kernel(t, states, params, out):
    for i in range(states.shape[0]):
        rhs(t, states[i], params, out[i])
'''


def _motion_source(motion_import: str | None, fm: str) -> str:
    """Header lines binding ``body_position(t, params, b, body_pos) -> (x, y, z)`` (compiled
    with the kernels' fast-math flags ``fm``, like the right-hand side)."""
    if motion_import is None:
        return ("@njit(inline='always')\n"
                "def body_position(t, params, b, body_pos):\n"
                "    return body_pos[b, 0], body_pos[b, 1], body_pos[b, 2]\n\n\n")
    return (f"{motion_import}\n"
            f"body_position = njit(inline='always', fastmath={fm})(body_position.py_func)\n\n")


def step_factor_source(beta: float) -> str:
    """Text of ``_step_factor(err, err_old)``: SAFETY * err^-EXPO1 * err_old^BETA, the step-size
    controller's factor before clipping (``err_old`` 1.0 for a rejected step).

    With I control (``beta`` 0, the default) err^-1/8 is ``1 / sqrt(sqrt(sqrt(err)))``: three
    square roots and a division, each rounded correctly by IEEE 754, so the factor is the same on
    every machine (libm's ``pow`` is not specified to the last bit, and is slower). With PI
    control it stays ``pow``."""
    if float(beta) == 0.0:
        expr = "SAFETY / np.sqrt(np.sqrt(np.sqrt(err)))"
    else:
        expr = "SAFETY * err ** -EXPO1 * err_old ** BETA"
    return ("@njit(inline='always')\n"
            "def _step_factor(err, err_old):\n"
            f"    return {expr}\n\n\n")


def growth_cap_error(safety: float, max_growth: float, beta: float) -> float:
    """Error estimate at or below which an accepted step's growth factor is ``max_growth``.

    With I control (``beta`` 0) the factor is min(max_growth, safety * err^-1/8), which is
    max_growth for err <= (safety / max_growth)^8 (2.56e-6 at the defaults). The bound returned
    is that value times (1 + 1e-9)^-8, so that safety * err^-1/8 exceeds max_growth by 1e-9
    relative there, far more than the rounding of the factor (:func:`step_factor_source`):
    testing it first skips the factor (a ``pow``; clipped steps that land on an output time
    mostly have such errors) and gives the factor ``min`` would have given, bit for bit. -1.0
    (never) with PI control (``beta`` not 0), whose factor also depends on the previous step's
    error.
    """
    if beta != 0.0:
        return -1.0
    return (float(safety) / (float(max_growth) * (1.0 + 1e-9))) ** (1.0 / 0.125)


@dataclass(frozen=True)
class StepControl:
    """The step-size controller: h_new = h * clip(safety * err^-(1/8 - beta/5) * err_prev^beta,
    min_shrink, max_growth) (Hairer's DOP853 PI control; beta = 0 is I control, the default:
    larger values took more steps on the 9:2 NRHO)."""

    safety: float = 0.8
    max_growth: float = 4.0
    min_shrink: float = 0.2
    beta: float = 0.0


@dataclass(frozen=True)
class LaneKernel:
    """The SIMD-lockstep kernel to add: the right-hand side rewritten for lanes
    (:func:`.lane_rhs.lane_body`), a line binding the global names its body reads, and the
    particles per batch (None: :func:`.dop853_lanes_source.lanes_for` the body)."""

    body: Any
    import_line: str = ""
    lanes: int | None = None


def generate_source(rhs_import: str, dim: int, *, cache: bool = True, control: StepControl = StepControl(),
                    fastmath=DEFAULT_FASTMATH, title: str = "", motion_import: str | None = None,
                    lanes: LaneKernel | None = None) -> str:
    """Text of a module holding the DOP853 ensemble kernels for one right-hand side.

    Parameters
    ----------
    rhs_import : str
        A line that binds the name ``rhs`` (e.g. ``"from pkg.mod import my_rhs as rhs"``), or
        ``""`` when the caller injects ``rhs`` into the module's globals itself.
    dim : int
        State dimension (6 for position and velocity).
    cache : bool
        numba ``cache=`` of the generated functions.
    control : StepControl
        The step-size controller (safety, max_growth, min_shrink, beta).
    fastmath : set of str or bool
        numba ``fastmath=`` flags of the kernels, also applied to the inlined right-hand side
        (whatever its own flags). The default (none) keeps results independent of whether the
        kernels were compiled or loaded from the cache; see :data:`DEFAULT_FASTMATH`.
    title : str
        Named in the generated module's docstring.
    motion_import : str, optional
        A line that binds ``body_position`` (``""`` when the caller injects it): an ``@njit``
        function ``body_position(t, params, b, body_pos) -> (x, y, z)`` giving body ``b``'s
        position at ``t`` for models whose bodies move (e.g. the Moon in an inertial frame).
        ``None`` (default): bodies sit at the fixed ``body_pos[b]``.
    lanes : LaneKernel, optional
        Adds the lockstep kernel ``propagate_lanes_kernel`` (:mod:`.dop853_lanes_source`).
    """
    safety, max_growth, min_shrink, beta = control.safety, control.max_growth, control.min_shrink, control.beta
    fm = ("{" + ", ".join(repr(f) for f in sorted(fastmath)) + "}") if not isinstance(fastmath, bool) else repr(fastmath)
    header = (f'"""Generated by cistrack.propagation.dop853_source {title}: do not edit."""\n'
              "import numpy as np\n"
              "from numba import njit\n"
              f"{rhs_import}\n"
              "# The model compiled once with the kernels' flags and called (LLVM inlines it where it\n"
              "# pays); numba-IR inlining into each of the 13 stages of every step function cost\n"
              "# about 7 s of CPU per first compilation, for the same machine code.\n"
              f"rhs = njit(fastmath={fm})(rhs.py_func)\n\n"
              + _motion_source(motion_import, fm) +
              f"DIM = {int(dim)}\n"
              f"CACHE = {bool(cache)!r}\n"
              f"SAFETY = {float(safety)!r}\n"
              f"MAX_GROWTH = {float(max_growth)!r}\n"
              f"MIN_SHRINK = {float(min_shrink)!r}\n"
              f"BETA = {float(beta)!r}\n"
              f"EXPO1 = {0.125 - 0.2 * float(beta)!r}\n"
              f"GROWTH_CAP_ERR = {growth_cap_error(safety, max_growth, beta)!r}\n"
              f"FASTMATH = {fm}\n\n\n" + step_factor_source(beta))
    return (header + _rk_step_source(dim) + _BODY + "\n\n" + _rk_step_source(dim, dense=True)
            + DENSE_BODY
            + ("" if lanes is None else "\n\n" + lanes.import_line + lanes_source(dim, lanes.body, lanes.lanes)))
