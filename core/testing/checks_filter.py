"""Conformance checks for Filter plugins: initialize / predict / update with a small cloud
around the 9:2 NRHO, the reference CR3BP and the geocentric angles-only fixture sensor."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cistrack.model.belief import Belief, GaussianMixture, ParticleCloud
from cistrack.interfaces.filter import DIAGNOSTICS_RULE, Filter, bad_diagnostic
from cistrack.model.measurement import Measurement
from cistrack.testing.check_support import (close, fresh, no_global_random_state, require, round_trip, unchanged)
from cistrack.testing.fixtures import FIXTURE_SEED, initial_cloud, nrho_truth
from cistrack.testing.reference_dynamics import ReferenceCR3BP
from cistrack.testing.reference_sensor import GeocentricAnglesSensor

__all__ = ["FILTER_CHECKS"]

N_UPDATES = 2
LIFECYCLE_UPDATES = 5
"""Updates of the lifecycle check: a few more than the others make, so that a belief that turns
NaN (or stops moving) after a couple of updates is caught here rather than in a run."""


@dataclass
class _Case:
    cloud: ParticleCloud
    truth_times: np.ndarray
    truth: np.ndarray
    measurements: list[Measurement]
    dynamics: ReferenceCR3BP
    sensor: GeocentricAnglesSensor


def _case(n_updates: int = N_UPDATES) -> _Case:
    cloud, _ = initial_cloud(300)
    times, states = nrho_truth(16)
    sensor = GeocentricAnglesSensor()
    ms = sensor.simulate(states[1:n_updates + 1], times[1:n_updates + 1], np.random.default_rng(FIXTURE_SEED))
    return _Case(cloud, times, states, list(ms), ReferenceCR3BP(), sensor)


def _check_belief(f, epoch: float, when: str) -> Belief:
    b = f.belief
    require(isinstance(b, Belief), f"belief {when} is {type(b).__name__}, not cistrack.model.belief.Belief")
    require(abs(float(b.epoch) - epoch) < 1e-9, f"belief epoch {when} is {b.epoch}, expected {epoch}")
    gm = b.mixture
    require(isinstance(gm, GaussianMixture) and gm.dim == 6, f"belief.mixture {when} must be a 6-dimensional GaussianMixture")
    require(np.all(np.isfinite(gm.means)) and np.all(np.isfinite(gm.covariances)), f"belief.mixture {when} has NaN or infinity")
    require(abs(gm.weights.sum() - 1.0) < 1e-9, f"mixture weights {when} do not sum to 1")
    require(np.allclose(gm.covariances, np.swapaxes(gm.covariances, 1, 2), rtol=1e-8, atol=0),
            f"mixture covariances {when} are not symmetric")
    require(np.all(np.linalg.eigvalsh(gm.covariances) > 0), f"mixture covariances {when} are not positive definite")
    s = b.samples
    require(isinstance(s, ParticleCloud) and s.states.ndim == 2 and s.states.shape[1] == 6 and len(s) >= 1,
            f"belief.samples {when} must be a ParticleCloud of (n, 6) states")
    require(np.all(np.isfinite(s.states)), f"belief.samples {when} contain NaN or infinity")
    _check_diagnostics(f.diagnostics, when)
    return b


def _check_diagnostics(diag, when: str) -> None:
    """A dict with str keys, whose keys of :class:`~cistrack.interfaces.filter.Diagnostics` (counts,
    sizes: the verdict reads them) are finite, non-negative numbers."""
    require(isinstance(diag, dict) and all(isinstance(k, str) for k in diag), f"diagnostics {when} must be a dict with str keys")
    bad = bad_diagnostic(diag)
    require(bad is None, "" if bad is None else f"diagnostics[{bad[0]!r}] {when} is {bad[1]!r}; {DIAGNOSTICS_RULE}")


def _run(f, case: _Case, seed: int = 0, steps: int = N_UPDATES) -> list[tuple[Belief, Belief]]:
    """Initialise, then predict+update ``steps`` times; (prior, posterior) beliefs per step."""
    f.initialize(case.cloud, case.dynamics, case.sensor, np.random.default_rng(seed))
    _check_belief(f, case.cloud.epoch, "after initialize()")
    out = []
    for m in case.measurements[:steps]:
        f.predict(m.t)
        prior = _check_belief(f, m.t, f"after predict({m.t:.4g})")
        f.update(m)
        post = _check_belief(f, m.t, f"after update() at t={m.t:.4g}")
        out.append((prior, post))
    return out


def check_is_filter(f) -> None:
    require(isinstance(f, Filter), f"{type(f).__name__} does not derive from cistrack.interfaces.Filter")


def check_lifecycle_and_belief(f) -> None:
    """initialize, then predict and update :data:`LIFECYCLE_UPDATES` times; the belief is valid
    (epoch, shapes, finite PD covariances) after every call."""
    _run(f, _case(LIFECYCLE_UPDATES), steps=LIFECYCLE_UPDATES)


def _logdet_position(b: Belief) -> float:
    return float(np.linalg.slogdet(b.mixture.covariance[:3, :3])[1])


def check_update_reduces_uncertainty(f) -> None:
    """An angle measurement at 1.5 arcsec shrinks a 100 km position uncertainty."""
    (prior, post), = _run(f, _case(), steps=1)
    drop = _logdet_position(prior) - _logdet_position(post)
    require(drop > 1.0, f"the update changed log det(position covariance) by {-drop:.3g}; a 1.5 arcsec angle "
                        "measurement of a target known to 100 km must shrink it")


def check_prediction_consistent_with_truth(f) -> None:
    """A cloud centred on the truth, predicted 40 minutes, still contains the truth
    (moment-matched NEES of the prior below 50): predict() propagates correctly."""
    case = _case()
    (prior, _), = _run(f, case, steps=1)
    k = int(np.argmin(np.abs(case.truth_times - prior.epoch)))
    e = case.truth[k] - prior.mixture.mean
    nees = float(e @ np.linalg.solve(prior.mixture.covariance, e))
    require(nees < 50.0, f"after predict() the truth is far outside the belief (NEES {nees:.3g}); a cloud centred "
                         "on the truth and propagated 40 minutes must still contain it")


def check_reproducible(f) -> None:
    case = _case()
    g = fresh(f)
    with no_global_random_state("the filter"):
        a = _run(f, case, seed=11)[-1][1]
    b = _run(g, case, seed=11)[-1][1]
    ok, diff = close(a.mixture.mean, b.mixture.mean, 1e-12, 0)
    require(ok, f"two runs with generators of the same seed end with means {diff:.3g} apart")


def check_inputs_not_mutated(f) -> None:
    """The cloud, the measurements, and the dynamics and sensor objects (their attributes) are as
    they were after the filter ran: a run shares them with the truth and the other components."""
    case = _case()
    with unchanged(cloud=case.cloud, measurements=case.measurements, dynamics=case.dynamics, sensor=case.sensor):
        _run(f, case)


def check_picklable_mid_run(f) -> None:
    """A filter pickled after its first update continues exactly like the original."""
    case = _case()
    _run(f, case, seed=13, steps=1)
    g = round_trip(f)
    for h in (f, g):
        m = case.measurements[1]
        h.predict(m.t)
        h.update(m)
    ok, diff = close(f.belief.mixture.mean, g.belief.mixture.mean, 1e-12, 0)
    require(ok, f"the unpickled copy continued differently (means {diff:.3g} apart)")


FILTER_CHECKS = [
    ("is_filter", check_is_filter),
    ("lifecycle_and_belief", check_lifecycle_and_belief),
    ("update_reduces_uncertainty", check_update_reduces_uncertainty),
    ("prediction_consistent_with_truth", check_prediction_consistent_with_truth),
    ("reproducible", check_reproducible),
    ("inputs_not_mutated", check_inputs_not_mutated),
    ("picklable_mid_run", check_picklable_mid_run),
]
