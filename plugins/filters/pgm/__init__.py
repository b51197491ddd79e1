"""The particle Gaussian mixture (PGM) filter, composed of registered, swappable steps.

==========================  ===================================================================
module                      holds
==========================  ===================================================================
:mod:`.filter`              :class:`PGMFilter`: the orchestration (predict; cluster, update,
                            reweight, draw; the re-anchoring and kernel-update hooks)
:mod:`.presets`             ``pgm-paper`` (:data:`PaperPGMFilter`): the PGM with the paper's settings
:mod:`.prediction`          the ``pgm-prediction`` step ``propagate``
:mod:`.component_update`    the ``pgm-update`` steps ``iterated`` and ``ensemble``
:mod:`.posterior_draw`      the ``pgm-draw`` steps ``transform`` and ``gaussian``
:mod:`.posterior_transform` the shape-keeping map of clusters onto their posteriors
:mod:`.reanchor_modes`      the ``pgm-reanchor`` steps ``arcs``, ``across-gaps`` and ``off``
:mod:`.reanchoring`         one run's re-anchoring: arcs, least-squares fits, lines of variations
:mod:`.kernel_modes`        the ``pgm-kernel`` steps ``after-gap`` and ``off``
:mod:`.kernel_update`       every particle its own kernel, in the first pass after a gap
:mod:`.step_choice`         a step given by name or as a component, with the PGM's settings
:mod:`.clusterer_choice`    the clusterer, with the PGM's ``n_components``
:mod:`.cluster_merge`       merging clusters too small for a covariance
:mod:`.component_spread`    moment-preserving shrinkage of the components (``kept_spread``)
:mod:`.measurement_sharpness` how sharp a measurement is against the cloud (``split_ess``)
:mod:`.reacquisition_particles` more particles while reacquiring (``reacquire_factor``)
:mod:`.state_bounds`        optional cislunar pruning bounds
==========================  ===================================================================

The steps' interfaces are in :mod:`cistrack.interfaces.pgm_steps`; docs/pgm-parameters.md says
how the defaults were chosen and how to swap a step.
"""
from __future__ import annotations

from cistrack import hookimpl

from .clusterer_choice import resolve_clusterer
from .component_update import EnsembleUpdate, IteratedUpdate
from .filter import PGMFilter
from .kernel_modes import AfterGapKernels, NoKernels
from .posterior_draw import GaussianDraw, TransformDraw
from .prediction import PropagateParticles
from .presets import PaperPGMFilter
from .reanchor_modes import AcrossGapsReanchor, ArcsReanchor, NoReanchor

__all__ = ["PGMFilter", "PaperPGMFilter", "resolve_clusterer", "IteratedUpdate", "EnsembleUpdate",
           "TransformDraw", "GaussianDraw", "ArcsReanchor", "AcrossGapsReanchor", "NoReanchor", "PropagateParticles",
           "AfterGapKernels", "NoKernels"]


@hookimpl
def cistrack_register(registry):
    registry.add("filter", "pgm", PGMFilter)
    registry.add("filter", "pgm-paper", PaperPGMFilter)
    registry.add("pgm-prediction", "propagate", PropagateParticles)
    registry.add("pgm-update", "iterated", IteratedUpdate)
    registry.add("pgm-update", "ensemble", EnsembleUpdate)
    registry.add("pgm-draw", "transform", TransformDraw)
    registry.add("pgm-draw", "gaussian", GaussianDraw)
    registry.add("pgm-kernel", "after-gap", AfterGapKernels)
    registry.add("pgm-kernel", "off", NoKernels)
    registry.add("pgm-reanchor", "arcs", ArcsReanchor)
    registry.add("pgm-reanchor", "across-gaps", AcrossGapsReanchor)
    registry.add("pgm-reanchor", "off", NoReanchor)
