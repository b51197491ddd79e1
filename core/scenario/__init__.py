"""Scenario files: parsing and validation (:mod:`.loading`), the built-in scenarios, ``--set``
overrides, up-front limits on work and memory, and the custody table.

May import the layers below it, up to :mod:`cistrack.evaluation`.
``cistrack.scenario`` was one module before 0.2: its names (``load_scenario``, ``Scenario``, ...)
still resolve here, with a DeprecationWarning, from :mod:`cistrack.scenario.loading`.
"""
from cistrack._moved import module_getattr

__getattr__ = module_getattr(__name__, "cistrack.scenario.loading")
