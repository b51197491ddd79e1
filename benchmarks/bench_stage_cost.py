"""Cost of one lockstep integrator step's stages, per lane, by model (not a test).

    .venv/bin/python benchmarks/bench_stage_cost.py [--steps 20000] [--repeats 5]

Calls the generated ``_lanes_step`` (12 stage functions and the error estimate, no driver) of
each model's SIMD-lockstep kernel from compiled code ``--steps`` times on one lane batch, and
prints nanoseconds per lane and step (best of ``--repeats``): the CR3BP; the CR3BP plus a table
read keyed by time (``k: LaneUniform``, the table holding zeros, so that the difference is the
keyed stage's own cost); the ephemeris model (its default right-hand side,
``ephemeris_point_mass_rhs``, and with Earth J2 on, ``ephemeris_rhs``); and the default ephemeris
right-hand side with its record fixed and every coefficient a literal constant (written from the
model's own source at run time, into a temporary module): no table at all, the arithmetic
alone. With the integrator's scalar work per step (step control, impact test,
output) added, these make ``bench_ephemeris.py``'s per-particle-period figures. Prints the machine.
"""
from __future__ import annotations

import argparse
import importlib
import inspect
import os
import re
import sys
import tempfile
import time

import numpy as np

sys.path.insert(0, os.path.dirname(__file__))

from cistrack.lazy import lazy_njit  # noqa: E402
from cistrack.plugins.dynamics.cr3bp import CR3BP  # noqa: E402
from cistrack.propagation.lane_rhs import LaneUniform  # noqa: E402


@lazy_njit(cache=False)
def keyed_cr3bp_rhs(t, y, p, out):
    """CR3BP plus a table entry (zero) read by the time's record: p = [mu, 1/width, table...].

    cr3bp_rhs's lines written out again on purpose: calling it (passing ``y`` and ``out`` to
    another function) would make the lane rewriter refuse this body, and the benchmark would then
    time the one-particle kernel instead of the keyed lockstep stages it is for."""
    k: LaneUniform = min(max(int(np.floor(t * p[1])), 0), 1000)
    c0 = p[2 + k]
    mu = p[0]
    x = y[0]
    yy = y[1]
    z = y[2]
    vx = y[3]
    vy = y[4]
    xe = x + mu
    xm = x - 1.0 + mu
    yz2 = yy * yy + z * z
    r1s = xe * xe + yz2
    r2s = xm * xm + yz2
    c1 = (1.0 - mu) / (r1s * np.sqrt(r1s))
    c2 = mu / (r2s * np.sqrt(r2s))
    cs = c1 + c2
    out[0] = vx
    out[1] = vy
    out[2] = y[5]
    out[3] = x + 2.0 * vy - c1 * xe - c2 * xm + c0
    out[4] = yy - 2.0 * vx - cs * yy
    out[5] = -cs * z


class KeyedCR3BP(CR3BP):
    rhs = keyed_cr3bp_rhs

    def params_vector(self) -> np.ndarray:
        return np.concatenate([[self.mu, 4.0], np.zeros(1002)])


_KEY = "    k: LaneRecord = min(max(int(np.floor(v)), 0), nrec - 1)\n"


def literal_coefficients(directory: str, record: int):
    """Module (written to ``directory``) with ``literal_coefficients_rhs``: the model's
    ``ephemeris_point_mass_rhs`` with its record fixed to ``record`` and every coefficient load
    ``p[j + c]`` replaced by a literal constant (one per column ``c``)."""
    from cistrack.plugins.dynamics import ephemeris_rhs as model
    from cistrack.plugins.dynamics.ephemeris_point_mass_rhs import ephemeris_point_mass_rhs

    text = inspect.getsource(ephemeris_point_mass_rhs.py_func)
    if _KEY not in text:
        raise RuntimeError("bench_stage_cost: the record statement changed; update _KEY")
    text = text.replace("def ephemeris_point_mass_rhs", "def literal_coefficients_rhs")
    text = re.sub(r"p\[j( \+ (\d))?\]", lambda m: f"COEF_{m.group(2) or 0}",
                  text.replace(_KEY, "    k = FIXED_RECORD\n"))
    names = ", ".join(n for n in model.__all__ if n.isupper()) + ", GM_E, GM_M, GM_S, EARTH_SHARE"
    head = ["import numpy as np", "from cistrack.lazy import lazy_njit",
            f"from cistrack.plugins.dynamics.ephemeris_rhs import {names}", f"FIXED_RECORD = {int(record)}"]
    head += [f"COEF_{c} = {1e-3 * (c + 1)!r}" for c in range(6)]
    name = f"stage_cost_literal_{os.getpid()}"
    with open(os.path.join(directory, name + ".py"), "w") as f:
        f.write("\n".join(head) + "\n\n\n" + text.replace("@lazy_njit(cache=True)", "@lazy_njit(cache=False)"))
    sys.path.insert(0, directory)
    return importlib.import_module(name)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, default=20_000)
    ap.add_argument("--repeats", type=int, default=5)
    args = ap.parse_args(argv)

    from numba import njit

    from machine import machine_lines
    from cistrack.plugins.dynamics.ephemeris import EphemerisDynamics
    from cistrack.plugins.dynamics.ephemeris_rhs import SERIES_HDR
    from cistrack.plugins.dynamics.orbit_catalog import ORBITS

    @njit
    def loop(step, w, p, n):
        for _ in range(n):
            step(w, p, 1e-12, 2e-11)

    orbit = ORBITS["nrho-9-2"]
    ephemeris = EphemerisDynamics(epoch="2026-01-01T00:00:00Z")
    ephemeris._ensure_window(0.0, 2.0)
    p = ephemeris._params()
    record = int(np.floor((0.5 - p[SERIES_HDR]) * p[SERIES_HDR + 1]))  # the lanes' record at t = 0.5
    tmp = tempfile.TemporaryDirectory()
    literal = literal_coefficients(tmp.name, record)
    models = {"cr3bp": CR3BP(), "cr3bp + keyed table read": KeyedCR3BP(), "ephemeris": ephemeris,
              "ephemeris + J2": EphemerisDynamics(epoch=ephemeris.epoch, j2=True),
              "ephemeris, literal coefficients": type("Literal", (EphemerisDynamics,),
                                                      {"rhs": literal.literal_coefficients_rhs,
                                                       "_rhs": lambda self: type(self).rhs})(epoch=ephemeris.epoch)}
    for line in machine_lines():
        print(f"# {line}")
    print(f"{'model':<33}{'lanes':>6}{'ns per lane-step':>18}{'per lane-stage':>16}")
    for name, m in models.items():
        if isinstance(m, EphemerisDynamics):
            m._ensure_window(0.0, 2.0)
            x = m.to_inertial(orbit.state[None], 0.5)[0]
        else:
            x = orbit.state
        mod = m._kernels()
        lanes = mod.LANES
        w = np.zeros(mod.ROWS * lanes)
        for j in range(6):
            w[(mod.ROW_Y + j) * lanes:(mod.ROW_Y + j + 1) * lanes] = x[j]
        w[mod.ROW_T * lanes:(mod.ROW_T + 1) * lanes] = 0.5
        w[mod.ROW_H * lanes:(mod.ROW_H + 1) * lanes] = 0.01
        p = m._params()
        loop(mod._lanes_step, w, p, 10)
        best = np.inf
        for _ in range(args.repeats):
            t = time.perf_counter()
            loop(mod._lanes_step, w, p, args.steps)
            best = min(best, time.perf_counter() - t)
        ns = best / args.steps / lanes * 1e9
        print(f"{name:<33}{lanes:>6}{ns:>18.1f}{ns / 12:>16.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
