"""The least-squares mathematics of orbit determination: batch differential correction of an
orbit over an arc of measurements (state transition matrices from the variational equations),
outlier rejection, post-fit residuals, the line of variations and prediction.

- :func:`fit_orbit` (:mod:`.differential_correction`): Gauss-Newton / Levenberg-Marquardt on the
  state (6,) at an epoch (synodic LU, VU), with chi-square outlier rejection and readmission
  (:mod:`.outliers`); returns a :class:`FitResult` (:mod:`.result`) with the covariance (6, 6),
  the post-fit :class:`ResidualTable` (:mod:`.residual_table`), the noise scale and the
  observability diagnostics (:mod:`.observability`).
- :class:`FitOptions` (:mod:`.options`): convergence, damping and rejection settings.
- :func:`predict` (:mod:`.prediction`): the fitted state and covariance at other times, linear or
  by sigma points (:mod:`.unscented_prediction`).
- :mod:`.line_of_variations`: least-squares points along the weakest direction of a fit.
- :mod:`.trajectory`: states and transition matrices over an arc (epoch anywhere in it);
  :mod:`.measurement_model`: predicted measurements, residuals and their Jacobian per site;
  :mod:`.chi_square`: chi-square quantiles.

Plain mathematics on the interfaces, model types and units: it imports nothing above
:mod:`cistrack.propagation` and :mod:`cistrack.astro`, so a filter plugin can use it. The
``cistrack fit`` workflow (observation files in, results folders out) is :mod:`cistrack.fitting`.
"""
from cistrack.least_squares.errors import FitError, UnobservableWarning
from cistrack.least_squares.differential_correction import fit_orbit
from cistrack.least_squares.options import FitOptions
from cistrack.least_squares.prediction import predict
from cistrack.least_squares.residual_table import ResidualTable
from cistrack.least_squares.result import FitResult

__all__ = ["fit_orbit", "predict", "FitOptions", "FitResult", "ResidualTable", "FitError", "UnobservableWarning"]

