"""Orbit fitting from observations: batch least-squares differential correction over an arc
(state transition matrices from the variational equations), outlier rejection and post-fit
residuals.

- :func:`fit_orbit` (:mod:`.least_squares`): Gauss-Newton / Levenberg-Marquardt on the state at an
  epoch, with chi-square outlier rejection and readmission; returns a :class:`FitResult`
  (:mod:`.result`) with the covariance, the post-fit :class:`ResidualTable`
  (:mod:`.residual_table`), the noise scale and the observability diagnostics
  (:mod:`.observability`).
- :class:`FitOptions` (:mod:`.options`): convergence, damping and rejection settings.
- :func:`predict` (:mod:`.prediction`): the fitted state and covariance at other times.
- :mod:`.trajectory`: states and transition matrices over an arc (epoch anywhere in it);
  :mod:`.measurement_model`: predicted measurements, residuals and their Jacobian per site.

The package is callable: ``cistrack.fit(files, ...)`` is :func:`cistrack.api.fit` (observation
files in, one :class:`ObjectFit` per object out; the top-level package makes it so).

May import the layers below it, up to :mod:`cistrack.runs`.
"""
from cistrack.fit.errors import FitError, UnobservableWarning
from cistrack.fit.least_squares import fit_orbit
from cistrack.fit.options import FitOptions
from cistrack.fit.prediction import predict
from cistrack.fit.residual_table import ResidualTable
from cistrack.fit.result import FitResult

__all__ = ["fit_orbit", "predict", "FitOptions", "FitResult", "ResidualTable", "FitError", "UnobservableWarning"]

