"""Built-in maneuver detectors (kind ``maneuver-detector``): ``nis-window`` and ``mixture-likelihood``.

Both run the windowed sequential test of :mod:`cistrack.plugins.maneuvers.sequential` on one
chi-square contribution per update and return as the statistic a surprise, -log10 of a tail
probability (the larger of the window's and the newest update's), against the threshold
-log10(false_alarm) (4 by default). Neither estimates the burn: ``Detection.delta_v`` is None,
``t_burn`` None, and ``t_burn_bounds`` runs from the last update before the window's first
surprising one to the update that fired. Both are deterministic: the same inputs give the same
outputs in every process.

Defaults, measured on healthy runs (issue 52; Example 1, PGM, seeds 201-205, five orbits, 157
updates each, 2 dof): after the first 10 updates the NIS has mean 2.13, 95 % and 99 % quantiles
6.57 and 8.94 (chi-square: 5.99, 9.21), largest 16.9, lag-1 autocorrelation within +-0.1; the
mixture detector's per-update p is below 0.05 at 6.8 % and below 0.01 at 1.0 % of updates. The
first three updates after the IOD have NIS below 0.1 (the prior is still far wider than the
noise), later ones look like the rest. With ``false_alarm = 1e-4`` per test (two tests per
update: 300 updates give at most 6 % of maneuver-free runs an alarm by the union bound) and two
of the window's updates each below ``update_level = 0.01`` required, neither detector fires on
those runs (largest statistic 3.7, threshold 4), and 300-update runs resampled from their
updates raise an alarm in 1.2 % (nis-window) and 0.9 % (mixture-likelihood) of runs (0.1 %
resampling blocks of 10 consecutive updates); one gross outlier (NIS 400) among them fires in
2-3 % of cases. With ``min_surprising = 1`` those become 4.4 % and 1.5 % of runs, and every
gross outlier fires. ``warmup = 5`` skips the collapsing first updates with a margin of two.

On a 1 m/s in-track burn in the gap before a pass (``example-1-burn``, same seeds) the first
update after it has NIS 26-62 in four runs of five, and the PGM, whose prior is wide after the
gap, absorbs much of the burn at once: the next updates may look consistent. Both detectors fire
at the first pass after the burn in two runs, at the next pass (1.5-1.6 days after) in three;
``t_burn_bounds`` holds the burn in four (the look-back of :mod:`.sequential`). With
``min_surprising = 1`` four of five fire at the first update after the burn. A 10 cm/s
station-keeping burn (``example-1-maneuver``) is detected 1.7-2.7 days after it, when the
error has grown; the bounds then start after the burn (no update near it was surprising), so a
burn estimate should search before ``t_burn_bounds[0]`` too.

``window = 5`` (the default; it was 3 in the measurements above): on ``example-1-burn`` seeds
11-16 with no response, both surprising updates of the first pass after the burn fall in one
window in every run, and all six are detected in that pass (3.95-4.28 days, the burn at 3.62);
with ``window = 3`` two of the six waited for the next pass. On maneuver-free Example 1 (seeds
21-60, PGM, 29 updates each) it raised no alarm.
"""
from __future__ import annotations

from cistrack.api import hookimpl
from cistrack.interfaces.component import check_int
from cistrack.model.innovation import innovation

from .predictive_mixture import predictive_mixture, tail_probability
from .sequential import SequentialDetector

__all__ = ["NisWindowDetector", "MixtureLikelihoodDetector"]


class NisWindowDetector(SequentialDetector):
    """Sequential chi-square test on the normalised innovation squared (NIS).

    Per update (one time; several sites' measurements stacked), NIS = nu^T S^-1 nu with m dof,
    nu and S from the prior's particles pushed through the sensor
    (:func:`cistrack.model.innovation.innovation`). The sum over the last ``window`` updates is
    tested against chi2(summed dof) and the newest alone against chi2(m), each at
    ``false_alarm``; a detection also needs ``min_surprising`` of the window's updates each
    beyond their own ``update_level`` quantile.

    Parameters
    ----------
    window : int
        Updates whose NIS are summed (the window test). 5 (one pass of Example 1's schedule)
        integrates a burn's bias over the pass after it, where the PGM absorbs part of the burn
        at the first update and the surprising updates come one or two apart (module docstring).
    false_alarm : float
        Per-test false-alarm probability of the window and single-update tests, in (0, 0.5].
        1e-4: a run of 150-300 updates makes 300-600 tests, so at most 3 % to 6 % of
        maneuver-free runs cross it by the union bound, before ``min_surprising`` removes most
        of those (chance rarely makes two surprising updates in one window): about 1 % of
        runs, measured (module docstring).
    warmup : int
        Updates after :meth:`reset` that are judged but never fire nor enter the window: the
        first updates after the IOD, while the particle cloud still collapses onto the
        measurements (their NIS is near 0 and says nothing about a burn). Call :meth:`reset`
        when the filter restarts from a new cloud, to skip its first updates again.
    min_surprising : int
        A detection needs this many of the window's updates each individually surprising at
        ``update_level``; 2 keeps one gross outlier among good measurements from firing by
        itself (a burn biases later updates too), at the cost of at least one update's delay,
        and of a pass or more where the filter absorbs the burn at its first update after it
        (module docstring). 1 fires on the first gross update. At most ``window``.
    update_level : float
        Per-update tail probability below which an update counts as surprising for
        ``min_surprising``, in [false_alarm, 1]. 0.01: two chance updates of one window below it
        have probability ~3e-4.
    gap_hours : float
        An update at least this many hours after the one before it (the first of a pass) fires
        alone when it is gross (tail probability below ``false_alarm``), whatever
        ``min_surprising`` says: a burn in the gap shows first there, and a filter whose prior is
        wide after the gap may absorb it at once (:mod:`.sequential`). 6 h lies between Example
        1's spacing within a pass (40-60 min) and its gaps between passes (0.6-0.9 d); ``inf``
        turns the rule off. In (0, inf].
    """

    registry_name = "nis-window"  # also when built without the registry: Detection.detector names it

    def __init__(self, window: int = 5, false_alarm: float = 1e-4, warmup: int = 5, min_surprising: int = 2,
                 update_level: float = 0.01, gap_hours: float = 6.0) -> None:
        self._init_test(window, false_alarm, warmup, min_surprising, update_level, gap_hours)

    def _contribution(self, t, prior, group, sensor):
        inn = innovation(prior, group, sensor)
        nis = inn.nis
        return nis, float(len(inn.names)), {"nis": nis, "nis_dof": len(inn.names)}


class MixtureLikelihoodDetector(SequentialDetector):
    """Sequential test on the predictive likelihood of a Gaussian-mixture belief.

    Per update each component of the prior's mixture (the PGM's propagated components; one Gaussian from the
    samples when the belief has no usable mixture) predicts the measurement by the unscented
    transform plus the noise R (:mod:`cistrack.plugins.maneuvers.predictive_mixture`). The
    observed measurement's tail probability p = P(log f(Z) <= log f(z)), Z from the predictive
    mixture f, is the smaller of an analytic upper bound (exact for one component) and a
    seeded Monte Carlo estimate. Each update contributes -2 ln p, chi2(2) for a consistent
    filter, and the last ``window`` are combined by Fisher's method; the per-update surprise
    is -log10 p. Unlike the NIS it judges a multi-modal prior by its modes, not by its one
    moment-matched ellipse.

    Parameters
    ----------
    window : int
        Updates combined by Fisher's method.
    false_alarm : float
        Per-test false-alarm probability of the window and single-update tests, in (0, 0.5]
        (see ``nis-window``).
    warmup : int
        Updates after :meth:`reset` that are judged but never fire nor enter the window (see
        ``nis-window``).
    min_surprising : int
        A detection needs this many of the window's updates each with p < ``update_level``
        (at most ``window``; see ``nis-window``).
    update_level : float
        Per-update p below which an update counts as surprising, in [false_alarm, 1].
    gap_hours : float
        An update at least this many hours after the one before it fires alone when it is gross
        (see ``nis-window``). In (0, inf].
    n_draws : int
        Monte Carlo draws from the predictive mixture per update (0: the analytic bound only).
        2000 resolve p to ~±0.005 at p = 0.05; below ~1/n_draws the analytic bound decides.
    seed : int
        Seeds the Monte Carlo generator together with the update's time, so results repeat in
        any process and do not depend on the order of runs.
    """

    registry_name = "mixture-likelihood"

    def __init__(self, window: int = 5, false_alarm: float = 1e-4, warmup: int = 5, min_surprising: int = 2,
                 update_level: float = 0.01, n_draws: int = 2000, seed: int = 52, gap_hours: float = 6.0) -> None:
        self.n_draws = check_int(self, "n_draws", n_draws, minimum=0, maximum=10_000_000)
        self.seed = check_int(self, "seed", seed, minimum=0)
        self._init_test(window, false_alarm, warmup, min_surprising, update_level, gap_hours)

    def _contribution(self, t, prior, group, sensor):
        weights, means, covs = predictive_mixture(prior, group, sensor)
        log_p, parts = tail_probability(weights, means, covs, self.n_draws, self.seed, t)
        return -2.0 * log_p, 2.0, dict(parts, n_components=int(weights.shape[0]))


@hookimpl
def cistrack_register(registry):
    registry.add("maneuver-detector", "nis-window", NisWindowDetector)
    registry.add("maneuver-detector", "mixture-likelihood", MixtureLikelihoodDetector)
