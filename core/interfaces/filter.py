"""Filter: initialise from a cloud, predict, update; exposes its belief."""
from __future__ import annotations

from abc import abstractmethod
from typing import Any, ClassVar, TypedDict

import numpy as np

from cistrack.model.belief import Belief, ParticleCloud
from cistrack.interfaces.component import Component
from cistrack.errors import FilterError
from cistrack.model.measurement import Measurement
from cistrack.interfaces.dynamics import Dynamics
from cistrack.interfaces.sensor import Sensor

__all__ = ["Filter", "FilterBase", "Diagnostics", "DIAGNOSTIC_PREFIX", "diagnostic_column", "DOCUMENTED_DIAGNOSTICS",
           "DIAGNOSTICS_RULE", "bad_diagnostic"]


class Diagnostics(TypedDict, total=False):
    """The diagnostics whose meaning the framework relies on, by key (all floats; a filter reports
    those that apply to it, and any others it likes, in :attr:`Filter.diagnostics`).

    Each step's table has them as columns ``diag_<key>`` (:func:`diagnostic_column`); the final
    verdict reads ``ess_before_resampling``, ``unique_particles`` and ``n_particles`` to call a
    particle filter's weights degenerate.
    """

    n_particles: float
    """Particles carried after this step."""
    ess_before_resampling: float
    """Effective sample size 1 / sum(w^2) of the weights before resampling (the smallest over the
    stages of one update)."""
    unique_particles: float
    """Distinct particles after resampling (resampling duplicates the heavy ones)."""
    n_components: float
    """Gaussian components of the belief after this step."""
    particles_lost: float
    """Particles lost to impacts so far in the run."""


DIAGNOSTIC_PREFIX = "diag_"
"""Prefix of the diagnostics' columns in a run's step table."""


def diagnostic_column(key: str) -> str:
    """The step-table column of diagnostic ``key``: ``diag_ess_before_resampling``."""
    return DIAGNOSTIC_PREFIX + key


DOCUMENTED_DIAGNOSTICS: tuple[str, ...] = tuple(Diagnostics.__annotations__)
"""The diagnostics whose meaning the framework relies on: each a count or size, finite and >= 0."""

DIAGNOSTICS_RULE = (f"a documented diagnostic (cistrack.interfaces.filter.Diagnostics: {', '.join(DOCUMENTED_DIAGNOSTICS)}) "
                    "is a count or size: a finite number >= 0")
"""What :data:`DOCUMENTED_DIAGNOSTICS` must be, as messages state it."""


def bad_diagnostic(diagnostics: dict) -> tuple[str, Any] | None:
    """(key, value) of the first of ``diagnostics`` that is one of :data:`DOCUMENTED_DIAGNOSTICS`
    and not a finite number >= 0 (:data:`DIAGNOSTICS_RULE`); None when they all keep the rule
    (other keys are the filter's own)."""
    for key in DOCUMENTED_DIAGNOSTICS:
        if key not in diagnostics:
            continue
        value = diagnostics[key]
        number = isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(value, (bool, np.bool_))
        if not (number and np.isfinite(value) and value >= 0):
            return key, value
    return None


class Filter(Component):
    """A recursive estimator.

    Lifecycle: ``initialize(cloud, dynamics, sensor, rng)`` once, then for each measurement
    ``predict(t)`` followed by ``update(measurement)``. ``belief`` is valid after each call.
    """

    kind = "filter"
    stacked_updates: ClassVar[bool] = False
    """Whether ``update`` accepts a :class:`cistrack.model.measurement.StackedMeasurement` (several
    sites at one time as one measurement: stacked z, block-diagonal R, names repeating). A run
    hands such a filter one stacked update per time; others get the parts one after another."""

    @abstractmethod
    def initialize(self, cloud: ParticleCloud, dynamics: Dynamics, sensor: Sensor,
                   rng: np.random.Generator) -> None:
        """Start from the IOD cloud (N, 6) at ``cloud.epoch``."""

    @abstractmethod
    def predict(self, t: float) -> None:
        """Propagate the belief to time ``t`` (TU)."""

    @abstractmethod
    def update(self, measurement: Measurement) -> None:
        """Condition the belief on one measurement taken at the current time."""

    @property
    @abstractmethod
    def belief(self) -> Belief:
        """The current density as a Gaussian mixture plus samples."""

    def process_noise(self, t0: float, t1: float) -> np.ndarray | None:
        """The covariance (6, 6, nondimensional) this filter adds to its belief when predicting
        from ``t0`` to ``t1`` (TU), or None when it adds none (the default). The information bound
        (:mod:`cistrack.evaluation.information_bound`) adds the same."""
        return None

    @property
    def diagnostics(self) -> dict[str, float]:
        """Per-step numbers worth recording, as floats by key; the keys of :class:`Diagnostics`
        carry the meaning declared there (components, particles, effective sample size, ...)."""
        return {}


class FilterBase(Filter):
    """A :class:`Filter` with the bookkeeping every recursive filter repeats.

    - ``_who()``: the name used in error messages (the registered name, else ``default_name``);
    - ``_require_init()``: a :class:`~cistrack.errors.FilterError` unless :meth:`_is_initialized`;
    - :meth:`predict`: checks initialisation, does nothing when ``t`` is the current time
      ``self._t``, else calls :meth:`_predict_to` and moves ``self._t`` to ``t``;
    - :attr:`diagnostics`: the per-step numbers in ``self._diag`` plus :meth:`_totals`.

    A subclass sets ``self._t`` (TU) and ``self._diag`` in ``initialize`` and implements
    :meth:`_is_initialized`, :meth:`_predict_to`, ``update`` and ``belief``.
    """

    default_name: ClassVar[str] = "filter"
    _t: float
    """The filter's current time, TU (set by ``initialize``)."""
    _diag: dict[str, float]
    """This step's diagnostics (set by ``initialize`` and each step)."""

    def _who(self) -> str:
        return self.registry_name or self.default_name

    @abstractmethod
    def _is_initialized(self) -> bool:
        """Whether ``initialize`` has run."""

    def _require_init(self) -> None:
        if not self._is_initialized():
            raise FilterError(f"filter '{self._who()}': call initialize() first")

    def predict(self, t: float) -> None:
        """Propagate the belief to time ``t`` (TU); a no-op at the current time."""
        self._require_init()
        if isinstance(t, (bool, str, bytes)) or not isinstance(t, (int, float, np.integer, np.floating)):
            raise FilterError(f"filter '{self._who()}': predict() needs a time in TU (a number), got "
                              f"{type(t).__name__} {t!r}")
        t = float(t)
        if t == self._t:
            return
        self._predict_to(t)
        self._t = t

    @abstractmethod
    def _predict_to(self, t: float) -> None:
        """Move the filter's state from ``self._t`` to ``t`` (TU, a float, not the current time)."""

    def _totals(self) -> dict[str, float]:
        """Run totals added to every step's diagnostics (e.g. particles lost so far)."""
        return {}

    @property
    def diagnostics(self) -> dict[str, float]:
        self._require_init()
        d = dict(getattr(self, "_diag", {}))
        d.update(self._totals())
        return d
