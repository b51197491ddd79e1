"""A run's estimates carried into an Earth-centred inertial frame, for export.

The frame (:class:`~cistrack.astro.inertial_frame.InertialFrame`, re-exported here) is the one a
sensor names through :meth:`cistrack.interfaces.Sensor.inertial_frame`; :func:`to_inertial`
maps the moment-matched means through it and the covariances through its exact Jacobian.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cistrack.astro.inertial_frame import InertialFrame
from cistrack.results.estimates import Estimates
from cistrack.units import KM_SCALE

__all__ = ["InertialFrame", "InertialEstimates", "to_inertial"]


@dataclass
class InertialEstimates:
    """Estimates in an inertial frame: (K,) times and (K, 6) km, km/s states, (K, 6, 6) covariances."""

    frame: InertialFrame
    utc: np.ndarray
    t_tu: np.ndarray
    state_km: np.ndarray
    covariance_km: np.ndarray
    step: np.ndarray
    kind: np.ndarray


def to_inertial(est: Estimates, frame: InertialFrame) -> InertialEstimates:
    """The moment-matched means and covariances of ``est`` in ``frame``."""
    syn = est.mean_km / KM_SCALE
    states = frame.from_synodic(syn, est.t_tu)
    covs = np.empty_like(est.covariance_km)
    for k in range(len(est)):
        j = frame.jacobian(syn[k], est.t_tu[k])
        c = j @ est.covariance_km[k] @ j.T
        covs[k] = 0.5 * (c + c.T)
    return InertialEstimates(frame, est.utc, est.t_tu, states, covs, est.step, est.kind)
