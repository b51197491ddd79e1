"""Re-anchoring after a long gap: batch least squares over every measurement the filter has seen,
started from its own posterior particles that best fit all of them.

After a gap of months the prior cloud is a long, thin, bent filament (the 3:1 NRHO stretches one
direction ~3,600-fold in 150 days), and sequential Gaussian updates of clusters of it keep the
first post-gap pass's posterior honest but wide: on Example 3 the PGM ends that pass 3,000-6,600
km from the truth with a position sigma of ~3,400 km, where the information bound is ~10 km. A
least-squares fit of one trajectory to the pre-gap and post-gap measurements together reaches
the bound, but its cost over the 150-day arc has many local minima and a small basin around the
right one. The PGM's posterior particles lie in that basin often enough to start from:

1. A gap of at least ``gap_days`` between two updates opens a re-anchoring.
2. When the next pause between updates exceeds ``pause_hours`` (the post-gap pass is over) and
   at least ``min_measurements`` updates have come since the gap, every posterior particle is
   scored by the chi-square of all the measurements the filter has conditioned on (one backward
   propagation of the cloud through their times), and the ``starts`` best particles each start a
   Levenberg-Marquardt fit (:func:`cistrack.fit.fit_orbit`) of the state at the last update.
3. A fit is accepted when it converged and its chi-square is at most the 99.9 % point of
   chi-square with (measured components - 6) degrees of freedom. Accepted fits closer than
   chi-square(6) 99 % (16.8) in Mahalanobis distance are one solution (the starts stop once a
   solution has been found twice); the solutions become a Gaussian mixture weighted by their
   Laplace evidence exp(-chi2 / 2) |P|^(1/2). No accepted fit: the belief is left as it is.

The IOD's own measurements are not refitted (the filter never sees them); the information they
carry reaches the fit through the particles that start it. One attempt per gap.
"""
from __future__ import annotations

import warnings

import numpy as np

from cistrack.errors import CistrackError
from cistrack.interfaces import Dynamics, Sensor
from cistrack.model.belief import GaussianMixture
from cistrack.model.measurement import Measurement, MeasurementSet

from .measured_components import MeasuredComponents

__all__ = ["GapReanchor"]

_SAME_SOLUTION_M2 = 16.81  # chi-square(6) 99 %: two fits this close are one solution


def _chi2_limit(dof: int) -> float:
    from scipy.stats import chi2  # on use: scipy.stats is slow to import

    return float(chi2.ppf(0.999, max(dof, 1)))


class GapReanchor:
    """The re-anchoring state of one filter run (see the module docstring).

    Parameters
    ----------
    gap_days : float            a gap between updates at least this long opens a re-anchoring
    pause_hours : float         a pause between updates at least this long ends the post-gap pass
    min_measurements : int      updates since the gap needed before the attempt
    starts : int                most fits started, from the best-fitting posterior particles
    """

    def __init__(self, gap_days: float, pause_hours: float, min_measurements: int, starts: int) -> None:
        from cistrack import units

        self.gap_tu = float(units.days_to_tu(gap_days))
        self.pause_tu = float(units.hours_to_tu(pause_hours))
        self.min_measurements = int(min_measurements)
        self.starts = int(starts)
        self.history: list[Measurement] = []
        self._t_last: float | None = None
        self._since: int | None = None  # updates since the latest gap; None: no re-anchoring open
        self.attempts = 0
        self.solutions = 0

    def observe(self, measurement: Measurement) -> None:
        """Record a measurement the filter is about to condition on."""
        t = float(measurement.t)
        if self._t_last is not None and t - self._t_last >= self.gap_tu:
            self._since = 0
        self._t_last = t
        self.history.append(measurement)
        if self._since is not None:
            self._since += 1

    def due(self, t: float) -> bool:
        """True when a prediction to ``t`` (TU) ends the post-gap pass and an attempt is due."""
        return (self._since is not None and self._since >= self.min_measurements
                and self._t_last is not None and t - self._t_last >= self.pause_tu)

    def _measurement_set(self) -> MeasurementSet | None:
        h = self.history
        names = h[0].names
        if not all(isinstance(m, Measurement) for m in h) or any(m.names != names for m in h) \
                or len({m.t for m in h}) < len(h):
            return None  # mixed components or several sites at one time: not refitted
        return MeasurementSet(np.array([m.t for m in h]), np.array([m.z for m in h]),
                              np.array([np.sqrt(np.diag(m.covariance)) for m in h]), names)

    def _scores(self, x: np.ndarray, t: float, dynamics: Dynamics, sensor: Sensor) -> np.ndarray:
        """Chi-square (N,) of every particle ``x`` (N, 6) at ``t`` over the whole history."""
        times = np.array([m.t for m in self.history])
        chi2 = np.zeros(x.shape[0])
        earlier = np.unique(times[times < t])[::-1]
        states = {t: x}
        if earlier.size:
            prop = dynamics.propagate(x, t, earlier)
            chi2[~np.asarray(prop.alive, dtype=bool)] = np.inf
            states.update({float(tk): prop.states[k] for k, tk in enumerate(earlier)})
        for m in self.history:
            meas = MeasuredComponents(sensor, m)
            d = meas.residuals_to_measurement(states[float(m.t)])
            chi2 += np.einsum("ni,ij,nj->n", d, np.linalg.inv(meas.R), d)
        return np.where(np.isfinite(chi2), chi2, np.inf)

    def attempt(self, x: np.ndarray, t: float, dynamics: Dynamics, sensor: Sensor) -> GaussianMixture | None:
        """Fit from the best of the posterior particles ``x`` (N, 6) at the last update ``t`` (TU);
        the mixture of accepted solutions at ``t`` (LU, VU), or None when no fit is accepted."""
        from cistrack.fit.least_squares import fit_orbit
        from cistrack.fit.options import FitOptions

        self._since = None
        self.attempts += 1
        ms = self._measurement_set()
        if ms is None:
            return None
        scores = self._scores(x, t, dynamics, sensor)
        order = np.argsort(scores)[: self.starts]
        order = order[np.isfinite(scores[order])]
        opts = FitOptions(reject_outliers=False, max_iterations=300, max_damping=1e12)
        limit = _chi2_limit(len(ms) * len(ms.names) - 6)
        kept: list = []
        for i in order:
            try:
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    r = fit_orbit(dynamics, sensor, ms, x[i], t, options=opts)
            except (CistrackError, np.linalg.LinAlgError, FloatingPointError):
                continue
            if not (r.converged and r.chi2 <= limit and np.all(np.isfinite(r.covariance))):
                continue
            same = [k for k in kept if (r.state - k.state) @ np.linalg.solve(k.covariance, r.state - k.state)
                    <= _SAME_SOLUTION_M2]
            if same:
                break  # the same solution from a second start: enough
            kept.append(r)
        if not kept:
            return None
        self.solutions = len(kept)
        logw = np.array([-0.5 * r.chi2 + 0.5 * np.linalg.slogdet(r.covariance)[1] for r in kept])
        w = np.exp(logw - logw.max())
        return GaussianMixture(w / w.sum(), np.array([r.state for r in kept]),
                               np.array([r.covariance for r in kept]))
