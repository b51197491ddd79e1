"""How a run is judged: per-step metrics (errors, NEES, entropy), innovation consistency and
residuals, the custody rule, the metric stage that computes a step's metrics in a declared order,
final verdicts and the typed run summary.

Imports the layers below it, up to :mod:`cistrack.results`.
"""
