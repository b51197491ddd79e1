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

from cistrack import _moved
from cistrack.errors import (CistrackError, ConfigError, DuplicateComponentError, FilterError, IODError,
                             MeasurementError, ParameterError, UnknownComponentError)
from cistrack.plugin.hookspecs import hookimpl

_moved.install()  # old import paths of moved modules keep working, with a DeprecationWarning

# The belief and measurement types load on first access (PEP 562), so that ``import cistrack``
# (and with it ``cistrack --help``) does not pay for numpy and scipy.
_LAZY = {"Belief": "model.belief", "GaussianMixture": "model.belief", "ParticleCloud": "model.belief",
         "Measurement": "model.measurement", "MeasurementSet": "model.measurement"}


def __getattr__(name: str):
    module = _LAZY.get(name)
    if module is None:
        raise AttributeError(f"module 'cistrack' has no attribute {name!r}")
    from importlib import import_module

    value = getattr(import_module(f".{module}", __name__), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_LAZY))


__all__ = [
    "__version__", "Belief", "GaussianMixture", "ParticleCloud", "Measurement", "MeasurementSet",
    "hookimpl", "CistrackError", "ConfigError", "DuplicateComponentError", "FilterError", "IODError",
    "MeasurementError", "ParameterError", "UnknownComponentError",
]
