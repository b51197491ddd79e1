"""Orbit fitting from observations: batch least-squares differential correction over an arc
(state transition matrices from the variational equations), outlier rejection and post-fit
residuals.

May import the layers below it, up to :mod:`cistrack.runs`.
"""
