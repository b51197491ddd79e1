"""What a run leaves on disk and how it is read back: the results writer and manifest
(:mod:`.store`), per-step tables, estimates, part files, run status, output paths.

May import the layers below it: base, model, interfaces, plugin, propagation, astro.
``cistrack.results`` was one module before 0.2: its names (``ResultsWriter``, ``read_steps``,
...) still resolve here, with a DeprecationWarning, from :mod:`cistrack.results.store`.
"""
from cistrack._moved import module_getattr

__getattr__ = module_getattr(__name__, "cistrack.results.store")
