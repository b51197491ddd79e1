"""The ``cistrack fit`` workflow: observation files in, a least-squares orbit per object out.

- :mod:`.from_observations`: :func:`fit_files` reads the files (:mod:`.observation_input`),
  runs the filter of a scenario built for the data, refines its estimate with
  :func:`cistrack.least_squares.fit_orbit` and returns one
  :class:`ObjectFit` per object;
  ``cistrack.fit(files, ...)`` (:func:`cistrack.api.fit`) and ``cistrack fit`` call it.
- :mod:`.fit_record`: ``fit.json``, ``residuals.csv`` and the residual plots
  (:mod:`.residual_plots`) of a fit's results folder; :mod:`.fit_export`: a fitted orbit as
  OEM / OPM; :mod:`.restart`: starting points from an earlier estimate.

The mathematics is :mod:`cistrack.least_squares`; this package sits above :mod:`cistrack.runs`
(it runs scenarios and writes results folders).
"""
