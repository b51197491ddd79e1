"""Re-anchoring: batch least squares over the measurements of an arc, started from the filter's own
posterior particles that fit them best, at the end of a pass.

The PGM's components are kept wider than the data require (the shrinkage that keeps its NEES
honest), and sequential Gaussian updates of clusters do not use everything a whole arc says: their
error at the ends of passes stays several times the information bound (docs/history/pgm.md). A
least-squares fit of one trajectory to every measurement of the arc reaches
the bound, if it starts in the right basin; the posterior particles are the starts:

1. At the end of a pass (the first prediction ``pause_hours`` or more after the last update) that
   brought new measurements, from the arc's second pass on and once ``min_measurements`` have come
   since the latest gap, the posterior particles are
   scored by the chi-square of the arc's measurements (one backward propagation of at most 1,000
   of them, every k-th; after a gap in "across-gaps" mode all of them).
2. The ``starts`` best particles each start a Levenberg-Marquardt fit (:func:`cistrack.least_squares.fit_orbit`)
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
leaves the range ambiguous. In mode "across-gaps" the fit spans the gap, attempted
when the first pass after it is over. After a gap the chi-square valley is long and bent, so
the solution's linearised covariance can miss the truth far along the fit's sharpest direction.
The belief after a gap is therefore each solution's line of variations
(:mod:`cistrack.least_squares.line_of_variations`): least-squares points every half sigma along the weakest
direction out to 4 sigma, each with its covariance on its hyperplane and weighted by its Laplace
evidence; the particles are drawn along the line (:meth:`Reanchoring.draw`), following the bend.
Across a gap the fits' transition matrices use difference steps of 1e-8 (see
:class:`_DifferencedDynamics`). Measurements: docs/history/pgm.md, docs/information-bound.md.

The IOD's own measurements are not refitted (the filter never sees them); their information
reaches the fit through the particles that start it.
"""
from __future__ import annotations

import warnings

import numpy as np

from cistrack.errors import CistrackError
from cistrack.interfaces import Dynamics, Sensor
from cistrack.interfaces.pgm_steps import ReanchorRun
from cistrack.model.belief import GaussianMixture
from cistrack.model.measurement import Measurement, MeasurementSet
from cistrack.numerics.special_functions import chi2_ppf

from ..measured_components import MeasuredComponents
from .measurement_sharpness import measurement_quadratic

__all__ = ["Reanchoring", "REANCHOR_MODES"]

REANCHOR_MODES = ("off", "arcs", "across-gaps")
_PASS_SCORED = 1000  # particles scored at a pass end (all of them after a gap, across-gaps)
_MAX_ITERATIONS = 300  # Example 3's 150-day arcs needed up to ~260 from the best particles
_SAME_SOLUTION_M2 = 16.81  # chi-square(6) 99 %: two fits this close are one solution
_CONTINUATION_STARTS = 4  # starts fitted by continuation when no direct fit is accepted after a gap
_CONTINUATION_SCALES = (1e3, 1e2, 1e1, 1.0)  # noise factors of the pre-gap measurements, stage by stage
_GAP_STM_STEP = 1e-8  # LU, VU: see _DifferencedDynamics
_LOV_STEP = 0.5  # sigmas between the points of the line of variations after a gap
_LOV_MAX_SIGMA = 4.0


def _valley(dynamics: Dynamics, sensor: Sensor, ms: MeasurementSet, fit, opts) -> tuple[list, np.ndarray]:
    """A solution's line of variations: its points and the weakest direction they follow."""
    from cistrack.least_squares.line_of_variations import line_of_variations, weakest_direction

    pts = line_of_variations(dynamics, sensor, ms, fit, step=_LOV_STEP, max_sigma=_LOV_MAX_SIGMA, options=opts)
    return pts, weakest_direction(fit.covariance)


def _valley_mixture(pts: list, v: np.ndarray) -> GaussianMixture:
    """The line as a Gaussian mixture: a component at every point, its covariance on the point's
    hyperplane widened along the line by the spacing, weighted by its Laplace evidence."""
    from cistrack.least_squares.line_of_variations import line_weights

    along = (_LOV_STEP ** 2) * np.outer(v, v)
    return GaussianMixture(line_weights(pts, _LOV_STEP, v), np.array([p.state for p in pts]),
                           np.array([p.covariance + along for p in pts]))


class _DifferencedDynamics:
    """The filter's dynamics with transition matrices by central differences of its own
    ``propagate`` (13 trajectories in one call of the run's compiled kernel): the variational
    kernels the model may also have would be one more compilation on a first run (~17 s on 2
    cores for Example 1). Levenberg-Marquardt only needs the Jacobian approximately; the fixed
    point is the model's own least-squares solution either way.

    Across a months-long gap the default steps (1e-6 LU = 384 m, 1e-6 VU) are too large: the 3:1
    NRHO stretches a displacement 3,585-fold in 150 days, so the perturbed trajectories leave the
    linear regime and the Levenberg-Marquardt iteration stalls short of the minimum (Example 3,
    seeds 3388 and 3389: chi-square 44.1 and 54.3, within the limit, but "not converged" from
    every start). After a gap the steps are 1e-8 (3.8 m, 0.01 mm/s): the same starts converge."""

    def __init__(self, dynamics: Dynamics, step: float | None = None) -> None:
        self._dynamics = dynamics
        self._steps = None if step is None else np.full(6, step)

    def __getattr__(self, name: str):
        return getattr(self._dynamics, name)

    def propagate(self, *args, **kwargs):
        return self._dynamics.propagate(*args, **kwargs)

    def propagate_with_stm(self, state: np.ndarray, t0: float, times) -> tuple[np.ndarray, np.ndarray]:
        from cistrack.interfaces.transition_matrix import stm_by_central_differences

        return stm_by_central_differences(self._dynamics, state, t0, times, steps=self._steps)


def _chi2_limit(dof: int) -> float:
    """The 99.9 % point of chi-square with ``dof`` degrees of freedom (at least 1)."""
    return chi2_ppf(0.999, max(dof, 1))


class Reanchoring(ReanchorRun):
    """The re-anchoring state of one filter run (see the module docstring); made by the ``arcs``
    and ``across-gaps`` components (:mod:`.reanchor_modes`).

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
        self.attempts = 0
        self.solutions = 0
        self._valleys: tuple[np.ndarray, list] | None = None
        self._before_gap = 0  # measurements of the history before the latest gap

    def observe(self, measurement: Measurement) -> None:
        """Record a measurement the filter is about to condition on."""
        t = float(measurement.t)
        if self._t_last is not None and t - self._t_last >= self.gap_tu:
            self._segment, self._passes = 0, 1
            if self.across_gaps:
                self._gap_open = True
                self._before_gap = len(self.history)
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
        from cistrack.least_squares.differential_correction import fit_orbit
        from cistrack.least_squares.options import FitOptions

        after_gap, self._gap_open = self._gap_open, False
        dynamics = _DifferencedDynamics(dynamics, _GAP_STM_STEP if after_gap else None)
        self._new = 0
        self.attempts += 1
        self._valleys = None
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
        if not kept and after_gap:
            kept = self._continued_fits(order, x, t, ms, dynamics, sensor, opts, limit)
        if not kept:
            return None
        self.solutions = len(kept)
        logw = np.array([-0.5 * r.chi2 + 0.5 * np.linalg.slogdet(r.covariance)[1] for r in kept])
        w = np.exp(logw - logw.max())
        w = w / w.sum()
        if not after_gap:
            return GaussianMixture(w, np.array([r.state for r in kept]), np.array([r.covariance for r in kept]))
        valleys = [_valley(dynamics, sensor, ms, r, opts) for r in kept]
        parts = [_valley_mixture(pts, v) for pts, v in valleys]
        self._valleys = (w, valleys)
        return GaussianMixture(np.concatenate([wk * p.weights for wk, p in zip(w, parts)]),
                               np.concatenate([p.means for p in parts]),
                               np.concatenate([p.covariances for p in parts]))

    def _continued_fits(self, order, x, t, ms, dynamics, sensor, opts, limit) -> list:
        """Fits across the gap by continuation, when no direct fit was accepted: the measurements
        before the gap first count with their noise times 1,000, then 100, 10 and 1, each stage
        started from the one before. The first stage is nearly the post-gap arc alone (short and
        well conditioned); each later one moves the solution a little along the valley the
        pre-gap measurements cut, which a direct fit from a particle tens of km off does not
        reach in its iterations."""
        from cistrack.least_squares.differential_correction import fit_orbit

        before = np.arange(len(ms)) < self._before_gap
        for i in order[: _CONTINUATION_STARTS]:
            xi = x[i]
            r = None
            try:
                for scale in _CONTINUATION_SCALES:
                    sig = np.where(before[:, None], ms.sigmas * scale, ms.sigmas)
                    staged = MeasurementSet(ms.times, ms.values, sig, ms.names)
                    with warnings.catch_warnings():
                        warnings.simplefilter("ignore")
                        r = fit_orbit(dynamics, sensor, staged, xi, t, options=opts)
                    xi = r.state
            except (CistrackError, np.linalg.LinAlgError, FloatingPointError):
                continue
            if r.converged and r.chi2 <= limit and np.all(np.isfinite(r.covariance)):
                return [r]
        return []

    def draw(self, n: int, rng: np.random.Generator) -> np.ndarray | None:
        """Particles (n, 6) along the lines of variations of the latest accepted solutions after a
        gap (:func:`cistrack.least_squares.line_of_variations.sample_line`: they follow the bend, which the
        mixture's straight components do not); None when the latest attempt was within an arc."""
        from cistrack.least_squares.line_of_variations import sample_line

        if self._valleys is None:
            return None
        w, valleys = self._valleys
        counts = rng.multinomial(n, w)
        return np.concatenate([sample_line(pts, int(c), rng, _LOV_STEP, v)
                               for c, (pts, v) in zip(counts, valleys) if c > 0])
