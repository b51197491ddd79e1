"""How large a burn the observations of a fit would not show, gap by gap.

A ballistic fit's covariance says nothing of maneuvers: it assumes none. Between two observing
sessions, a burn at time t changes every later observation (or, behind the fit's epoch, every
earlier one); refitting the orbit absorbs part of that change, and the rest raises the fit's
cost by dv^T S(t) dv, where S(t) is the information on the delta-v left once the state is
estimated (the Schur complement of the joint normal matrix of the state and the delta-v,
linearised about the fit, in its weights: the observations' sigmas times the noise scale when it
exceeds 1). A burn that raises it by less than HIDDEN_SIGMAS^2 (9) would not show in the
residuals; the largest such burn, in its worst direction, is HIDDEN_SIGMAS / sqrt(lambda_min(S)).
Each gap reports the largest over :data:`GAP_FRACTIONS` of it: a burn hides best just before the
session after it, or just after the one before (a first version tried five times evenly inside
the gaps and understated the largest tenfold on a probe's survey sets: 21 m/s where the gap's end
hid 201).

The figure is linear and counts every observation the fit used: a burn that shows does move the
fit, which then rejects the observations that show it most, so some larger burns can hide too (on
a probe's set, burns twice and four times a last gap's figure were absorbed, the fit rejecting two
and three of the observations after them). It is a size that hides, not a size beyond which every
burn shows.

Measured on survey sets of objects that burned 0.5 m/s and whose fits saw no burn (unseen seeds
159-160): the gap holding the burn hid burns of 166 and 10 m/s, the other gaps of dro-s159 as
little as 0.03 m/s. A gap followed by one short tracklet hides the most: the fit's predictions
after it hold only if the object did not maneuver there.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cistrack import units
from cistrack.least_squares.impulse_fit import MS_PER_VU, _dv_partials
from cistrack.least_squares.measurement_model import MeasurementModel
from cistrack.least_squares.result import sigma_factor
from cistrack.least_squares.trajectory import arc_states_and_stms
from cistrack.model.measurement import MeasurementSet

__all__ = ["GapSensitivity", "burn_sensitivity", "HIDDEN_SIGMAS", "GAP_FRACTIONS"]

HIDDEN_SIGMAS = 3.0
"""A burn that raises the refitted cost by less than this squared would not show (3 sigma, the size
test a burn the fit reports must pass: :data:`cistrack.fitting.maneuver_search.MIN_BURN_SIGMAS`)."""
GAP_FRACTIONS = (1e-4, 1e-3, 0.01, 0.03, 0.1, 0.2, 0.35, 0.5, 0.65, 0.8, 0.9, 0.97, 0.99, 0.999, 0.9999)
"""Burn times tried in each gap, as fractions of it from the observation before: dense at its ends."""


@dataclass(frozen=True)
class GapSensitivity:
    """One gap between observing sessions.

    start, end : float          TU, the last observation before the gap and the first after it
    largest_hidden_ms : float   m/s, the largest burn inside it that the observations would not
                                show, linearly (worst time and direction; inf: a burn there is
                                not determined at all)
    t_worst : float             TU, the time of that burn
    direction : (3,) float      its direction, a unit vector in the fit's frame (synodic); its
                                sign is arbitrary
    """

    start: float
    end: float
    largest_hidden_ms: float
    t_worst: float
    direction: np.ndarray


def _session_gaps(times: np.ndarray) -> list[tuple[float, float]]:
    """The gaps between observing sessions: the burn search's gaps of at least
    :data:`~cistrack.least_squares.burn_search.NIGHT_GAP_HOURS`."""
    from cistrack.least_squares.burn_search import NIGHT_GAP_HOURS, _gaps

    night = float(units.hours_to_tu(NIGHT_GAP_HOURS))
    return [(a, b) for a, b in _gaps(times, []) if b - a >= night]


def _hidden(q: np.ndarray, a_dv: np.ndarray) -> tuple[float, np.ndarray]:
    """(HIDDEN_SIGMAS / sqrt(lambda_min(S)) in m/s, its eigenvector), S the delta-v's information
    left after the state is estimated: a_dv's part orthogonal to the state's partials (whitened
    rows; ``q`` an orthonormal basis of them), squared."""
    rest = a_dv - q @ (q.T @ a_dv)
    lam, vec = np.linalg.eigh(rest.T @ rest)
    size = float(HIDDEN_SIGMAS / np.sqrt(lam[0]) * MS_PER_VU) if lam[0] > 0.0 else float("inf")
    return size, vec[:, 0]


def burn_sensitivity(fit, dynamics, sensor, measurements: MeasurementSet) -> list[GapSensitivity]:
    """The largest hidden burn of each gap between the observing sessions of ``fit`` (module
    docstring); ``measurements`` are the observations it was fitted to (TU, its rejected rows left
    out here), ``dynamics`` flies its orbit (with the fit's solve-for parameters set, and held
    fixed here) and ``sensor`` predicts them. Empty for one session."""
    used = measurements.subset(~np.asarray(fit.residuals.rejected, dtype=bool))
    gaps = _session_gaps(used.times)
    if not gaps:
        return []
    model = MeasurementModel(sensor, used)
    times = np.asarray(model.times, dtype=float)
    inside = np.array([a + (b - a) * f for a, b in gaps for f in GAP_FRACTIONS])
    states, stms = arc_states_and_stms(dynamics, np.asarray(fit.state, dtype=float), float(fit.epoch),
                                       np.concatenate([times, inside]))
    n = times.size
    scale = sigma_factor(fit.noise_scale)
    h = model.jacobian(states[:n]) / (model.sigmas * scale)[:, :, None]
    q, _ = np.linalg.qr(np.einsum("kmj,kjl->kml", h, stms[:n]).reshape(-1, 6))
    tried = [_hidden(q, _dv_partials(stms[:n], stms[n + k], h, times, float(fit.epoch),
                                           float(tb)).reshape(-1, 3)) for k, tb in enumerate(inside)]
    m, out = len(GAP_FRACTIONS), []
    for g, (a, b) in enumerate(gaps):
        k = g * m + max(range(m), key=lambda j: tried[g * m + j][0])
        out.append(GapSensitivity(a, b, tried[k][0], float(inside[k]), tried[k][1]))
    return out
