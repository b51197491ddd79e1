"""The innovation of a measurement under a belief: what the belief predicts it to be, and how far off it is.

Before each update the prior belief predicts the measurement: its particles pushed through the
sensor give the predicted mean z_hat (circular on angles) and covariance P_zz; with the noise R,
S = P_zz + R and the innovation nu = z - z_hat (angles wrapped),

    NIS = nu^T S^-1 nu  ~  chi^2(m)    for a consistent filter (m measured components).

It lives with the data types so that plugins (maneuver detectors, filters) and the pipeline's
consistency metrics (:mod:`cistrack.evaluation.consistency`, which re-exports it) share one
definition.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["Innovation", "innovation", "MAX_NIS_SAMPLES", "block_diagonal"]

MAX_NIS_SAMPLES = 4000
"""At most this many prior particles (an evenly strided subset) predict the measurement."""


@dataclass(frozen=True)
class Innovation:
    """The innovation of one measurement under a prior belief.

    Attributes
    ----------
    names : (m,) str          measured components (the sensor's names)
    nu : (m,) float           z - z_hat, angles wrapped into [-pi, pi) (rad; ranges LU)
    s : (m, m) float          P_zz + R, the predicted covariance of z
    r : (m, m) float          the measurement noise covariance R
    """

    names: tuple[str, ...]
    nu: np.ndarray
    s: np.ndarray
    r: np.ndarray

    @property
    def nis(self) -> float:
        """nu^T S^-1 nu, chi^2(m) for a consistent filter."""
        return float(self.nu @ np.linalg.solve(self.s, self.nu))


def innovation(prior, measurement, sensor) -> Innovation:
    """The :class:`Innovation` of ``measurement`` (a :class:`cistrack.model.measurement.Measurement`,
    or a sequence of them taken at one time by several sites: stacked, with a block-diagonal
    noise covariance, ``names`` repeating per measurement) under the ``prior`` belief, each
    measurement predicted by ``sensor.for_measurement(measurement)``."""
    group = list(measurement) if isinstance(measurement, (list, tuple)) else [measurement]
    x = np.asarray(prior.samples.states, dtype=float)
    w = prior.samples.weights
    if x.shape[0] > MAX_NIS_SAMPLES:
        step = int(np.ceil(x.shape[0] / MAX_NIS_SAMPLES))
        x = x[::step]
        w = None if w is None else w[::step] / w[::step].sum()
    w = np.full(x.shape[0], 1.0 / x.shape[0]) if w is None else np.asarray(w, dtype=float)
    rs, noises, used = [], [], []
    for m in group:
        own = sensor.for_measurement(m) if hasattr(sensor, "for_measurement") else sensor
        names = tuple(own.names)
        cols = np.array([names.index(n) for n in m.names], dtype=np.intp)
        full_z = np.zeros(len(names))
        full_z[cols] = m.z
        zs = np.asarray(own.measure(x, m.t), dtype=float)
        rs.append(np.asarray(own.residual(zs, full_z[None, :]), dtype=float)[:, cols])  # zs - z, wrapped
        noises.append(np.asarray(m.covariance, dtype=float))
        used += [names[c] for c in cols]
    r = rs[0] if len(rs) == 1 else np.concatenate(rs, axis=1)
    mean_r = w @ r
    d = r - mean_r
    pzz = (d * w[:, None]).T @ d
    noise = noises[0] if len(noises) == 1 else block_diagonal(noises)
    return Innovation(tuple(used), -mean_r, pzz + noise, noise)  # nu = z - z_hat


def block_diagonal(blocks) -> np.ndarray:
    """The block-diagonal matrix of the square ``blocks`` (each (m_i, m_i)): (sum m_i, sum m_i)."""
    n = sum(b.shape[0] for b in blocks)
    out = np.zeros((n, n))
    i = 0
    for b in blocks:
        out[i:i + b.shape[0], i:i + b.shape[0]] = b
        i += b.shape[0]
    return out


_block_diagonal = block_diagonal  # the name cistrack.evaluation.consistency re-exports
