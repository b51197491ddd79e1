"""Ensemble propagation speed over one 9:2 NRHO period, at equal accuracy (not a test).

    .venv/bin/python benchmarks/bench_propagation.py [--sizes 1000 10000 100000] [--repeats 3]

Prints microseconds per particle-period for
  * cistrack's default path (CR3BP().propagate, default tolerance, all threads; and on one
    thread), and cistrack at the loosest tolerance that still meets 1e-9 LU ("tol-matched"),
  * scipy DOP853 one particle at a time (measured on a subset),
  * scipy DOP853 on the stacked 6N system (subset; its error control is an RMS over all particles),
  * heyoka batch mode, a Python loop over SIMD-width batches (if heyoka is installed), at the
    loosest tolerance that meets 1e-9 LU,
with the max position error of each against a scipy DOP853 rtol=1e-13 reference on a subset and
the ratio to the fastest, plus the machine. Ensemble: 9:2 NRHO + N(0, 10 km) position and
N(0, 1 cm/s) velocity perturbations.
"""
from __future__ import annotations

import argparse
import os
import platform
import sys
import time

import numpy as np
from scipy.integrate import solve_ivp

import numba
from cistrack import units
from cistrack.plugins.dynamics.orbit_catalog import ORBITS
from cistrack.plugins.dynamics.cr3bp import CR3BP, cr3bp_rhs

TARGET = 1e-9


def cpu_model() -> str:
    try:
        with open("/proc/cpuinfo") as fh:
            for line in fh:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown"


def ensemble(n: int, rng: np.random.Generator) -> np.ndarray:
    orbit = ORBITS["nrho-9-2"]
    sig = np.r_[[units.km_to_lu(10.0)] * 3, [units.kms_to_vu(1e-5)] * 3]
    return orbit.state + rng.normal(size=(n, 6)) * sig


def best_time(fn, repeats: int) -> float:
    best = np.inf
    for _ in range(repeats):
        t = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t)
    return best


def scipy_rhs(mu):
    p = np.array([mu])

    def f(t, y):
        out = np.empty(6)
        cr3bp_rhs(t, y, p, out)
        return out
    return f


def scipy_stacked_rhs(mu):
    def f(t, y):
        s = y.reshape(-1, 6)
        x, yy, z, vx, vy = s[:, 0], s[:, 1], s[:, 2], s[:, 3], s[:, 4]
        r1 = ((x + mu) ** 2 + yy ** 2 + z ** 2) ** 1.5
        r2 = ((x - 1 + mu) ** 2 + yy ** 2 + z ** 2) ** 1.5
        c = (1 - mu) / r1 + mu / r2
        out = np.empty_like(s)
        out[:, :3] = s[:, 3:]
        out[:, 3] = x + 2 * vy - (1 - mu) * (x + mu) / r1 - mu * (x - 1 + mu) / r2
        out[:, 4] = yy - 2 * vx - c * yy
        out[:, 5] = -c * z
        return out.ravel()
    return f


def heyoka_runner(mu: float, tol: float):
    import heyoka as hy
    x, y, z, vx, vy, vz = hy.make_vars("x", "y", "z", "vx", "vy", "vz")
    r1m3 = ((x + mu) ** 2 + y ** 2 + z ** 2) ** -1.5
    r2m3 = ((x - (1 - mu)) ** 2 + y ** 2 + z ** 2) ** -1.5
    sysm = [(x, vx), (y, vy), (z, vz),
            (vx, x + 2 * vy - (1 - mu) * (x + mu) * r1m3 - mu * (x - (1 - mu)) * r2m3),
            (vy, y - 2 * vx - (1 - mu) * y * r1m3 - mu * y * r2m3),
            (vz, -(1 - mu) * z * r1m3 - mu * z * r2m3)]
    b = hy.recommended_simd_size()
    ta = hy.taylor_adaptive_batch(sysm, np.zeros((6, b)), tol=tol)

    def run(states: np.ndarray, t_end: float) -> np.ndarray:
        n = states.shape[0]
        out = np.empty_like(states)
        for i in range(0, n, b):
            chunk = states[i:i + b]
            m = chunk.shape[0]
            st = np.empty((6, b))
            st[:, :m] = chunk.T
            st[:, m:] = chunk[-1:].T
            ta.set_time(0.0)
            ta.state[:] = st
            ta.propagate_until(t_end)
            out[i:i + m] = ta.state[:, :m].T
        return out
    return run, b


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[1000, 10000, 100000])
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--ref", type=int, default=16, help="particles in the accuracy reference subset")
    ap.add_argument("--scipy-subset", type=int, default=20)
    ap.add_argument("--stacked-subset", type=int, default=200)
    args = ap.parse_args()

    orbit = ORBITS["nrho-9-2"]
    period, mu = orbit.period, orbit.mu
    rng = np.random.default_rng(2024)
    big = ensemble(max(args.sizes), rng)
    sub = big[:args.ref]
    ref = np.array([solve_ivp(scipy_rhs(mu), (0, period), s, method="DOP853", rtol=1e-13,
                              atol=1e-15).y[:3, -1] for s in sub])

    def err(final: np.ndarray) -> float:
        return float(np.max(np.abs(final[:args.ref, :3] - ref)))

    print(f"machine: {cpu_model()}; {os.cpu_count()} logical cores; numba threads {numba.get_num_threads()}")
    print(f"python {platform.python_version()}, numpy {np.__version__}, numba {numba.__version__}",
          end="")
    try:
        import heyoka as hy
        print(f", heyoka {hy.__version__}")
    except ImportError:
        hy = None
        print(", heyoka not installed")
    print(f"orbit: 9:2 NRHO, one period = {period:.6f} TU ({units.tu_to_days(period):.3f} d); "
          "ensemble sigma 10 km, 1 cm/s; error = max |position - ref| (LU) on "
          f"{args.ref} particles, ref = scipy DOP853 rtol 1e-13")

    dyn = CR3BP()
    t = time.perf_counter()
    dyn.propagate(sub, 0.0, period)
    print(f"cistrack first call (kernel load or compile): {time.perf_counter() - t:.2f} s\n")

    # loosest cistrack tolerance that meets the target (rtol = atol / 10)
    loose = None
    for atol in (1e-8, 3e-9, 1e-9, 3e-10, 1e-10, 3e-11):
        if err(dyn.propagate(sub, 0.0, period, rtol=atol / 10, atol=atol).final) <= TARGET:
            loose = atol
            break

    rows = []  # (label, N, us per particle-period, error)
    for n in args.sizes:
        x = big[:n]
        out = {}
        tt = best_time(lambda: out.__setitem__("f", dyn.propagate(x, 0.0, period).final),
                       args.repeats if n <= 10000 else max(1, args.repeats - 1))
        rows.append(("cistrack default (rtol 1e-12, atol 2e-11)", n, tt / n * 1e6, err(out["f"])))
        if loose is not None:
            tt = best_time(lambda: out.__setitem__("g", dyn.propagate(
                x, 0.0, period, rtol=loose / 10, atol=loose).final),
                args.repeats if n <= 10000 else max(1, args.repeats - 1))
            rows.append((f"cistrack tol-matched (atol {loose:g})", n, tt / n * 1e6, err(out["g"])))

    # per-core figure: cistrack's default on one thread (N = the middle size)
    n = sorted(args.sizes)[len(args.sizes) // 2]
    os.environ["CISTRACK_NUM_THREADS"] = "1"
    out = {}
    tt = best_time(lambda: out.__setitem__("f", dyn.propagate(big[:n], 0.0, period).final), args.repeats)
    del os.environ["CISTRACK_NUM_THREADS"]
    rows.append(("cistrack default, 1 thread", n, tt / n * 1e6, err(out["f"])))

    # scipy, one particle at a time, same tolerances as cistrack's default
    m = args.scipy_subset
    f1 = scipy_rhs(mu)
    res = []
    t = time.perf_counter()
    for s in big[:m]:
        res.append(solve_ivp(f1, (0, period), s, method="DOP853", rtol=dyn.rtol, atol=dyn.atol).y[:, -1])
    tt = time.perf_counter() - t
    rows.append((f"scipy DOP853 one at a time (N={m} subset)", m, tt / m * 1e6, err(np.array(res))))

    # scipy on the stacked system
    m = args.stacked_subset
    t = time.perf_counter()
    sol = solve_ivp(scipy_stacked_rhs(mu), (0, period), big[:m].ravel(), method="DOP853",
                    rtol=dyn.rtol, atol=dyn.atol)
    tt = time.perf_counter() - t
    rows.append((f"scipy DOP853 stacked 6N (N={m} subset)", m, tt / m * 1e6,
                 err(sol.y[:, -1].reshape(-1, 6))))

    if hy is not None:
        chosen = None
        for tol in (1e-9, 1e-10, 1e-11, 1e-12, 1e-13, 1e-14, 1e-15):
            run, b = heyoka_runner(mu, tol)
            e = err(run(sub, period))
            if e <= TARGET:
                chosen = (tol, run, b)
                break
        if chosen is not None:
            tol, run, b = chosen
            for n in args.sizes:
                x = big[:n]
                out = {}
                tt = best_time(lambda: out.__setitem__("h", run(x, period)),
                               args.repeats if n <= 10000 else 1)
                rows.append((f"heyoka batch {b}, 1 thread (tol {tol:g})", n, tt / n * 1e6, err(out["h"])))

    fastest = min(r[2] for r in rows)
    print(f"{'method':52s} {'N':>7s} {'us/particle-period':>19s} {'x fastest':>10s} {'max err':>9s}")
    for label, n, us, e in rows:
        print(f"{label:52s} {n:7d} {us:19.2f} {us / fastest:10.1f} {e:9.1e}")


if __name__ == "__main__":
    sys.exit(main())
