"""cistrack: probabilistic IOD and OD in cislunar space, a plugin-based estimation framework.

The framework (this package) holds no physics choices: the interfaces, belief types,
registry, scenario files, runs, metrics and studies. Dynamics, sensors, schedules, IOD
methods, clusterers, filters and recorders are plugins (``cistrack.plugins``), found through
the entry-point group ``cistrack`` exactly like third-party ones.
"""
from importlib import metadata as _md

try:
    __version__ = _md.version("cistrack")
except _md.PackageNotFoundError:  # pragma: no cover - running from a source tree
    __version__ = "0+unknown"

from .belief import Belief, GaussianMixture, ParticleCloud
from .errors import (CistrackError, ConfigError, DuplicateComponentError, FilterError, IODError,
                     MeasurementError, ParameterError, UnknownComponentError)
from .hookspecs import hookimpl
from .measurement import Measurement, MeasurementSet

__all__ = [
    "__version__", "Belief", "GaussianMixture", "ParticleCloud", "Measurement", "MeasurementSet",
    "hookimpl", "CistrackError", "ConfigError", "DuplicateComponentError", "FilterError", "IODError",
    "MeasurementError", "ParameterError", "UnknownComponentError",
]
