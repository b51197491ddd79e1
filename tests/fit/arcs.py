"""Simulated arcs for the fit tests: the 9:2 NRHO observed from the ground every 40 minutes over
~3.3 days, in the CR3BP (``ground-telescope`` az/el, 1.5 arcsec) and in the ephemeris model
(``real-telescope`` astrometric RA/Dec, 0.5 arcsec). Truth states come from the same
``propagate`` call pattern the fit uses (one call from the epoch to all times)."""
from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from cistrack.model.measurement import MeasurementSet
from cistrack.plugin.registry import default_registry
from cistrack.units import hours_to_tu, km_to_lu, kms_to_vu

EPOCH = "2026-01-01T00:00:00Z"
NRHO = np.array([1.0221, 0.0, -0.1821, 0.0, -0.1033, 0.0])
GUESS_OFFSET = np.concatenate([np.full(3, km_to_lu(50.0)), np.full(3, kms_to_vu(5e-4))])
"""Initial-guess error: 50 km per position axis and 0.5 m/s per velocity axis."""


@dataclass(frozen=True)
class Arc:
    dynamics: object
    sensor: object
    truth0: np.ndarray          # (6,) at t = 0
    times: np.ndarray           # (K,) TU
    truth: np.ndarray           # (K, 6)
    exact: MeasurementSet       # noise-free

    def noisy(self, seed: int) -> MeasurementSet:
        rng = np.random.default_rng(seed)
        values = self.exact.values + rng.standard_normal(self.exact.values.shape) * self.exact.sigmas
        return MeasurementSet(self.times, values, self.exact.sigmas, self.exact.names)


def _arc(dyn, sen, x0) -> Arc:
    grid = np.arange(1, 120) * float(hours_to_tu(40.0 / 60.0))
    seen = sen.visible(dyn.propagate(x0[None], 0.0, grid).states[:, 0], grid)
    times = grid[seen]
    truth = dyn.propagate(x0[None], 0.0, times).states[:, 0]
    z = sen.measure(truth, times)
    return Arc(dyn, sen, x0, times, truth, MeasurementSet(times, z, sen.sigmas(truth, times), sen.names))


@lru_cache(maxsize=1)
def cr3bp_arc() -> Arc:
    reg = default_registry()
    return _arc(reg.create("dynamics", "cr3bp"), reg.create("sensor", "ground-telescope", epoch=EPOCH), NRHO)


@lru_cache(maxsize=1)
def ephemeris_arc() -> Arc:
    reg = default_registry()
    dyn = reg.create("dynamics", "ephemeris", epoch=EPOCH)
    sen = reg.create("sensor", "real-telescope", epoch=EPOCH, measurement="radec", sigma_arcsec=0.5)
    x0 = dyn.frame.gcrs_to_synodic(dyn.frame.pulsating_to_gcrs(NRHO, 0.0), 0.0)
    return _arc(dyn, sen, x0)
