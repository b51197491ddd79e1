"""The frame a recording shows: the run's synodic frame, or the sensor's Earth-centred inertial one.

``frame = "synodic"`` (default) logs states as the run carries them. ``frame = "inertial"`` maps
every logged state, covariance and body through the sensor's
:meth:`~cistrack.interfaces.Sensor.inertial_frame` (for the real-geometry sensor: GCRS, from the
real Earth-Moon frame of DE421), so the 3-D view shows the orbit as it moves in space. States
stay nondimensional (LU, VU) so the recorder's km conversion applies unchanged.
"""
from __future__ import annotations

import numpy as np

from cistrack.errors import ParameterError
from cistrack.units import KM_SCALE

__all__ = ["VIEW_FRAMES", "ViewFrame"]

VIEW_FRAMES = ("synodic", "inertial")


class ViewFrame:
    """Maps synodic states (N, 6) at a time t (TU) into the recording's frame (N, 6), LU and VU."""

    def __init__(self, name: str, run) -> None:
        self.name = name
        self.inertial = None
        if name == "inertial":
            sensor = getattr(run, "sensor", None)
            frame = sensor.inertial_frame() if sensor is not None else None
            if frame is None:
                raise ParameterError(f"recorder: frame = 'inertial' needs a sensor that places the synodic "
                                     f"frame in inertial space (Sensor.inertial_frame); {sensor!r} does not")
            self.inertial = frame

    @property
    def is_synodic(self) -> bool:
        return self.inertial is None

    def states(self, states: np.ndarray, t) -> np.ndarray:
        """States (N, 6) in the view frame; ``t`` scalar or (N,) TU."""
        s = np.asarray(states, dtype=float).reshape(-1, 6)
        if self.inertial is None or s.shape[0] == 0:
            return s
        tt = np.broadcast_to(np.asarray(t, dtype=float), (s.shape[0],))
        return self.inertial.from_synodic(s, np.ascontiguousarray(tt)) / KM_SCALE

    def positions(self, pos: np.ndarray, t) -> np.ndarray:
        """Positions (N, 3) LU in the view frame (a synodic point at rest)."""
        p = np.asarray(pos, dtype=float).reshape(-1, 3)
        return self.states(np.hstack([p, np.zeros_like(p)]), t)[:, :3]

    def covariances(self, means: np.ndarray, covs: np.ndarray, t: float) -> np.ndarray:
        """Position-velocity covariances (M, 6, 6) carried into the view frame (exact Jacobian)."""
        c = np.asarray(covs, dtype=float)
        if self.inertial is None:
            return c
        out = np.empty_like(c)
        for i, m in enumerate(np.asarray(means, dtype=float)):
            jac = self.inertial.jacobian(m, float(t)) * (KM_SCALE[None, :] / KM_SCALE[:, None])
            out[i] = jac @ c[i] @ jac.T
        return out
