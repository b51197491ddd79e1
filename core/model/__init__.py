"""The data a run passes around: beliefs (particle clouds, Gaussian mixtures) and measurements.

Imports only the base modules (``cistrack.errors``, ``cistrack.units``, ``cistrack.lazy``).
"""
