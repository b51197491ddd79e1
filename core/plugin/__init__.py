"""The plugin machinery: lifecycle hook specifications, the component registry (entry-point
loading, names, duplicates), component tables of scenario files and parameter documentation.

Imports the base modules, :mod:`cistrack.model` and :mod:`cistrack.interfaces`.
"""
