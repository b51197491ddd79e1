"""The idealised synodic frame of the CR3BP and its Earth-centred inertial counterpart.

The synodic frame turns at +1 rad/TU about the inertial z axis, with the Earth at (-mu, 0, 0);
its axes coincide with the Earth-centred inertial (ECI) axes at t = 0. These transforms are the
frame math shared by plugins (Gauss's IOD works in ECI; the sensors' geometry builds on the same
rotation). A real Earth-Moon frame from an ephemeris is a different, richer model.
"""
from __future__ import annotations

import numpy as np

from cistrack.astro.primaries import MU_EARTH_MOON

__all__ = ["rot_z", "synodic_to_eci", "eci_to_synodic"]


def rot_z(angle) -> np.ndarray:
    """Active rotation by ``angle`` (rad) about z: scalar -> (3, 3), (K,) -> (K, 3, 3)."""
    a = np.asarray(angle, dtype=float)
    c, s = np.cos(a), np.sin(a)
    out = np.zeros(a.shape + (3, 3))
    out[..., 0, 0] = c
    out[..., 0, 1] = -s
    out[..., 1, 0] = s
    out[..., 1, 1] = c
    out[..., 2, 2] = 1.0
    return out


def synodic_to_eci(states: np.ndarray, t, mu: float = MU_EARTH_MOON) -> np.ndarray:
    """Synodic states (N, 6) at t (scalar or (N,) TU) -> Earth-centred inertial (N, 6) (LU, VU).

    q = R (r - r_E), q_dot = R (v + omega x (r - r_E)), R = rot_z(t), omega = z,
    r_E = (-mu, 0, 0).
    """
    x = np.atleast_2d(np.asarray(states, dtype=float))
    rot = np.broadcast_to(rot_z(np.asarray(t, dtype=float)), (x.shape[0], 3, 3))
    rel = x[:, :3] - np.array([-mu, 0.0, 0.0])
    w_x_r = np.stack([-rel[:, 1], rel[:, 0], np.zeros(len(rel))], axis=1)
    q = np.einsum("nij,nj->ni", rot, rel)
    qd = np.einsum("nij,nj->ni", rot, x[:, 3:] + w_x_r)
    return np.concatenate([q, qd], axis=1)


def eci_to_synodic(states: np.ndarray, t, mu: float = MU_EARTH_MOON) -> np.ndarray:
    """Inverse of :func:`synodic_to_eci`: ECI (N, 6) at t -> synodic (N, 6);
    v_syn = R^T q_dot - omega x (r_syn - r_E)."""
    x = np.atleast_2d(np.asarray(states, dtype=float))
    rot = np.broadcast_to(rot_z(np.asarray(t, dtype=float)), (x.shape[0], 3, 3))
    rel = np.einsum("nji,nj->ni", rot, x[:, :3])
    v = np.einsum("nji,nj->ni", rot, x[:, 3:])
    w_x_r = np.stack([-rel[:, 1], rel[:, 0], np.zeros(len(rel))], axis=1)
    r = rel + np.array([-mu, 0.0, 0.0])
    return np.concatenate([r, v - w_x_r], axis=1)
