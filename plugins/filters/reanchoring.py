"""Re-anchoring: batch least squares over the measurements of an arc, started from the filter's own
posterior particles that fit them best, at the end of a pass.

The PGM's components are kept wider than the data require (the shrinkage that keeps its NEES
honest), and sequential Gaussian updates of clusters do not use everything a whole arc says: on
Example 1 its RMS error at the ends of passes 3-6 was 2.5-4.8 times the information bound (seen
seeds 11600-11629). A least-squares fit of one trajectory to every measurement of the arc reaches
the bound, if it starts in the right basin; the posterior particles are the starts:

1. At the end of a pass (the first prediction ``pause_hours`` or more after the last update) that
   brought new measurements, from the arc's second pass on and once ``min_measurements`` have come
   since the latest gap, the posterior particles are
   scored by the chi-square of the arc's measurements (one backward propagation of at most 1,000
   of them, every k-th; after a gap in "across-gaps" mode all of them).
2. The ``starts`` best particles each start a Levenberg-Marquardt fit (:func:`cistrack.fit.fit_orbit`)
   of the state at the last update; the starts stop once a solution has been found twice.
3. A fit is accepted when it converged, its chi-square is at most the 99.9 % point of chi-square
   with (measured components - 6) degrees of freedom, and its weakest direction is determined to
   better than ``FitOptions.max_weak_sigma_km`` (1,000 km: the first pass of a cislunar arc is
   not). Accepted fits closer than chi-square(6) 99 % (16.8) in Mahalanobis distance are one
   solution; the solutions become a Gaussian mixture weighted by their Laplace evidence
   exp(-chi2 / 2) |P|^(1/2), and the particles are drawn from it. No accepted fit: the filter's
   belief carries on.

An arc ends at a gap of ``gap_days`` or more between updates. In mode "arcs" the next arc starts
afresh (fits never span a gap) and is not fitted before its second pass: a single pass of angles
leaves the range ambiguous (on Example 3, fits to the one night after the gap alone put 3 of 22
runs on a wrong solution ~950 km away). In mode "across-gaps" the fit spans the gap, attempted
when the first pass after it is over, with the particles drawn at the arc's first measurement and propagated
(the linearised covariance at the end of a months-long arc is too narrow where the posterior
bends). Measured: on Example 2 (10-day gap, seen seeds 3000-3029) across-gaps fits ended all 30
runs tracking within 27 km (6 ended 52-70 km off without); on Example 3 (150-day gap) the median
final error fell from 64 to 6 km but 3 of 30 runs ended overconfident (truth 10-12 km away
outside a 4-7 km sigma), so Example 3 does not use it (docs/information-bound.md).

The IOD's own measurements are not refitted (the filter never sees them); their information
reaches the fit through the particles that start it.
"""
from __future__ import annotations

import warnings

import numpy as np

from cistrack.errors import CistrackError
from cistrack.interfaces import Dynamics, Sensor
from cistrack.model.belief import GaussianMixture
from cistrack.model.measurement import Measurement, MeasurementSet

from .measured_components import MeasuredComponents
from .measurement_sharpness import measurement_quadratic

__all__ = ["Reanchoring", "REANCHOR_MODES"]

REANCHOR_MODES = ("off", "arcs", "across-gaps")
_PASS_SCORED = 1000  # particles scored at a pass end (all of them after a gap, across-gaps)
_MAX_ITERATIONS = 300  # Example 3's 150-day arcs needed up to ~260 from the best particles
_SAME_SOLUTION_M2 = 16.81  # chi-square(6) 99 %: two fits this close are one solution


class _DifferencedDynamics:
    """The filter's dynamics with transition matrices by central differences of its own
    ``propagate`` (13 trajectories in one call of the run's compiled kernel): the variational
    kernels the model may also have would be one more compilation on a first run (~17 s on 2
    cores for Example 1). Levenberg-Marquardt only needs the Jacobian approximately; the fixed
    point is the model's own least-squares solution either way."""

    def __init__(self, dynamics: Dynamics) -> None:
        self._dynamics = dynamics

    def __getattr__(self, name: str):
        return getattr(self._dynamics, name)

    def propagate(self, *args, **kwargs):
        return self._dynamics.propagate(*args, **kwargs)

    def propagate_with_stm(self, state: np.ndarray, t0: float, times) -> tuple[np.ndarray, np.ndarray]:
        from cistrack.interfaces.transition_matrix import stm_by_central_differences

        return stm_by_central_differences(self._dynamics, state, t0, times)


def _chi2_limit(dof: int) -> float:
    """The 99.9 % point of chi-square with ``dof`` degrees of freedom (scipy.special: scipy.stats
    costs a second to import)."""
    from scipy.special import gammaincinv

    return float(2.0 * gammaincinv(0.5 * max(dof, 1), 0.999))


class Reanchoring:
    """The re-anchoring state of one filter run (see the module docstring).

    Parameters
    ----------
    mode : str                  "arcs" or "across-gaps" (see the module docstring)
    gap_days : float            a gap between updates at least this long ends an arc
    pause_hours : float         a pause between updates at least this long ends a pass
    min_measurements : int      measurements the arc needs before an attempt
    starts : int                most fits started, from the best-fitting posterior particles
    """

    def __init__(self, mode: str, gap_days: float, pause_hours: float, min_measurements: int,
                 starts: int) -> None:
        from cistrack import units

        self.across_gaps = mode == "across-gaps"
        self.gap_tu = float(units.days_to_tu(gap_days))
        self.pause_tu = float(units.hours_to_tu(pause_hours))
        self.min_measurements = int(min_measurements)
        self.starts = int(starts)
        self.history: list[Measurement] = []
        self._t_last: float | None = None
        self._new = 0  # updates since the latest attempt
        self._segment = 0  # updates since the latest gap (or the start)
        self._passes = 1  # passes since the latest gap (or the start), the current one included
        self._gap_open = False  # a gap has come since the latest attempt
        self._draw_from: tuple[float, GaussianMixture] | None = None
        self.attempts = 0
        self.solutions = 0

    def observe(self, measurement: Measurement) -> None:
        """Record a measurement the filter is about to condition on."""
        t = float(measurement.t)
        if self._t_last is not None and t - self._t_last >= self.gap_tu:
            self._segment, self._passes = 0, 1
            if self.across_gaps:
                self._gap_open = True
            else:
                self.history = []  # a new arc
        elif self._t_last is not None and t - self._t_last >= self.pause_tu:
            self._passes += 1
        self._t_last = t
        self.history.append(measurement)
        self._new += 1
        self._segment += 1

    def due(self, t: float) -> bool:
        """True when a prediction to ``t`` (TU) ends a pass and an attempt is due: new measurements,
        ``min_measurements`` since the latest gap, and either a second pass since it or (across
        gaps) an arc before it to anchor the fit."""
        anchored = self._passes >= 2 or (self.across_gaps and self._gap_open)
        return (anchored and self._segment >= self.min_measurements and self._new > 0
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
            chi2 += measurement_quadratic(d, meas.R)
        return np.where(np.isfinite(chi2), chi2, np.inf)

    def attempt(self, x: np.ndarray, t: float, dynamics: Dynamics, sensor: Sensor) -> GaussianMixture | None:
        """Fit from the best of the posterior particles ``x`` (N, 6) at the last update ``t`` (TU);
        the mixture of accepted solutions at ``t`` (LU, VU), or None when no fit is accepted."""
        from cistrack.fit.least_squares import fit_orbit
        from cistrack.fit.options import FitOptions

        dynamics = _DifferencedDynamics(dynamics)
        after_gap, self._gap_open = self._gap_open, False
        self._new = 0
        self.attempts += 1
        ms = self._measurement_set()
        if ms is None:
            return None
        if not after_gap and x.shape[0] > _PASS_SCORED:  # a compact posterior: a thousand starts suffice
            x = x[:: -(-x.shape[0] // _PASS_SCORED)]
        scores = self._scores(x, t, dynamics, sensor)
        order = np.argsort(scores)[: self.starts]
        order = order[np.isfinite(scores[order])]
        opts = FitOptions(reject_outliers=False, max_iterations=_MAX_ITERATIONS, max_damping=1e12)
        limit = _chi2_limit(len(ms) * len(ms.names) - 6)
        kept: list = []
        for i in order:
            try:
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    r = fit_orbit(dynamics, sensor, ms, x[i], t, options=opts)
            except (CistrackError, np.linalg.LinAlgError, FloatingPointError):
                continue
            weak_km = float(np.linalg.norm(r.weakest_direction_km[:3]))
            if weak_km > opts.max_weak_sigma_km:
                break  # the arc leaves a direction undetermined, whatever the start
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
        mix = GaussianMixture(w / w.sum(), np.array([r.state for r in kept]), np.array([r.covariance for r in kept]))
        self._draw_from = None
        if after_gap:  # the same solutions at the arc's first measurement, where they are Gaussian
            t0 = float(ms.times[0])
            at0 = []
            for r in kept:
                x0 = dynamics.propagate(r.state[None], t, np.array([t0])).states[-1][0]
                try:
                    with warnings.catch_warnings():
                        warnings.simplefilter("ignore")
                        at0.append(fit_orbit(dynamics, sensor, ms, x0, t0, options=opts))
                except (CistrackError, np.linalg.LinAlgError, FloatingPointError):
                    break
            if len(at0) == len(kept) and all(np.all(np.isfinite(r.covariance)) for r in at0):
                self._draw_from = (t0, GaussianMixture(mix.weights, np.array([r.state for r in at0]),
                                                       np.array([r.covariance for r in at0])))
        return mix

    def draw(self, mix: GaussianMixture, t: float, n: int, rng: np.random.Generator,
             dynamics: Dynamics) -> np.ndarray | None:
        """Particles (<= n, 6) at ``t`` from the latest accepted solutions ``mix``: after a gap drawn
        at the arc's first measurement and propagated to ``t`` (the linearised covariance at ``t``
        is too narrow there: the posterior is bent by the months-long propagation); None: draw from
        ``mix`` at ``t``."""
        if self._draw_from is None:
            return None
        t0, mix0 = self._draw_from
        x0, _ = mix0.sample(n, rng)
        prop = dynamics.propagate(x0, t0, np.array([t]))
        alive = np.asarray(prop.alive, dtype=bool)
        return np.array(prop.states[-1][alive], dtype=float) if alive.any() else None
