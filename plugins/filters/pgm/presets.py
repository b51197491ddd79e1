"""Variants of the PGM that are only other settings: presets (:func:`cistrack.interfaces.preset.preset`)."""
from __future__ import annotations

from cistrack.interfaces.preset import preset

from .filter import PGMFilter

__all__ = ["PaperPGMFilter"]

PaperPGMFilter = preset(
    PGMFilter, "PaperPGMFilter",
    """The paper's plain PGM, kept by name for comparisons: k-means clusters, the ensemble (particle
    cross-covariance) Kalman update of each component, draws from the posterior mixture, no
    re-anchoring, no shrinkage or reacquisition, clusters down to twice the state dimension.""",
    component_update="ensemble", posterior_draw="gaussian", reanchor="off", kept_spread=1.0,
    reacquire_factor=1.0, min_cluster_size=12)
