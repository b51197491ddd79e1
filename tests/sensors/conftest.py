"""Fixtures for the sensor tests: the default observer and a short NRHO truth arc (shared with
the reader tests through tests/observer_fixtures.py)."""
from observer_fixtures import nrho_arc, telescope  # noqa: F401  (tests/ is on sys.path)
