"""Old import paths of modules that moved, kept working for at least one release.

``import cistrack.belief`` (or ``from cistrack.belief import ParticleCloud``) still works after
the module moved to :mod:`cistrack.model.belief`: a finder on :data:`sys.meta_path` answers the
old name with the module at its new path (the same module object, so classes, ``isinstance``
checks and pickles are unchanged) and issues a :class:`DeprecationWarning` that names the new
path, attributed to the line that imported the old one.

:data:`MOVED` is the one table of such moves; ``tests/core/test_moved_modules.py`` imports every
old path in it, and ``cistrack plugins --check`` lists the old paths a plugin still uses.
"""
from __future__ import annotations

import importlib
import importlib.util
import importlib.abc
import importlib.machinery
import sys
import warnings
from types import ModuleType
from typing import Any

#: old module path -> new module path. Moved in 0.2 (the regrouping of core into packages)
#: unless marked otherwise; remove an entry no earlier than the release after the one that moved it.
MOVED: dict[str, str] = {
    "cistrack.component": "cistrack.interfaces.component",
    "cistrack.belief": "cistrack.model.belief",
    "cistrack.measurement": "cistrack.model.measurement",
    "cistrack.hookspecs": "cistrack.plugin.hookspecs",
    "cistrack.registry": "cistrack.plugin.registry",
    "cistrack.param_docs": "cistrack.plugin.param_docs",
    "cistrack.component_tables": "cistrack.plugin.component_tables",
    "cistrack.primaries": "cistrack.astro.primaries",
    "cistrack.timescales": "cistrack.astro.timescales",
    "cistrack.ephemeris": "cistrack.astro.ephemeris",
    "cistrack.frames": "cistrack.astro",
    "cistrack.frames.earth_moon": "cistrack.astro.earth_moon",
    "cistrack.rotating_frame": "cistrack.astro.rotating_frame",
    "cistrack.observer": "cistrack.astro.observer",
    "cistrack.sky": "cistrack.astro.sky",
    "cistrack.sites": "cistrack.astro.sites",
    "cistrack.site_network": "cistrack.astro.site_network",
    "cistrack.site_simulation": "cistrack.astro.site_simulation",
    "cistrack.part_files": "cistrack.results.part_files",
    "cistrack.fingerprint": "cistrack.results.fingerprint",
    "cistrack.step_table": "cistrack.results.step_table",
    "cistrack.estimates": "cistrack.results.estimates",
    "cistrack.inertial_frame": "cistrack.results.inertial_frame",
    "cistrack.run_status": "cistrack.results.run_status",
    "cistrack.output_paths": "cistrack.results.output_paths",
    "cistrack.custody": "cistrack.evaluation.custody",
    "cistrack.metrics": "cistrack.evaluation.metrics",
    "cistrack.consistency": "cistrack.evaluation.consistency",
    "cistrack.residuals": "cistrack.evaluation.residuals",
    "cistrack.verdicts": "cistrack.evaluation.verdicts",
    "cistrack.run_summary": "cistrack.evaluation.run_summary",
    "cistrack.builtin_scenarios": "cistrack.scenario.builtin_scenarios",
    "cistrack.settings": "cistrack.scenario.settings",
    "cistrack.limits": "cistrack.scenario.limits",
    "cistrack.custody_table": "cistrack.scenario.custody_table",
    "cistrack.run": "cistrack.runs.pipeline",
    "cistrack.run_context": "cistrack.runs.run_context",
    "cistrack.truth": "cistrack.runs.truth",
    "cistrack.progress": "cistrack.runs.progress",
    "cistrack.observation_files": "cistrack.runs.observation_files",
    "cistrack.export": "cistrack.runs.export",
    "cistrack.study": "cistrack.studies.study",
    "cistrack.study_file": "cistrack.studies.study_file",
    "cistrack.study_resume": "cistrack.studies.resume",
    "cistrack.study_report": "cistrack.studies.report",
    "cistrack.report_plots": "cistrack.studies.report_plots",
    "cistrack.report_verdicts": "cistrack.studies.report_verdicts",
    "cistrack.calibration": "cistrack.studies.calibration",
    "cistrack.calibration_plots": "cistrack.studies.calibration_plots",
    "cistrack.study_cli": "cistrack.cli.study",
    "cistrack.process_exit": "cistrack.cli.process_exit",
    "cistrack.signals": "cistrack.cli.signals",
    # Moved earlier without an alias (the plugin package of issue 26 broke on the first).
    "cistrack.plugins.dynamics.compiled": "cistrack.propagation.compiled",
    "cistrack.plugins.dynamics.integrator_dop853": "cistrack.propagation.dop853_source",
    "cistrack.run_types": "cistrack.runs.run_context",
    "cistrack.testing.results": "cistrack.testing.check_results",
    "cistrack.plugins.clustering.standardize": "cistrack.plugins.clustering.points_and_labels",
    "cistrack.plugins.filters.observation": "cistrack.plugins.filters.measured_components",
    # Issue 48: the PGM became a package of components (cistrack.plugins.filters.pgm).
    "cistrack.plugins.filters.cluster_merge": "cistrack.plugins.filters.pgm.cluster_merge",
    "cistrack.plugins.filters.clusterer_choice": "cistrack.plugins.filters.pgm.clusterer_choice",
    "cistrack.plugins.filters.component_spread": "cistrack.plugins.filters.pgm.component_spread",
    "cistrack.plugins.filters.component_update": "cistrack.plugins.filters.pgm.component_update",
    "cistrack.plugins.filters.kernel_update": "cistrack.plugins.filters.pgm.kernel_update",
    "cistrack.plugins.filters.measurement_sharpness": "cistrack.plugins.filters.pgm.measurement_sharpness",
    "cistrack.plugins.filters.posterior_transform": "cistrack.plugins.filters.pgm.posterior_transform",
    "cistrack.plugins.filters.reanchoring": "cistrack.plugins.filters.pgm.reanchoring",
    "cistrack.plugins.filters.reacquisition_particles": "cistrack.plugins.filters.pgm.reacquisition_particles",
    "cistrack.plugins.filters.state_bounds": "cistrack.plugins.filters.pgm.state_bounds",
    # Issue 48: cistrack.fit split into the mathematics and the `cistrack fit` workflow.
    "cistrack.fit": "cistrack.least_squares",
    "cistrack.fit.least_squares": "cistrack.least_squares.differential_correction",
    "cistrack.fit.errors": "cistrack.least_squares.errors",
    "cistrack.fit.line_of_variations": "cistrack.least_squares.line_of_variations",
    "cistrack.fit.measurement_model": "cistrack.least_squares.measurement_model",
    "cistrack.fit.observability": "cistrack.least_squares.observability",
    "cistrack.fit.options": "cistrack.least_squares.options",
    "cistrack.fit.outliers": "cistrack.least_squares.outliers",
    "cistrack.fit.prediction": "cistrack.least_squares.prediction",
    "cistrack.fit.residual_table": "cistrack.least_squares.residual_table",
    "cistrack.fit.result": "cistrack.least_squares.result",
    "cistrack.fit.trajectory": "cistrack.least_squares.trajectory",
    "cistrack.fit.unscented_prediction": "cistrack.least_squares.unscented_prediction",
    "cistrack.fit.fit_export": "cistrack.fitting.fit_export",
    "cistrack.fit.fit_record": "cistrack.fitting.fit_record",
    "cistrack.fit.from_observations": "cistrack.fitting.from_observations",
    "cistrack.fit.observation_input": "cistrack.fitting.observation_input",
    "cistrack.fit.residual_plots": "cistrack.fitting.residual_plots",
    "cistrack.fit.restart": "cistrack.fitting.restart",
    # Issue 48: cmd_export back in the command's module (it was split out only to fit a file-size cap).
    "cistrack.cli.export_command": "cistrack.cli.main",
}


def moved_message(old: str, new: str) -> str:
    return (f"{old} moved to {new}; import it from there "
            f"(the old path keeps working, with this warning, until the next release)")


class _ExistingModule(importlib.abc.Loader):
    """Loads an old name as the module already imported at its new path."""

    def __init__(self, module: ModuleType) -> None:
        self._module = module

    def create_module(self, spec: importlib.machinery.ModuleSpec) -> ModuleType:
        return self._module

    def exec_module(self, module: ModuleType) -> None:
        """Nothing to run: the module was executed once, under its new name."""


class MovedModuleFinder(importlib.abc.MetaPathFinder):
    """Answers the old paths in :data:`MOVED` (and nothing else) with the moved modules."""

    def find_spec(self, fullname: str, path=None, target=None):
        new = MOVED.get(fullname)
        if new is None:
            return None
        # stacklevel 2 is the importing line: the warnings module skips importlib's own frames.
        warnings.warn(moved_message(fullname, new), DeprecationWarning, stacklevel=2)
        module = importlib.import_module(new)
        _set_on_function(fullname, module)
        _names_on_function(fullname, module)
        return importlib.machinery.ModuleSpec(fullname, _ExistingModule(module),
                                              is_package=hasattr(module, "__path__"))


def _set_on_function(fullname: str, module: ModuleType) -> None:
    """``import cistrack.fit.least_squares as m`` reaches ``m`` by attributes: where a function now
    holds the old package's name (``cistrack.fit`` is :func:`cistrack.api.fit`), the old submodule
    is set as an attribute of that function."""
    parent, _, child = fullname.rpartition(".")
    holder, _, name = parent.rpartition(".")
    if parent in MOVED and holder in sys.modules:
        function = getattr(sys.modules[holder], name, None)
        if callable(function) and not isinstance(function, ModuleType):
            setattr(function, child, module)


def _names_on_function(fullname: str, module: ModuleType) -> None:
    """``import cistrack.run as pipeline`` binds ``pipeline`` to the package's attribute ``run``, which
    is now the function :func:`cistrack.api.run`: the moved module's public names (its ``__all__``) are
    set on that function, so that ``pipeline.run_scenario`` keeps working. This import is the one
    that gave the DeprecationWarning naming the new module."""
    holder, _, name = fullname.rpartition(".")
    if holder not in sys.modules:
        return
    function = getattr(sys.modules[holder], name, None)
    if not callable(function) or isinstance(function, ModuleType):
        return
    for public in getattr(module, "__all__", ()):
        if not hasattr(function, public):
            setattr(function, public, getattr(module, public))


def renamed_names(module: str, renames: dict[str, tuple[str, Any]]):
    """A module ``__getattr__`` that answers each old name in ``renames`` (old -> (new name, the
    object)) with the object and a DeprecationWarning naming the new one, for at least one release."""
    def __getattr__(name: str) -> Any:
        if name in renames:
            new, obj = renames[name]
            warnings.warn(f"{module}.{name} is now {new}; import it by that name (the old one keeps working, "
                          "with this warning, until the next release)", DeprecationWarning, stacklevel=2)
            return obj
        raise AttributeError(f"module {module!r} has no attribute {name!r}")

    return __getattr__


def install() -> None:
    """Put the finder first on :data:`sys.meta_path` (once per process)."""
    if not any(isinstance(f, MovedModuleFinder) for f in sys.meta_path):
        sys.meta_path.insert(0, MovedModuleFinder())


def module_getattr(package: str, module: str):
    """A PEP 562 ``__getattr__`` for a package that replaced a module of the same name.

    ``cistrack.results`` was a module and is now a package whose results writer lives in
    ``cistrack.results.store``: ``from cistrack.results import ResultsWriter`` keeps working,
    with a DeprecationWarning naming the new module, and imports that module only when asked.
    """
    def __getattr__(name: str):
        if name.startswith("_"):
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        if importlib.util.find_spec(f"{package}.{name}") is not None:  # a submodule of the package, not a moved name
            return importlib.import_module(f"{package}.{name}")
        target = importlib.import_module(module)
        try:
            value = getattr(target, name)
        except AttributeError:
            raise AttributeError(f"module {package!r} has no attribute {name!r}") from None
        warnings.warn(moved_message(f"{package}.{name}", f"{module}.{name}"), DeprecationWarning, stacklevel=2)
        return value

    return __getattr__
