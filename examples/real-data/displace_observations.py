"""Displace a share of the observations of an ADES PSV file, to see the fit reject them.

    .venv/bin/python examples/real-data/displace_observations.py IN.psv OUT.psv [--fraction 0.05]
        [--min-arcsec 10] [--max-arcsec 100] [--seed N]

Picks round(fraction x count) observations at random (at least one) and moves each on the sky by
a distance drawn uniformly between --min-arcsec and --max-arcsec in a random direction (RA x
cos(Dec) and Dec), keeping its stated uncertainty; writes OUT.psv and prints the displaced rows'
times. Same seed, same file. docs/real-data.md ("Outliers").
"""
from __future__ import annotations

import argparse
import math
from pathlib import Path

import numpy as np

from cistrack.runs.observation_files import read_observations, write_observations
from cistrack.units import ARCSEC_RAD, format_utc, tu_to_utc, parse_utc

_EPOCH = "2000-01-01T00:00:00Z"


def displace(src: Path, dst: Path, fraction: float = 0.05, lo: float = 10.0, hi: float = 100.0,
             seed: int = 0) -> list[int]:
    """Write ``dst`` with the displaced observations; returns their row indices (time order)."""
    ms = read_observations(src, _EPOCH)
    rng = np.random.default_rng(seed)
    n = max(1, int(round(fraction * len(ms))))
    rows = np.sort(rng.choice(len(ms), size=n, replace=False))
    for i in rows:
        d = rng.uniform(lo, hi) * ARCSEC_RAD
        ang = rng.uniform(0.0, 2.0 * math.pi)
        dec = ms.values[i, 1]
        ms.values[i, 0] = (ms.values[i, 0] + d * math.cos(ang) / math.cos(dec)) % (2.0 * math.pi)
        ms.values[i, 1] = dec + d * math.sin(ang)
    write_observations(dst, ms, _EPOCH, format="ades-psv")
    for i in rows:
        print(f"displaced {format_utc(tu_to_utc(parse_utc(_EPOCH), ms.times[i]))} site {ms.site_at(i)}")
    return [int(i) for i in rows]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("src", type=Path)
    ap.add_argument("dst", type=Path)
    ap.add_argument("--fraction", type=float, default=0.05)
    ap.add_argument("--min-arcsec", type=float, default=10.0)
    ap.add_argument("--max-arcsec", type=float, default=100.0)
    ap.add_argument("--seed", type=int, default=0)
    a = ap.parse_args()
    displace(a.src, a.dst, a.fraction, a.min_arcsec, a.max_arcsec, a.seed)


if __name__ == "__main__":
    main()
