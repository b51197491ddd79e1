"""Per-step metrics of a belief against the truth: errors, per-axis sigmas, NEES, entropy, truth likelihood.

Person-facing units: positions km, velocities km/s (errors in m/s, sigmas in cm/s), densities of
the state in km and km/s (entropy and log-likelihood in nats of that density).
"""
from __future__ import annotations

from typing import Any

import numpy as np

from cistrack.evaluation.metric_stage import StepMetric
from cistrack.model.belief import Belief
from cistrack.results.step_table import is_table_step
from cistrack.numerics.special_functions import chi2_cdf
from cistrack.units import LU_KM, VU_KMS

__all__ = ["step_metrics", "entropy", "nees", "hdr_level", "LOG_JACOBIAN_KM", "BeliefMetric", "PassIndexMetric", "pass_index"]

LOG_JACOBIAN_KM: float = 3.0 * np.log(LU_KM) + 3.0 * np.log(VU_KMS)
"""log |d(state_km)/d(state_nd)|: log p_km(x) = log p_nd(x) - LOG_JACOBIAN_KM."""

_SCALE = np.array([LU_KM] * 3 + [VU_KMS] * 3)


def entropy(belief: Belief, sample_logpdf: np.ndarray | None = None) -> float:
    """The paper's entropy estimate H = -(1/N) sum log p(x_i) over the belief's samples, with p
    the belief's mixture density of the state in km and km/s (nats). ``sample_logpdf`` (N,)
    may pass the nondimensional log density of the samples when it is already known."""
    lp = belief.mixture.logpdf(belief.samples.states) if sample_logpdf is None else sample_logpdf
    w = belief.samples.weights
    if w is None:
        return -float(np.mean(lp)) + LOG_JACOBIAN_KM
    with np.errstate(invalid="ignore"):
        h = -float(w @ lp)
    if np.isnan(h):  # a sample of weight 0 where the density is 0 adds nothing (0 x -inf is NaN)
        kept = w > 0.0
        h = -float(w[kept] @ lp[kept])
    return h + LOG_JACOBIAN_KM


def nees(error: np.ndarray, covariance: np.ndarray) -> float:
    """Normalised estimation error squared e^T P^-1 e (unit-free): e (d,), P (d, d)."""
    with np.errstate(over="ignore"):  # a collapsed belief's NEES beyond the largest float is infinite, said so
        try:
            c = np.linalg.cholesky(covariance)
            y = np.linalg.solve(c, error)
            return float(y @ y)
        except np.linalg.LinAlgError:
            return float(error @ np.linalg.pinv(covariance) @ error)


def step_metrics(belief: Belief, truth: np.ndarray | None) -> dict[str, float]:
    """All metrics of one belief against the truth (6,) nondimensional, or None if unknown.

    Keys: entropy (nats, km/km/s density); n_components; n_samples; sigma_x_km, sigma_y_km,
    sigma_z_km; sigma_vx_cms, sigma_vy_cms, sigma_vz_cms (per-axis standard deviations of the
    mixture); with truth also pos_err_km, vel_err_ms (error of the mixture mean), nees (of the
    moment-matched mean and covariance), truth_loglik (log density of the truth, km/km/s) and
    hdr_level (probability mass of the highest-density region whose boundary passes through the
    truth: 0 at the mode, 1 far outside; :func:`hdr_level`).
    """
    mix = belief.mixture
    mean = mix.mean
    cov = mix.covariance
    sig = np.sqrt(np.maximum(np.diag(cov), 0.0)) * _SCALE
    lp_samples = mix.logpdf(belief.samples.states)
    out: dict[str, float] = {
        "entropy": entropy(belief, lp_samples),
        "n_components": float(mix.n_components),
        "n_samples": float(len(belief.samples)),
        "sigma_x_km": sig[0], "sigma_y_km": sig[1], "sigma_z_km": sig[2],
        "sigma_vx_cms": sig[3] * 1e5, "sigma_vy_cms": sig[4] * 1e5, "sigma_vz_cms": sig[5] * 1e5,
        "sigma_pos_km": float(np.sqrt(np.sum(sig[:3] ** 2))),
        "sigma_vel_cms": float(np.sqrt(np.sum(sig[3:] ** 2)) * 1e5),
    }
    if truth is not None:
        e = np.asarray(truth, dtype=float) - mean
        out["pos_err_km"] = float(np.linalg.norm(e[:3]) * LU_KM)
        out["vel_err_ms"] = float(np.linalg.norm(e[3:]) * VU_KMS * 1e3)
        out["nees"] = nees(e, cov)
        lp_truth = float(mix.logpdf(np.asarray(truth, dtype=float)[None])[0])
        out["truth_loglik"] = lp_truth - LOG_JACOBIAN_KM
        out["hdr_level"] = hdr_level(belief, lp_truth, lp_samples, out["nees"])
    return out


def hdr_level(belief: Belief, lp_truth: float, lp_samples: np.ndarray, nees_truth: float) -> float:
    """Probability mass, under the belief's own density, of the highest-density region whose
    boundary passes through the truth (0 at the mode, 1 far outside).

    A single Gaussian (UKF, EnKF, a particle filter's moment-matched summary) is scored exactly:
    its level is the chi-square(d) distribution function of the truth's NEES. Its samples need
    not follow it (an EnKF's ensemble is heavy-tailed about its Gaussian), so ranking them by its
    density would place a truth far outside the Gaussian inside the region. A mixture of several
    components is scored by its samples, the fraction (weighted) whose density exceeds the
    truth's: the PGM's samples at an update are draws of its posterior mixture.
    ``lp_truth`` and ``lp_samples`` (N,) are log densities under ``belief.mixture``."""
    mix = belief.mixture
    if mix.n_components == 1:
        return chi2_cdf(max(nees_truth, 0.0), mix.dim)
    w = belief.samples.weights
    above = (lp_samples > lp_truth).astype(float)
    return float(above.mean() if w is None else w @ above)


class BeliefMetric(StepMetric):
    """The metric stage ``belief``: :func:`step_metrics` of every table step (not the prior of
    an update, which has no row)."""

    name = "belief"

    def compute(self, run: Any, step: Any, event: str) -> dict[str, float]:
        return step_metrics(step.belief, step.truth) if is_table_step(event, step) else {}


def pass_index(passes: list, t: float) -> int:
    """1 + the index of the pass of ``passes`` (each with ``start``, ``end`` TU) holding time
    ``t`` (TU), or 0 outside every pass."""
    for i, p in enumerate(passes):
        if p.start - 1e-9 <= t <= p.end + 1e-9:
            return i + 1
    return 0


class PassIndexMetric(StepMetric):
    """The metric stage ``pass_index``: ``pass_index`` (:func:`pass_index`, as a float) of every
    table step."""

    name = "pass_index"

    def compute(self, run: Any, step: Any, event: str) -> dict[str, float]:
        return {"pass_index": float(pass_index(run.passes, step.t))} if is_table_step(event, step) else {}
