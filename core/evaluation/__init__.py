"""How a run is judged: per-step metrics (errors, NEES, entropy), innovation consistency and
residuals, the custody rule and its observer, final verdicts and the typed run summary.

Imports the layers below it, up to :mod:`cistrack.results`.
"""
