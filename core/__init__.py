"""cistrack: probabilistic IOD and OD in cislunar space, a plugin-based estimation framework.

The framework (this package) holds no physics choices: the interfaces, belief types,
registry, scenario files, runs, metrics and studies. Dynamics, sensors, schedules, IOD
methods, clusterers, filters and recorders are plugins (``cistrack.plugins``), found through
the entry-point group ``cistrack`` exactly like third-party ones.

``cistrack.run(...)``, ``cistrack.read_run(...)``, ``cistrack.load_scenario(...)``,
``cistrack.study(...)`` and ``cistrack.fit(...)`` run scenarios, studies and orbit fits from
Python; :mod:`cistrack.api` holds every public name (see docs/python-api.md).
"""
import sys as _sys

try:  # Ctrl-C while the ``cistrack`` command is still loading its first modules: one line, status 130
    import types as _types
    from importlib import metadata as _md

    try:
        __version__ = _md.version("cistrack")
    except _md.PackageNotFoundError:  # pragma: no cover - running from a source tree
        __version__ = "0+unknown"

    from cistrack import _moved
    from cistrack.errors import (CistrackError, ConfigError, DuplicateComponentError, FilterError, IODError,
                                 MeasurementError, ParameterError, UnknownComponentError)
    from cistrack.plugin.hookspecs import hookimpl
except KeyboardInterrupt:
    if not (_sys.argv[:1] == ["-m"] or _sys.argv[0].rsplit("/", 1)[-1] == "cistrack"):
        raise  # imported from Python: the caller's interrupt, as it came
    from cistrack.interrupts import exit_interrupted_while_starting

    exit_interrupted_while_starting()

_moved.install()  # old import paths of moved modules keep working, with a DeprecationWarning

# The belief and measurement types and the run API load on first access (PEP 562), so that
# ``import cistrack`` (and with it ``cistrack --help``) does not pay for numpy and scipy.
_LAZY = {"Belief": "model.belief", "GaussianMixture": "model.belief", "ParticleCloud": "model.belief",
         "Measurement": "model.measurement", "MeasurementSet": "model.measurement",
         "run": "api", "read_run": "api", "load_scenario": "api", "Run": "api",
         "study": "api", "StudyResult": "api", "fit": "api", "ObjectFit": "api", "read_fit": "api"}
#: Submodules that are also documented as attributes of the package (``ct.api.default_registry()``).
_LAZY_MODULES = ("api",)


def __getattr__(name: str):
    module = _LAZY.get(name)
    if module is None and name not in _LAZY_MODULES:
        raise AttributeError(f"module 'cistrack' has no attribute {name!r}")
    from importlib import import_module

    if module is None:
        return import_module(f".{name}", __name__)  # the import system sets it on the package
    value = getattr(import_module(f".{module}", __name__), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_LAZY) | set(_LAZY_MODULES))


class _Package(_types.ModuleType):
    """``cistrack.run``, ``cistrack.study`` and ``cistrack.fit`` are functions of :mod:`cistrack.api`
    whose names were also modules or packages (now :mod:`cistrack.runs.pipeline`,
    :mod:`cistrack.studies.study`, :mod:`cistrack.least_squares`): importing an old path must not
    replace the function with the module on this package (the import system sets submodules as
    attributes)."""

    def __setattr__(self, name: str, value) -> None:
        if isinstance(value, _types.ModuleType) and _LAZY.get(name) == "api":
            return
        super().__setattr__(name, value)


_sys.modules[__name__].__class__ = _Package

__all__ = [
    "__version__", "run", "read_run", "load_scenario", "Run", "study", "StudyResult", "fit", "ObjectFit",
    "Belief", "GaussianMixture", "ParticleCloud", "Measurement", "MeasurementSet",
    "hookimpl", "CistrackError", "ConfigError", "DuplicateComponentError", "FilterError", "IODError",
    "MeasurementError", "ParameterError", "UnknownComponentError",
]
