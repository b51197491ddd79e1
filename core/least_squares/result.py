"""The result of a least-squares orbit fit."""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from cistrack.least_squares.observability import to_km
from cistrack.least_squares.residual_table import ResidualTable

__all__ = ["FitResult", "sigma_factor", "noise_scale_text", "UNDETERMINED_NOISE_SCALE"]

UNDETERMINED_NOISE_SCALE = "undetermined (no degrees of freedom)"
"""How a noise scale that cannot be computed (NaN: as many fitted parameters as observed components)
is written, in words, wherever a fit states its noise scale."""


def sigma_factor(noise_scale: float) -> float:
    """The factor a fit's sigmas are widened by when its residuals say the stated noise was too
    small: ``max(1, noise_scale)`` (dimensionless; 1 when the noise scale is undefined, NaN or
    infinite). Its square scales the covariance, as exported and predicted; a fit is never narrowed."""
    s = float(noise_scale)
    return s if math.isfinite(s) and s > 1.0 else 1.0


def noise_scale_text(noise_scale: float, spec: str = ".4g") -> str:
    """The noise scale (dimensionless) formatted with ``spec``, or :data:`UNDETERMINED_NOISE_SCALE`
    when it is not finite: never "nan"."""
    s = float(noise_scale)
    return format(s, spec) if math.isfinite(s) else UNDETERMINED_NOISE_SCALE


@dataclass(frozen=True)
class FitResult:
    """A fitted orbit, its covariance and its post-fit residuals.

    Attributes
    ----------
    state : (6,) float            estimate at ``epoch``: synodic LU, VU
    covariance : (6, 6) float     inverse of the normal matrix at the estimate (prior included), LU, VU
    epoch : float                 TU since the measurements' epoch
    residuals : ResidualTable     post-fit O - C of every observation, used or rejected
    rms : float                   weighted RMS: sqrt(chi2 / number of used components) (1 if the
                                  noise is as stated)
    chi2 : float                  sum of squared normalised residuals of the used observations
    n_used, n_rejected : int      observations (rows) used and rejected
    iterations : int              Gauss-Newton / Levenberg-Marquardt iterations, all passes together
    converged : bool              the iteration met its criteria and the rejected set settled
    condition_number : float      of the unit-diagonal normal matrix (units do not matter)
    weakest_direction_km : (6,) float  one-sigma displacement along the least determined
                                  direction, km and km/s
    noise_scale : float           sqrt(chi2 / (used components - 6)): the factor by which the
                                  post-fit residuals say the stated noise is off (1: right)
    rejection_threshold : float   chi-square above which an observation was rejected (inf: no rejection)
    unobservable : bool           the condition number or the weakest direction's sigma exceeded
                                  the fit's limits (a warning was given)
    messages : tuple of str       what happened, in words (convergence, rejections, warnings)
    parameter_names : tuple of str   dynamics parameters estimated with the state (solve-for
                                  parameters, e.g. "area_to_mass_m2_kg"); empty when none
    parameters : (P,) float       their estimates, each in its own unit (m^2/kg for the area-to-mass ratio)
    full_covariance : (6 + P, 6 + P) float or None  the inverse normal matrix of state and
                                  parameters (``covariance`` is its state block); None when P = 0
    area_to_mass_decision : str   with ``area_to_mass="auto"``: why the ratio was or was not
                                  estimated; "" otherwise
    """

    state: np.ndarray
    covariance: np.ndarray
    epoch: float
    residuals: ResidualTable
    rms: float
    chi2: float
    n_used: int
    n_rejected: int
    iterations: int
    converged: bool
    condition_number: float
    weakest_direction_km: np.ndarray
    noise_scale: float
    rejection_threshold: float = float("inf")
    unobservable: bool = False
    messages: tuple[str, ...] = field(default_factory=tuple)
    parameter_names: tuple[str, ...] = ()
    parameters: np.ndarray = field(default_factory=lambda: np.zeros(0))
    full_covariance: np.ndarray | None = None
    area_to_mass_decision: str = ""

    @property
    def parameter_sigmas(self) -> np.ndarray:
        """One-sigma uncertainty (P,) of each solve-for parameter, in its own unit."""
        if self.full_covariance is None:
            return np.zeros(0)
        return np.sqrt(np.diag(self.full_covariance)[6:])

    @property
    def parameter_correlations(self) -> np.ndarray:
        """Correlation coefficients (P, 6) of each solve-for parameter with the state's
        coordinates (x, y, z, vx, vy, vz; units cancel)."""
        if self.full_covariance is None:
            return np.zeros((0, 6))
        c = self.full_covariance
        s = np.sqrt(np.diag(c))
        return c[6:, :6] / np.outer(s[6:], s[:6])

    def parameter(self, name: str) -> tuple[float, float] | None:
        """(estimate, one sigma) of solve-for parameter ``name``, or None when it was not estimated."""
        if name not in self.parameter_names:
            return None
        j = self.parameter_names.index(name)
        return float(self.parameters[j]), float(self.parameter_sigmas[j])

    @property
    def state_km(self) -> np.ndarray:
        """The estimate (6,) in km and km/s (synodic)."""
        return to_km(self.state)

    @property
    def covariance_km(self) -> np.ndarray:
        """The covariance (6, 6) in km^2, km^2/s, km^2/s^2."""
        k = to_km(np.ones(6))
        return self.covariance * np.outer(k, k)

    @property
    def sigmas_km(self) -> np.ndarray:
        """One-sigma uncertainty of each coordinate (6,), km and km/s."""
        return np.sqrt(np.diag(self.covariance_km))

    def mahalanobis2(self, truth: np.ndarray) -> float:
        """(truth - state)^T covariance^-1 (truth - state) for a true state (6,) [LU, VU] at the epoch
        (chi-square with 6 degrees of freedom if the covariance is right)."""
        e = np.asarray(truth, dtype=float).reshape(6) - self.state
        return float(e @ np.linalg.solve(self.covariance, e))
