"""Rows of the first pass vs time of the IOD's gross-outlier screen (plugins/iod/pass_screen.py).

The first full pass of the approximate 9:2 NRHO seen by the default ground telescope (1.5 arcsec)
is sampled at K evenly spaced times (K = --rows), once clean and once with two observations a
degree off; each is screened the way the IOD does it (``prepare_fit``, which screens the whole
first pass and then selects the fit window). Prints the machine, then per K the wall and CPU
seconds (min of --repeat; CPU seconds per row), the rows screened out and the least-squares solves and QR
factorisations numpy was asked for:

    .venv/bin/python benchmarks/iod_screen_scaling.py --rows 100,400,1000,4000,40000,400000

``--reference FILE`` also times another pass_screen.py (e.g. the one before a change:
``git show REV:plugins/iod/pass_screen.py > /tmp/old_screen.py``) up to --reference-max-rows.
Not a test: timings depend on the machine and its load.
"""
from __future__ import annotations

import argparse
import importlib.util
import sys
import time
from pathlib import Path

import numpy as np
from scipy.integrate import solve_ivp

from cistrack.plugins.iod import kinematic_fit
from cistrack.plugins.iod.kinematic_fit import prepare_fit
from cistrack.plugins.sensors.ground_telescope import GroundTelescope
from cistrack.units import ARCSEC_RAD, hours_to_tu

sys.path.insert(0, str(Path(__file__).resolve().parent))
from machine import machine_lines  # noqa: E402

MU = 1.2150582e-2
NRHO_9_2 = [1.0221, 0.0, -0.1821, 0.0, -0.1033, 0.0]
WINDOW = dict(order=4, pass_gap_hours=3.0, fit_fraction=0.5, min_fit=8, max_fit=12)


def _rhs(_t, s):
    x, y, z, vx, vy, vz = s
    r1 = np.sqrt((x + MU) ** 2 + y * y + z * z) ** 3
    r2 = np.sqrt((x - 1 + MU) ** 2 + y * y + z * z) ** 3
    return [vx, vy, vz, x + 2 * vy - (1 - MU) * (x + MU) / r1 - MU * (x - 1 + MU) / r2,
            y - 2 * vx - (1 - MU) * y / r1 - MU * y / r2, -(1 - MU) * z / r1 - MU * z / r2]


def first_pass(sensor: GroundTelescope):
    """The dense truth (callable t TU -> (6, K)) and the first full pass's (start, end) TU."""
    t_end = 2 * 86400.0 / 375149.0
    sol = solve_ivp(_rhs, (0.0, t_end), NRHO_9_2, rtol=1e-11, atol=1e-12, method="DOP853", dense_output=True).sol
    grid = np.arange(0.0, t_end, float(hours_to_tu(1 / 6)))
    p = [p for p in sensor.passes(grid, sol(grid).T) if p.start > 0][0]
    return sol, (p.start, p.end)


def measurements(sensor: GroundTelescope, truth, span: tuple[float, float], rows: int, outliers: int):
    """``rows`` measurements evenly over ``span``; ``outliers`` of them (at 1/5 and 3/5 of the pass)
    moved a degree in elevation."""
    lo, hi = span
    times = np.linspace(lo + 1e-6, hi - 1e-6, rows)
    ms = sensor.simulate(truth(times).T, times, np.random.default_rng(rows))
    el = ms.names.index("elevation")
    for k in range(outliers):
        ms.values[(2 * k + 1) * rows // 5, el] += 3600.0 * ARCSEC_RAD
    return ms


class _Counted:
    """Counts the calls of one numpy.linalg function while installed."""

    def __init__(self, name: str):
        self.name, self.calls = name, 0
        self.original = getattr(np.linalg, name)

    def __call__(self, *args, **kwargs):
        self.calls += 1
        return self.original(*args, **kwargs)


def timed(ms, sensor, repeat: int, screen=None) -> tuple[float, float, int, int]:
    """(wall s, CPU s, rows screened out, least-squares solves + QR factorisations) of prepare_fit."""
    saved = kinematic_fit.screen_pass
    counters = [_Counted("lstsq"), _Counted("qr")]
    best_wall, best_cpu, found = np.inf, np.inf, 0
    try:
        if screen is not None:
            kinematic_fit.screen_pass = screen
        for c in counters:
            setattr(np.linalg, c.name, c)
        for _ in range(repeat):
            w0, c0 = time.perf_counter(), time.process_time()
            fit = prepare_fit(ms, sensor, need_range=False, **WINDOW)
            best_wall = min(best_wall, time.perf_counter() - w0)
            best_cpu = min(best_cpu, time.process_time() - c0)
            found = len(fit.screened)
    finally:
        kinematic_fit.screen_pass = saved
        for c in counters:
            setattr(np.linalg, c.name, c.original)
    return best_wall, best_cpu, found, sum(c.calls for c in counters) // repeat


def _reference(path: str | None):
    if path is None:
        return None
    spec = importlib.util.spec_from_file_location("reference_pass_screen", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod.screen_pass


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rows", default="100,400,1000,4000,40000,400000")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--reference", help="another pass_screen.py to time as well")
    ap.add_argument("--reference-max-rows", type=int, default=400)
    args = ap.parse_args()
    sensor = GroundTelescope(measure_range=True)
    truth, span = first_pass(sensor)
    ref = _reference(args.reference)
    for line in machine_lines():
        print(line)
    print(f"first pass {(span[1] - span[0]) * 375190.0 / 3600.0:.1f} h; min of {args.repeat} runs; "
          f"'fits': numpy lstsq + qr calls per screen")
    print(f"{'screen':<10}{'rows':>9}{'outliers':>9}{'wall s':>10}{'CPU s':>10}{'CPU us/row':>11}{'out':>5}{'fits':>6}")
    for rows in (int(r) for r in args.rows.split(",")):
        for outliers in (0, 2):
            ms = measurements(sensor, truth, span, rows, outliers)
            runs = [("this", None)] + ([("reference", ref)] if ref and rows <= args.reference_max_rows else [])
            for label, screen in runs:
                wall, cpu, out, fits = timed(ms, sensor, 1 if label == "reference" else args.repeat, screen)
                print(f"{label:<10}{rows:>9}{outliers:>9}{wall:>10.4f}{cpu:>10.4f}{1e6 * cpu / rows:>11.2f}"
                      f"{out:>5}{fits:>6}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
