"""Observations of an object that made an impulsive burn: the 14-day three-site campaign of
:func:`arc_campaigns.two_weeks` (9:2 NRHO, ephemeris dynamics, MPC 711, 809, 568), its first
``days`` days, the truth flown with one burn of ``dv_ms`` along the velocity at ``t_burn_days``
(:class:`cistrack.propagation.impulses.ImpulsiveDynamics`), measured with the campaign's noise."""
from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from .arc_campaigns import two_weeks
from cistrack import units
from cistrack.interfaces.maneuvers import Impulse
from cistrack.least_squares.measurement_model import MeasurementModel
from cistrack.least_squares.trajectory import arc_states
from cistrack.model.measurement import MeasurementSet
from cistrack.propagation.impulses import ImpulsiveDynamics


@dataclass(frozen=True)
class Burned:
    measurements: MeasurementSet
    dynamics: object          # the ballistic model (the fit's)
    sensor: object
    truth_dynamics: object    # the model with the burn
    x0: np.ndarray            # truth at t = 0 (LU, VU)
    t_burn: float             # TU
    dv_ms: np.ndarray         # (3,) synodic m/s


@lru_cache(maxsize=4)
def burned(dv_ms: float, t_burn_days: float = 3.4, days: float = 8.0, seed: int = 5) -> Burned:
    c = two_weeks()
    ms = c.measurements.subset(c.measurements.times <= units.days_to_tu(days))
    x0 = np.asarray(c.truth_at(np.array([0.0]))[0], dtype=float)
    tb = float(units.days_to_tu(t_burn_days))
    xb = c.dynamics.propagate(x0[None], 0.0, np.array([tb])).states[0, 0]
    dv = xb[3:] / np.linalg.norm(xb[3:]) * dv_ms
    truth = ImpulsiveDynamics(c.dynamics, [Impulse(tb, dv / (units.vu_to_kms(1.0) * 1000.0), "burn")])
    model = MeasurementModel(c.sensor, ms)
    noise = np.random.default_rng(seed).standard_normal(ms.values.shape) * ms.sigmas
    z = model.predict(arc_states(truth, x0, 0.0, ms.times)) + noise
    out = MeasurementSet(ms.times, z, ms.sigmas, ms.names, dict(ms.meta), ms.sites, ms.kinds, dict(ms.site_table))
    return Burned(out, c.dynamics, c.sensor, truth, x0, tb, dv)


def truth_state(b: Burned, t: float) -> np.ndarray:
    """The truth (6,) at ``t`` TU."""
    return arc_states(b.truth_dynamics, b.x0, 0.0, np.array([t]))[0]
