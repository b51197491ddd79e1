"""Conformance checks for maneuver detectors (kind ``maneuver-detector``).

The checks feed the detector a linear-Gaussian problem whose answer is known: a sensor that
measures the x and y position directly (1-sigma 20 km), and before each update a fresh prior,
N(truth + error, P) with the error drawn from P itself (400 particles whose mean and covariance
are exactly the prior's, and a one-component mixture). The innovation is then exactly
N(0, H P H^T + R): a consistent filter. Every fourth update stacks two measurements taken at one
time (two sites, independent noise). A burn is simulated as a step: from one update on, every
measurement is offset by 20 innovation sigmas in x.

A detector that declares its per-test false-alarm probability as ``false_alarm`` is held to
twice it per update (two tests per update, by the union bound); one that does not, to 1 %. A
step is placed ``30 + warmup`` updates in (``warmup`` read from the detector, 0 when absent).
"""
from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np

from cistrack.interfaces.maneuvers import Detection, ManeuverDetector
from cistrack.interfaces.schedule import Pass
from cistrack.interfaces.sensor import Sensor
from cistrack.model.belief import Belief, GaussianMixture, ParticleCloud
from cistrack.model.measurement import Measurement, MeasurementSet
from cistrack.testing.check_support import fresh, no_global_random_state, require, unchanged
from cistrack.testing.fixtures import NRHO_9_2_APOLUNE
from cistrack.units import km_to_lu, kms_to_vu

__all__ = ["MANEUVER_DETECTOR_CHECKS", "PlanePositionSensor", "linear_gaussian_updates"]

_SIGMA_Z = float(km_to_lu(20.0))
_P_SIGMAS = np.array([km_to_lu(60.0)] * 3 + [kms_to_vu(1e-4)] * 3, dtype=float)
_DT = 0.01
_STEP_SIGMAS = 20.0
_N_PARTICLES = 400


class PlanePositionSensor(Sensor):
    """Measures a state's synodic x and y directly (LU), 1-sigma ``sigma_lu`` each: the linear
    sensor of the maneuver-detector checks. It is not registered as a plugin."""

    names = ("x", "y")
    angular = (False, False)

    def __init__(self, sigma_lu: float = _SIGMA_Z) -> None:
        self.sigma_lu = float(sigma_lu)

    def measure(self, states: np.ndarray, t) -> np.ndarray:
        return np.atleast_2d(np.asarray(states, dtype=float))[:, :2].copy()

    def sigmas(self, states: np.ndarray, t) -> np.ndarray:
        return np.full((np.atleast_2d(states).shape[0], 2), self.sigma_lu)

    def visible(self, states: np.ndarray, t) -> np.ndarray:
        return np.ones(np.atleast_2d(states).shape[0], dtype=bool)

    def observer_position(self, t) -> np.ndarray:
        t = np.asarray(t, dtype=float)
        return np.zeros(t.shape + (3,))

    def line_of_sight(self, angles: np.ndarray, t) -> np.ndarray:
        a = np.atleast_2d(np.asarray(angles, dtype=float))
        return np.stack([np.cos(a[:, 1]) * np.cos(a[:, 0]), np.cos(a[:, 1]) * np.sin(a[:, 0]), np.sin(a[:, 1])], axis=1)

    def passes(self, times: np.ndarray, states: np.ndarray) -> list[Pass]:
        times = np.asarray(times, dtype=float)
        return [Pass(float(times[0]), float(times[-1]))] if times.size else []

    def simulate(self, states: np.ndarray, times: np.ndarray, rng: np.random.Generator) -> MeasurementSet:
        z = self.measure(states, times)
        return MeasurementSet(times, z + self.sigma_lu * rng.standard_normal(z.shape), np.full(z.shape, self.sigma_lu),
                              self.names)


def _unit_cloud(n: int, rng: np.random.Generator) -> np.ndarray:
    """(n, 6) points with mean exactly 0 and (1/n-normalised) covariance exactly I."""
    g = rng.standard_normal((n, 6))
    g -= g.mean(axis=0)
    chol = np.linalg.cholesky(g.T @ g / n)
    return np.linalg.solve(chol, g.T).T


def linear_gaussian_updates(n: int, seed: int, step_at: int | None = None,
                            step_sigmas: float = _STEP_SIGMAS) -> SimpleNamespace:
    """``n`` updates of the linear-Gaussian problem (module docstring): ``times`` (n,), ``priors``
    (Belief each), ``groups`` (list of Measurement each), ``sensor``, ``sigma_x`` (the innovation's
    1-sigma in x, LU); from update ``step_at`` on the measurements are offset by ``step_sigmas``
    of those sigmas in x."""
    rng = np.random.default_rng(seed)
    cov = np.diag(_P_SIGMAS ** 2)
    unit = _unit_cloud(_N_PARTICLES, rng)
    s_x = math.sqrt(cov[0, 0] + _SIGMA_Z ** 2)
    r = np.eye(2) * _SIGMA_Z ** 2
    times = 1.0 + _DT * np.arange(n)
    priors, groups = [], []
    for k, t in enumerate(times):
        truth = NRHO_9_2_APOLUNE + _P_SIGMAS * rng.standard_normal(6) * 10.0
        mean = truth + _P_SIGMAS * rng.standard_normal(6)
        priors.append(Belief(float(t), GaussianMixture(np.ones(1), mean[None], cov[None]),
                             ParticleCloud(mean + unit * _P_SIGMAS, float(t))))
        offset = np.array([step_sigmas * s_x, 0.0]) if step_at is not None and k >= step_at else np.zeros(2)
        n_meas = 2 if k % 4 == 3 else 1
        groups.append([Measurement(float(t), truth[:2] + offset + _SIGMA_Z * rng.standard_normal(2), r.copy(),
                                   ("x", "y"), k, f"site{j}") for j in range(n_meas)])
    return SimpleNamespace(times=times, priors=priors, groups=groups, sensor=PlanePositionSensor(), sigma_x=s_x)


def _warmup(c) -> int:
    w = getattr(c, "warmup", 0)
    return int(w) if isinstance(w, (int, np.integer)) and 0 <= w <= 1000 else 0


def _run(c, seq) -> list[tuple[float, Detection | None]]:
    out = []
    for t, prior, group in zip(seq.times, seq.priors, seq.groups):
        out.append(c.observe(float(t), prior, group, seq.sensor))
    return out


def _outcome_key(result: tuple[float, Detection | None]) -> tuple:
    stat, det = result
    if det is None:
        return (float(stat), None)
    return (float(stat), det.t, det.statistic, det.threshold, tuple(det.t_burn_bounds))


def _same(a, b) -> bool:
    """``a == b`` for outcome keys, with NaN equal to NaN (a detector giving NaN twice is not
    nondeterministic: that NaN is refused by the observe check)."""
    if isinstance(a, tuple) and isinstance(b, tuple):
        return len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b))
    if isinstance(a, float) and isinstance(b, float) and math.isnan(a) and math.isnan(b):
        return True
    return a == b


def _plain(bounds) -> str:
    """``t_burn_bounds`` as plain numbers: ``(6.35, 11.35)``, never ``np.float64(...)``."""
    try:
        return "(" + ", ".join(repr(float(v)) for v in bounds) + ")"
    except (TypeError, ValueError):
        return repr(bounds)


def _step_sequence(c, seed: int = 11) -> tuple[SimpleNamespace, int]:
    step_at = 30 + _warmup(c)
    return linear_gaussian_updates(step_at + 10, seed, step_at), step_at


def check_is_maneuver_detector(c) -> None:
    require(isinstance(c, ManeuverDetector), f"{type(c).__name__} does not derive from "
            "cistrack.interfaces.maneuvers.ManeuverDetector")


def _check_detection(det, t: float, t_first: float) -> None:
    require(isinstance(det, Detection), f"observe() returned {type(det).__name__} as its detection; "
            "expected a cistrack.interfaces.maneuvers.Detection or None")
    require(det.t == t, f"the detection's t = {det.t!r} is not the time of the update that raised it ({t!r})")
    require(math.isfinite(det.statistic) and math.isfinite(det.threshold),
            f"the detection's statistic {det.statistic!r} and threshold {det.threshold!r} must be finite")
    lo, hi = (float(v) for v in det.t_burn_bounds)
    require(math.isfinite(lo) and math.isfinite(hi) and t_first <= lo <= hi <= t,
            f"t_burn_bounds {_plain(det.t_burn_bounds)} must be finite and lie within [an earlier update's time, t] = "
            f"[{float(t_first)!r}, {float(t)!r}]")
    require(det.delta_v is None or np.shape(det.delta_v) == (3,), f"delta_v must be None or (3,), got {np.shape(det.delta_v)}")


def check_observe_returns_a_statistic_and_a_detection_or_none(c) -> None:
    """On a sequence with a burn: a finite float each update; each detection well formed, its
    ``t_burn_bounds`` within [an earlier update's time, t]; inputs unchanged; no global randomness."""
    seq, _ = _step_sequence(c)
    c.reset()
    for i, (t, prior, group) in enumerate(zip(seq.times, seq.priors, seq.groups)):
        with no_global_random_state("observe"), unchanged(states=prior.samples.states, means=prior.mixture.means,
                                                         covariances=prior.mixture.covariances, measurements=group):
            out = c.observe(float(t), prior, group, seq.sensor)
        require(isinstance(out, tuple) and len(out) == 2, f"observe() must return (statistic, detection or None), got {out!r}")
        stat, det = out
        require(isinstance(stat, (float, np.floating)) and math.isfinite(stat),
                f"update {i}: the statistic {stat!r} is not a finite float")
        if det is not None:
            _check_detection(det, float(t), float(seq.times[0]))


def check_deterministic(c) -> None:
    """Two fresh instances give the same statistics and detections for the same inputs."""
    seq, _ = _step_sequence(c)
    other = fresh(c)
    c.reset()
    other.reset()
    a = [_outcome_key(r) for r in _run(c, seq)]
    b = [_outcome_key(r) for r in _run(other, seq)]
    diff = next((i for i, (x, y) in enumerate(zip(a, b)) if not _same(x, y)), None)
    require(diff is None, f"two instances with the same parameters differ at update {diff}: {a[diff] if diff is not None else ''} "
            f"vs {b[diff] if diff is not None else ''}; derive any randomness from a seed parameter and the inputs")


def check_reset_forgets(c) -> None:
    """After ``reset()`` an instance that saw another run answers as a fresh one."""
    seq, _ = _step_sequence(c)
    first = linear_gaussian_updates(len(seq.times), 5, step_at=len(seq.times) // 2)
    c.reset()
    _run(c, first)
    c.reset()
    again = [_outcome_key(r) for r in _run(c, seq)]
    new = fresh(c)
    new.reset()
    want = [_outcome_key(r) for r in _run(new, seq)]
    require(_same(tuple(again), tuple(want)), "after reset() the detector answered differently from a fresh instance: it kept state of the "
            "previous run")


def _per_update_level(c) -> float:
    fa = getattr(c, "false_alarm", None)
    if isinstance(fa, (float, int)) and not isinstance(fa, bool) and 0 < fa < 0.5:
        return min(2.0 * float(fa), 1.0)
    return 0.01


def check_false_alarms_within_the_declared_level(c) -> None:
    """300 updates (after ``warmup``) of a consistent filter raise no more detections than the
    0.999 binomial quantile at twice ``false_alarm`` (or at 1 % when it declares none)."""
    from scipy.stats import binom

    n = 300
    seq = linear_gaussian_updates(n + _warmup(c), 3)
    c.reset()
    count = sum(det is not None for _, det in _run(c, seq))
    level = _per_update_level(c)
    bound = int(binom.ppf(0.999, n, level))
    require(count <= bound, f"{count} detections in {n} updates of a consistent filter; at a per-update level of {level:g} "
            f"more than {bound} happen with probability < 0.001")


def check_detects_a_step_within_five_updates(c) -> None:
    """A 20-sigma step in the measurements is detected within five updates of its start, with
    ``t_burn_bounds`` reaching back to the last update before it."""
    seq, step_at = _step_sequence(c)
    c.reset()
    results = _run(c, seq)
    hits = [i for i in range(step_at, step_at + 5) if results[i][1] is not None]
    require(hits, f"no detection in the five updates after a {_STEP_SIGMAS:g}-sigma step at update {step_at} "
            f"(statistics {[round(float(s), 3) for s, _ in results[step_at:step_at + 5]]})")
    det = results[hits[0]][1]
    lo = float(det.t_burn_bounds[0])
    require(math.isfinite(lo), f"t_burn_bounds {_plain(det.t_burn_bounds)} do not start at a finite time")
    require(lo <= seq.times[step_at - 1], f"t_burn_bounds {_plain(det.t_burn_bounds)} starts after "
            f"{float(seq.times[step_at - 1])!r}, the "
            f"last update before the step: the bounds must contain the burn")


MANEUVER_DETECTOR_CHECKS = [
    ("is_maneuver_detector", check_is_maneuver_detector),
    ("observe_returns_a_statistic_and_a_detection_or_none", check_observe_returns_a_statistic_and_a_detection_or_none),
    ("deterministic", check_deterministic),
    ("reset_forgets", check_reset_forgets),
    ("false_alarms_within_the_declared_level", check_false_alarms_within_the_declared_level),
    ("detects_a_step_within_five_updates", check_detects_a_step_within_five_updates),
]
