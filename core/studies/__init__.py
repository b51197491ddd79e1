"""Studies: grids of scenarios x filters x IOD variants x seeds run through an executor, resumed
after interruption, and reported as tables and figures (calibration, verdicts, HDR shares).

Imports the layers below it, up to :mod:`cistrack.runs` and :mod:`cistrack.testing`.
"""
