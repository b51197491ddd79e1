"""The swappable steps of the particle Gaussian mixture (PGM) filter, each a registry kind.

Between measurements the PGM propagates its particles (a :class:`ParticlePrediction`). At a
measurement it clusters them (a ``clustering`` component), conditions each cluster's Gaussian on
the measurement (a :class:`ComponentUpdate`), reweights the components by their likelihoods and
draws the posterior particles (a :class:`PosteriorDraw`). Two hooks change that course: a
:class:`KernelUpdate` may condition every particle as its own kernel instead (after a gap), and
at the end of a pass a :class:`Reanchor` may replace the belief by least-squares fits of the arc. A scenario
chooses each step by name (``component_update = "ensemble"``), and a third party registers its
own under the step's kind exactly as it registers a filter.

==============  ==========================  ==================================
kind            interface                   built-in names
==============  ==========================  ==================================
pgm-prediction  :class:`ParticlePrediction` ``propagate``
pgm-update      :class:`ComponentUpdate`    ``iterated``, ``ensemble``
pgm-draw        :class:`PosteriorDraw`      ``transform``, ``gaussian``
pgm-kernel      :class:`KernelUpdate`       ``after-gap``, ``off``
pgm-reanchor    :class:`Reanchor`           ``arcs``, ``across-gaps``, ``off``
==============  ==========================  ==================================

States are nondimensional synodic (LU, VU), times TU; ``d`` is the state dimension (6), ``m`` the
number of measured components, ``M`` the number of clusters.
"""
from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass
from typing import Any, Callable, ClassVar

import numpy as np

from cistrack.interfaces.component import Component
from cistrack.interfaces.dynamics import Dynamics
from cistrack.interfaces.sensor import Sensor
from cistrack.model.belief import GaussianMixture
from cistrack.model.measurement import Measurement

__all__ = ["ClusteredParticles", "ComponentUpdate", "KernelRun", "KernelUpdate", "ParticlePrediction",
           "PosteriorDraw", "Reanchor", "ReanchorRun", "PGM_STEP_KINDS"]

PGM_STEP_KINDS: tuple[str, ...] = ("pgm-prediction", "pgm-update", "pgm-draw", "pgm-kernel", "pgm-reanchor")
"""The registry kinds of the PGM's steps, in the order of a PGM update."""


@dataclass(frozen=True)
class ClusteredParticles:
    """The prior particles of one update and their clusters' sample moments (before the PGM
    reshapes the components with ``kept_spread``).

    states (N, d) LU and VU; labels (N,) int in [0, M); means (M, d); covariances (M, d, d).
    """

    states: np.ndarray
    labels: np.ndarray
    means: np.ndarray
    covariances: np.ndarray


class ParticlePrediction(Component):
    """How the PGM's particles are carried from one time to the next."""

    kind = "pgm-prediction"

    def __init__(self) -> None:
        """No parameters (a subclass with settings declares them, as every component does)."""

    @abstractmethod
    def predict(self, dynamics: Dynamics, states: np.ndarray, t0: float, t1: float, rng: np.random.Generator,
                steps: np.ndarray | None, who: str) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
        """Move the particles ``states`` (N, 6) from ``t0`` to ``t1`` (TU).

        ``steps`` (N,) TU: each particle's first integration step, carried from the previous call
        (None: the integrator chooses); ``who`` names the filter in errors. Returns the particles
        that survive (M, 6) (those that hit a body are dropped), ``alive`` (N,) bool, and the
        survivors' next steps (M,) or None. Raise :class:`~cistrack.errors.FilterError` when none
        survives.
        """


class ComponentUpdate(Component):
    """How each clustered component N(mean_i, P_i) is conditioned on one measurement."""

    kind = "pgm-update"
    uses_particles: ClassVar[bool] = False
    """True when the update reads the particles' cross-covariances with their predicted
    measurements (``moments.pxd``, ``moments.pdd``): the PGM then conditions the clusters as they
    are, without first reshaping their Gaussians (``kept_spread``)."""

    def __init__(self) -> None:
        """No parameters (a subclass with settings declares them, as every component does)."""

    @abstractmethod
    def update(self, moments: Any, residuals: Callable[[np.ndarray], np.ndarray],
               R: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Condition the M components on the measurement.

        ``moments``: the clusters' sample moments, with attributes counts (M,) int, mean_x (M, d),
        pxx (M, d, d) (the components' Gaussians) and, of the residuals h(x) - z of their
        particles, mean_d (M, m), pxd (M, d, m), pdd (M, m, m). ``residuals``: states (K, d) ->
        h(states) - z (K, m), angles wrapped to [-pi, pi). ``R``: noise covariance (m, m).

        Returns posterior means (M, d), covariances (M, d, d) and each component's predictive
        log-likelihood log p(z | component) (M,), which reweights the components.
        """


class PosteriorDraw(Component):
    """Where the PGM's posterior particles come from, once the posterior mixture is known."""

    kind = "pgm-draw"

    def __init__(self) -> None:
        """No parameters (a subclass with settings declares them, as every component does)."""

    @abstractmethod
    def draw(self, prior: ClusteredParticles, posterior: GaussianMixture, n: int,
             rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
        """``n`` posterior particles (n, d) and the posterior component of each (n,) int in [0, M).

        ``posterior`` has one component per cluster of ``prior``, in the same order. Use only
        ``rng``. (While the filter reacquires a cloud, drawing more particles than it carries, or
        prunes particles outside state bounds, it draws from the mixture itself.)
        """


class KernelRun(ABC):
    """The kernel update's state in one filter run (made by :meth:`KernelUpdate.start`)."""

    @abstractmethod
    def due(self, t: float, sharpness: Callable[[], float]) -> bool:
        """Whether the update at ``t`` (TU) conditions kernels instead of the clusters' Gaussians.
        Called at every update, in time order; ``sharpness()`` gives the measurement's likelihood
        ESS as a fraction of the particles (computed on the first call only: call it only when
        needed)."""

    @abstractmethod
    def update(self, prior: ClusteredParticles, residuals: Callable[[np.ndarray], np.ndarray], R: np.ndarray,
               n: int, rng: np.random.Generator, who: str) -> tuple[np.ndarray, np.ndarray, float]:
        """``n`` posterior particles (n, d), their clusters (n,) and the log evidence log p(z);
        ``residuals`` and ``R`` as for :meth:`ComponentUpdate.update`."""


class KernelUpdate(Component):
    """Whether and when the PGM conditions every particle as its own Gaussian kernel."""

    kind = "pgm-kernel"

    def __init__(self) -> None:
        """No parameters (a subclass with settings declares them, as every component does)."""

    @abstractmethod
    def start(self) -> KernelRun | None:
        """A fresh state for one run; None when this component never conditions kernels."""


class ReanchorRun(ABC):
    """The re-anchoring state of one filter run (made by :meth:`Reanchor.start`)."""

    @abstractmethod
    def observe(self, measurement: Measurement) -> None:
        """Record a measurement the filter is about to condition on."""

    @abstractmethod
    def due(self, t: float) -> bool:
        """Whether the prediction to ``t`` (TU) ends an arc worth fitting."""

    @abstractmethod
    def attempt(self, x: np.ndarray, t: float, dynamics: Dynamics, sensor: Sensor) -> GaussianMixture | None:
        """Fit the recorded measurements from the posterior particles ``x`` (N, 6) at the last
        update ``t`` (TU): the mixture of accepted solutions there, or None (the belief carries on)."""

    @abstractmethod
    def draw(self, n: int, rng: np.random.Generator) -> np.ndarray | None:
        """Particles (n, 6) for the latest accepted solutions, or None to draw them from the
        mixture :meth:`attempt` returned."""


class Reanchor(Component):
    """Whether and how the PGM replaces its belief by least-squares fits of whole arcs."""

    kind = "pgm-reanchor"

    def __init__(self) -> None:
        """No parameters (a subclass with settings declares them, as every component does)."""

    @abstractmethod
    def start(self) -> ReanchorRun | None:
        """A fresh re-anchoring state for one run; None when this component never re-anchors."""
