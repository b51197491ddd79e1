"""One run end to end: the pipeline (:mod:`.pipeline`: truth, measurements, IOD, the filter loop
and its observers), the run context, progress, observation files and export of a finished run.

Imports the layers below it, up to :mod:`cistrack.scenario`.
"""
