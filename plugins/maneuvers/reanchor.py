"""The refit behind the maneuver response ``reanchor``: the orbit refitted by least squares with an
impulsive burn (the response: :class:`~cistrack.plugins.maneuvers.responses.ReanchorResponse`).

On a detection at t with suspect interval [t_a, t] (the detection's ``t_burn_bounds``) the response
takes the run's history (:class:`~cistrack.interfaces.maneuvers.ResponseHistory`): the filter's
settled posterior N(m0, P0) at t0, a day before the interval (as the watch's burn estimate starts),
and the measurements in (t0, t), not those at t (the filter takes them right after the response:
using them here too would count them twice).
The unknowns are the state x0 (6,) at t0 and the velocity change dv (3,) of an impulsive burn at
t_b, with priors x0 ~ N(m0, P0) and dv ~ N(0, sigma^2 I) per synodic axis (``delta_v_sigma_ms``:
broad, so the problem stays well posed with few measurements after the burn). Gauss-Newton
(:data:`ITERATIONS` at most, each one propagation with transition matrices of the orbit flown with
the burn) solves for both at each of about :data:`CANDIDATES` burn times spread over the longest
:data:`MAX_GAPS` gaps between the measurements of the suspect interval (at least
:data:`~cistrack.least_squares.burn_search.MIN_GAP_HOURS` long; the last gap before t when none
is): :func:`burn_candidates`, and at as many in the gaps of the arc before the interval: a burn
the filter absorbed at the first pass after it is detected a pass later, its interval starting
after the burn (example-1-burn with 1000 particles, seed 1: burn at 3.62 d, interval 4.10-5.07 d).
The burn lies in the interval with prior probability :data:`INSIDE_PROBABILITY`, spread evenly
over its candidates, and before it with the rest: with no measurement after the burn yet, a burn
in an earlier gap explains the noise of the passes after it a little better, and without that
prior it takes a third of the particles (seed 9506: pass 3 at 3.14-3.28 d, burn at 3.62 d,
detection at 4.02 d).

Each candidate t_b gives a Gaussian for the state at t: the fitted orbit propagated there, with
covariance J C J^T, J = [Phi(t, t0), Phi(t, t_b)[:, 3:6]] and C the fit's (9, 9) covariance. The
new cloud draws N particles (N: the prior's) from the mixture of these Gaussians weighted by each
candidate's prior times its evidence, exp(-cost / 2) sqrt(det C) (cost: the measurements'
chi-square plus both priors' terms): the best burn time takes nearly every particle when the
measurements after the burn single it out, and the candidates share them when they do not (no
measurement after the burn yet).

Without a history (a call outside a run), without a settled posterior, with fewer than
:data:`MIN_MEASUREMENTS` measurements in the arc, or when the fit fails (FitError, LinAlgError,
PropagationError, MeasurementError), the response does what ``inflate`` does and says why in the
run's log; ``detection.extra["reanchor"]`` records what it did in either case.
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np

from cistrack import units
from cistrack.interfaces import Dynamics
from cistrack.interfaces.maneuvers import Detection, Impulse, ResponseHistory
from cistrack.least_squares.burn_search import MIN_GAP_HOURS
from cistrack.least_squares.errors import FitError
from cistrack.least_squares.measurement_model import MeasurementModel
from cistrack.least_squares.trajectory import arc_states_and_stms
from cistrack.model.belief import ParticleCloud
from cistrack.propagation.impulses import ImpulsiveDynamics

__all__ = ["Anchor", "refit", "draw", "burn_candidates", "CANDIDATES", "MAX_GAPS", "MIN_MEASUREMENTS", "ITERATIONS",
           "INSIDE_PROBABILITY"]

CANDIDATES = 12
"""Burn times tried in the suspect interval, and as many in the arc before it, each set shared by
its longest gaps in proportion to their lengths."""
MAX_GAPS = 4
"""The longest gaps tried for the burn (each gets one time at least)."""
MIN_MEASUREMENTS = 3
"""Fewer measurements than this between the posterior and the detection: fall back to ``inflate``."""
INSIDE_PROBABILITY = 0.8
"""The prior probability that the burn lies in the detection's suspect interval (the rest: in the
arc's gaps before it): the built-in detectors' ``t_burn_bounds`` held the burn in four runs of five
where they were measured (:mod:`cistrack.plugins.maneuvers.detectors`)."""
ITERATIONS = 6
"""Gauss-Newton steps at most per candidate burn time."""
_STEP_TOL = 1e-6
"""A step smaller than this (in prior sigmas) ends the iteration."""


@dataclass(frozen=True)
class _Arc:
    """One refit's fixed inputs: the ballistic model, the arc's measurement model, the posterior
    (m0 (6,), P0 (6, 6)) at t0 (TU), the detection time t (TU) and the delta-v prior sigma (VU)."""

    dynamics: Dynamics
    model: MeasurementModel
    t0: float
    m0: np.ndarray
    p0: np.ndarray
    t: float
    sigma_dv: float


@dataclass(frozen=True)
class Anchor:
    """A converged refit with the burn at ``tb`` (TU): its log evidence, its cost (the measurements'
    chi-square plus both priors' terms), the state's Gaussian at the detection (``mean`` (6,),
    ``covariance`` (6, 6)), the delta-v (3,) VU and the log prior probability of its burn time."""

    tb: float
    log_evidence: float
    cost: float
    mean: np.ndarray
    covariance: np.ndarray
    dv: np.ndarray
    log_prior: float = 0.0


def burn_candidates(times: np.ndarray, t0: float, t: float) -> np.ndarray:
    """Candidate burn times (C,) TU, in time order: :data:`CANDIDATES` shared in proportion to their
    lengths (at least one each) by the :data:`MAX_GAPS` longest gaps between the distinct times of
    ``[t0, times..., t]`` at least ``MIN_GAP_HOURS`` long (the last gap when none is), each gap's
    spread evenly over it (the centres of equal parts)."""
    grid = np.unique(np.concatenate([[t0], np.asarray(times, dtype=float), [t]]))
    a, b = grid[:-1], grid[1:]
    ok = np.nonzero(b - a >= float(units.hours_to_tu(MIN_GAP_HOURS)))[0]
    if ok.size == 0:
        ok = np.array([a.size - 1])
    keep = np.sort(ok[np.argsort(-(b[ok] - a[ok]), kind="stable")[:MAX_GAPS]])
    width = b[keep] - a[keep]
    counts = np.maximum(1, np.rint(CANDIDATES * width / np.sum(width))).astype(int)
    return np.concatenate([a[k] + (np.arange(c) + 0.5) / c * w for k, c, w in zip(keep, counts, width)])


def _whitened_prior(p0: np.ndarray) -> np.ndarray:
    """L^-1 (6, 6) with L L^T = P0, through the correlation matrix (P0's scales differ by orders)."""
    d = np.sqrt(np.diag(p0))
    corr = p0 / np.outer(d, d)
    low = np.linalg.cholesky(0.5 * (corr + corr.T))
    return np.linalg.inv(low) / d[None, :]


def _linearised(arc: _Arc, z: np.ndarray, tb: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """At the unknowns ``z`` = (x0 (6,) LU VU, dv (3,) VU) with the burn at ``tb``: the whitened
    rows (A (n, 9), b (n,)) of the measurements and both priors, the state at the detection (6,)
    and its Jacobian (6, 9)."""
    dyn = ImpulsiveDynamics(arc.dynamics, [Impulse(tb, z[6:], "reanchor")])
    times = np.asarray(arc.model.times, dtype=float)
    k = times.size
    states, stms = arc_states_and_stms(dyn, z[:6], arc.t0, np.concatenate([times, [tb, arc.t]]))
    sig = arc.model.sigmas
    r = arc.model.residuals(states[:k]) / sig
    h = arc.model.jacobian(states[:k]) / sig[:, :, None]
    from_burn = np.linalg.inv(stms[k])[:, 3:6]                         # Phi(t_b, t0)^-1 [:, 3:6]
    a_x = np.einsum("kmj,kjl->kml", h, stms[:k])
    a_v = np.einsum("kmj,kjl->kml", h, stms[:k] @ from_burn) * (times > tb)[:, None, None]
    rows = np.concatenate([a_x, a_v], axis=2).reshape(-1, 9)
    w0 = _whitened_prior(arc.p0)
    prior_rows = np.zeros((9, 9))
    prior_rows[:6, :6], prior_rows[6:, 6:] = w0, np.eye(3) / arc.sigma_dv
    b = np.concatenate([r.reshape(-1), w0 @ (arc.m0 - z[:6]), -z[6:] / arc.sigma_dv])
    jac = np.hstack([stms[k + 1], stms[k + 1] @ from_burn])
    return np.vstack([rows, prior_rows]), b, states[k + 1], jac


def _fit_at(arc: _Arc, tb: float) -> Anchor:
    """Gauss-Newton from (m0, 0) with the burn at ``tb`` (TU); the Gaussian at the detection from
    the last linearisation. Raises LinAlgError when the normal matrix is singular."""
    scale = np.concatenate([np.sqrt(np.diag(arc.p0)), np.full(3, arc.sigma_dv)])
    z = np.concatenate([arc.m0, np.zeros(3)])
    for k in range(ITERATIONS + 1):
        a, b, x_t, jac = _linearised(arc, z, tb)
        u, s, vt = np.linalg.svd(a * scale[None, :], full_matrices=False)
        if not s[-1] > s[0] * 1e-14:
            raise np.linalg.LinAlgError("the refit's normal matrix is singular")
        step = vt.T @ ((u.T @ b) / s)
        if np.max(np.abs(step)) < _STEP_TOL or k == ITERATIONS:
            break
        z = z + scale * step
    cov = (vt.T / s ** 2) @ vt * np.outer(scale, scale)                # C = D (A_s^T A_s)^-1 D
    covariance = jac @ cov @ jac.T
    log_ev = -0.5 * float(b @ b) - float(np.sum(np.log(s)))             # -cost/2 + log sqrt det C_s
    return Anchor(float(tb), log_ev, float(b @ b), x_t, 0.5 * (covariance + covariance.T), z[6:].copy())


def refit(detection: Detection, dynamics: Dynamics, history: ResponseHistory | None,
          delta_v_sigma_ms: float) -> list[Anchor]:
    """The refit at every candidate burn time (module docstring). Raises FitError when the history
    cannot carry one (none, no settled posterior, fewer than :data:`MIN_MEASUREMENTS`
    measurements), FitError, LinAlgError, PropagationError or MeasurementError when it fails."""
    if history is None or history.posterior is None:
        raise FitError("no history" if history is None else "no settled posterior before the suspect interval")
    post, t = history.posterior, float(detection.t)
    times = np.asarray(history.measurements.times, dtype=float)
    keep = (times > post.t + 1e-12) & (times < t - 1e-12)
    if int(np.sum(keep)) < MIN_MEASUREMENTS:
        raise FitError(f"{int(np.sum(keep))} measurements between the posterior and the detection "
                       f"(at least {MIN_MEASUREMENTS} needed)")
    model = MeasurementModel(history.sensor, history.measurements.subset(keep))
    sigma = float(units.kms_to_vu(delta_v_sigma_ms / 1000.0))
    arc = _Arc(dynamics, model, float(post.t), np.asarray(post.mean, dtype=float),
               np.asarray(post.covariance, dtype=float), t, sigma)
    return _fit_inside_and_before(arc, float(detection.t_burn_bounds[0]))


def _fit_inside_and_before(arc: _Arc, t_lo: float) -> list[Anchor]:
    """The fits with the burn in the suspect interval [``t_lo``, t] and in the arc's gaps before it,
    each with its share of the prior probability of its side (:data:`INSIDE_PROBABILITY` inside)."""
    times = np.asarray(arc.model.times, dtype=float)
    lo = t_lo if np.isfinite(t_lo) and t_lo > arc.t0 else arc.t0
    inside = burn_candidates(times[times >= lo], lo, arc.t)
    before = burn_candidates(times[times <= lo], arc.t0, lo) if lo > arc.t0 else np.zeros(0)
    p_in = INSIDE_PROBABILITY if before.size else 1.0
    out = [replace(_fit_at(arc, tb), log_prior=float(np.log((1.0 - p_in) / before.size))) for tb in before]
    return out + [replace(_fit_at(arc, tb), log_prior=float(np.log(p_in / inside.size))) for tb in inside]


PLACED_WEIGHT_FACTOR = 2.0
"""The burn time is said to be placed when its candidate's weight exceeds this many times the
uniform weight 1/K of K candidates; below, the log says the measurements cannot place it (the
cloud is the same either way)."""


def draw(detection: Detection, anchors: list[Anchor], n: int, rng: np.random.Generator,
         say: Callable[[str], None]) -> ParticleCloud:
    """``n`` particles (n, 6) at ``detection.t`` from the candidates' mixture, weighted by their
    evidence and prior; what was drawn recorded in ``detection.extra["reanchor"]`` and said."""
    log_ev = np.array([a.log_evidence + a.log_prior for a in anchors])
    w = np.exp(log_ev - np.max(log_ev))
    w = w / np.sum(w)
    counts = rng.multinomial(n, w)
    parts = [rng.multivariate_normal(a.mean, a.covariance, size=int(c), method="eigh")
             for a, c in zip(anchors, counts) if c > 0]
    best = anchors[int(np.argmax(w))]
    dv_ms = best.dv * float(units.vu_to_kms(1.0)) * 1000.0
    detection.extra["reanchor"] = {"fallback": None, "t_burn_candidates": [a.tb for a in anchors],
                                   "weights": w.tolist(), "t_burn": best.tb, "delta_v_ms": dv_ms.tolist()}
    if len(anchors) > 1 and np.max(w) < PLACED_WEIGHT_FACTOR / len(anchors):
        say(f"reanchor: the measurements cannot place the burn yet (largest weight {np.max(w):.2f} of {len(anchors)} "
            "candidate times): the cloud spreads over all of them")
    else:
        say(f"reanchor: refitted with a burn at {units.tu_to_days(best.tb):.3f} d (weight {np.max(w):.2f} of "
            f"{len(anchors)} candidate times), |dv| = {np.linalg.norm(dv_ms):.3f} m/s")
    return ParticleCloud(states=np.vstack(parts), epoch=float(detection.t))
