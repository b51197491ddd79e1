"""Responses to a detected maneuver (kind ``maneuver-response``): ``inflate``, ``impulse-samples`` and
``reanchor`` (its refit: :mod:`cistrack.plugins.maneuvers.reanchor`).

Both widen the filter's prior at the detection time t by what an unknown impulsive burn in the
suspect interval [t_a, t] (the detection's ``t_burn_bounds``) can have done: a burn dv at t_b
moves the state at t by Phi(t, t_b)[:, 3:6] dv, with Phi the transition matrix along the prior's
mean (one propagation with transition matrices to :data:`BURN_TIMES` times across the interval).
With dv ~ N(0, sigma^2 I) per axis and t_b uniform over the interval:

- ``inflate`` adds Gaussian process noise of covariance Q = mean over t_b of
  Phi_v sigma^2 Phi_v^T to every particle (process-noise inflation over the suspect interval);
- ``impulse-samples`` gives every particle its own burn: a t_b and a dv drawn, so the cloud carries
  the maneuver hypothesis itself (not Gaussian: a fan of trajectories the PGM's clusters follow).

``reanchor`` does not widen the prior: it refits the measurements since the filter's settled
posterior before the suspect interval with an impulsive burn as solve-for parameters and draws the
cloud from the fit (``inflate``'s when it cannot).

The filter then starts again from the new cloud and takes the measurements that raised the
detection.
"""
from __future__ import annotations

import numpy as np

from cistrack import units
from cistrack.api import hookimpl
from cistrack.interfaces import Dynamics, ManeuverResponse
from cistrack.interfaces.component import check_range
from cistrack.errors import MeasurementError, PropagationError
from cistrack.interfaces.maneuvers import Detection, ResponseHistory
from cistrack.least_squares.errors import FitError
from cistrack.model.belief import Belief, ParticleCloud
from cistrack.plugins.maneuvers import reanchor

__all__ = ["InflateResponse", "ImpulseSamplesResponse", "ReanchorResponse", "BURN_TIMES", "burn_maps"]

BURN_TIMES = 8
"""Burn times across the suspect interval at which the transition matrix is evaluated."""


def burn_maps(detection: Detection, prior: Belief, dynamics: Dynamics) -> np.ndarray:
    """Phi(t, t_b)[:, 3:6] (B, 6, 3) for :data:`BURN_TIMES` burn times t_b spread over the
    detection's suspect interval (its centres), along the prior's mean; (1, 6, 3) of zeros-free
    identity velocity block when the interval is empty."""
    t = float(detection.t)
    lo, hi = detection.t_burn_bounds
    lo = t if not np.isfinite(lo) else min(float(lo), t)
    if t - lo <= 0:
        out = np.zeros((1, 6, 3))
        out[0, 3:6, :] = np.eye(3)
        return out
    tbs = lo + (np.arange(BURN_TIMES) + 0.5) / BURN_TIMES * (t - lo)
    mean = np.asarray(prior.mixture.mean, dtype=float)
    _, back = dynamics.propagate_with_stm(mean, t, tbs[::-1])  # Phi(t_b, t), latest first
    fwd = np.linalg.inv(np.asarray(back, dtype=float)[::-1])    # Phi(t, t_b), in tbs order
    return fwd[:, :, 3:6]


MAX_DELTA_V_SIGMA_MS = 1000.0
"""The largest one-sigma delta-v per axis a response takes, m/s: a belief widened by more leaves
the Earth-Moon system within a day (orbital speeds there are about 1 km/s)."""


def _check_sigma(owner, value) -> float:
    return check_range(owner, "delta_v_sigma_ms", value, 0.0, MAX_DELTA_V_SIGMA_MS, lo_open=True)


class _Widen(ManeuverResponse):
    """Shared: parameters and the cloud."""

    default_name = "inflate"

    def __init__(self, delta_v_sigma_ms: float = 1.0) -> None:
        self.delta_v_sigma_ms = _check_sigma(self, delta_v_sigma_ms)

    def _sigma_vu(self) -> float:
        return float(units.kms_to_vu(self.delta_v_sigma_ms / 1000.0))

    def _cloud(self, detection: Detection, prior: Belief, kicks: np.ndarray) -> ParticleCloud:
        x = np.asarray(prior.samples.states, dtype=float)
        w = prior.samples.weights
        return ParticleCloud(states=x + kicks, epoch=float(detection.t),
                             weights=None if w is None else np.asarray(w, dtype=float).copy())


class InflateResponse(_Widen):
    """Process-noise inflation over the suspect interval: Gaussian noise of the covariance an
    unknown burn in it adds (module docstring).

    Parameters
    ----------
    delta_v_sigma_ms : float
        One sigma per axis of the unknown burn's delta-v, m/s (0 to 1000, above 0; default 1.0).
    """

    default_name = "inflate"

    def respond(self, detection: Detection, prior: Belief, dynamics: Dynamics,
                rng: np.random.Generator) -> ParticleCloud:
        maps = burn_maps(detection, prior, dynamics)
        s2 = self._sigma_vu() ** 2
        q = s2 * np.mean(maps @ np.swapaxes(maps, 1, 2), axis=0)
        n = np.asarray(prior.samples.states).shape[0]
        kicks = rng.multivariate_normal(np.zeros(6), 0.5 * (q + q.T), size=n, method="eigh")
        return self._cloud(detection, prior, kicks)


class ImpulseSamplesResponse(_Widen):
    """A maneuver hypothesis carried by the particles: each draws its own burn time in the suspect
    interval and its own delta-v (module docstring).

    Parameters
    ----------
    delta_v_sigma_ms : float
        One sigma per axis of the drawn delta-v, m/s (0 to 1000, above 0; default 1.0).
    """

    default_name = "impulse-samples"

    def respond(self, detection: Detection, prior: Belief, dynamics: Dynamics,
                rng: np.random.Generator) -> ParticleCloud:
        maps = burn_maps(detection, prior, dynamics)
        n = np.asarray(prior.samples.states).shape[0]
        which = rng.integers(0, maps.shape[0], size=n)
        dv = rng.standard_normal((n, 3)) * self._sigma_vu()
        kicks = np.einsum("nij,nj->ni", maps[which], dv)
        return self._cloud(detection, prior, kicks)


class ReanchorResponse(ManeuverResponse):
    """Re-anchoring by least squares: the measurements since the settled posterior before the
    suspect interval refitted with an impulsive burn, and the filter started again from the fit's
    Gaussians at the detection (:mod:`cistrack.plugins.maneuvers.reanchor`); ``inflate``'s cloud,
    said in the log, when that cannot be done.

    Parameters
    ----------
    delta_v_sigma_ms : float
        One sigma per synodic axis of the burn's delta-v prior (mean zero), m/s (0 to 1000, above 0;
        default 1.0); also the ``inflate`` fallback's.
    """

    default_name = "reanchor"
    needs_history = True

    def __init__(self, delta_v_sigma_ms: float = 1.0) -> None:
        self.delta_v_sigma_ms = _check_sigma(self, delta_v_sigma_ms)

    def respond(self, detection: Detection, prior: Belief, dynamics: Dynamics, rng: np.random.Generator,
                history: ResponseHistory | None = None) -> ParticleCloud:
        """The cloud (N, 6) at ``detection.t`` drawn from the refit (N: the prior's), or
        ``inflate``'s when there is none (no ``history``, no settled posterior, too few
        measurements, or the fit failed); ``detection.extra["reanchor"]`` says which."""
        say = history.say if history is not None else (lambda m: None)
        try:
            anchors = reanchor.refit(detection, dynamics, history, self.delta_v_sigma_ms)
        except (FitError, np.linalg.LinAlgError, PropagationError, MeasurementError) as exc:
            detection.extra["reanchor"] = {"fallback": str(exc)}
            say(f"reanchor: no refit at {units.tu_to_days(detection.t):.3f} d ({exc}); inflating instead")
            return InflateResponse(self.delta_v_sigma_ms).respond(detection, prior, dynamics, rng)
        return reanchor.draw(detection, anchors, np.asarray(prior.samples.states).shape[0], rng, say)


@hookimpl
def cistrack_register(registry):
    """The responses ``inflate``, ``impulse-samples`` and ``reanchor``."""
    registry.add("maneuver-response", "inflate", InflateResponse)
    registry.add("maneuver-response", "impulse-samples", ImpulseSamplesResponse)
    registry.add("maneuver-response", "reanchor", ReanchorResponse)
