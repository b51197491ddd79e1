"""Conformance suite for cistrack plugins, in the spirit of scikit-learn's ``check_estimator``.

A plugin author runs every check that applies to their component::

    from cistrack.testing import check_plugin
    check_plugin(MyFilter)                 # raises ConformanceError naming each failing check

or, in a pytest module, one test per check::

    from cistrack.testing import parametrize_with_checks

    @parametrize_with_checks([MyFilter, MyClusterer])
    def test_conformance(component, check):
        check(component)

``check_registered("pgm")`` runs the checks of a registered name and returns the results
(``cistrack plugins --check NAME`` prints them). The checks use small fixtures near the 9:2
NRHO (:mod:`cistrack.testing.fixtures`) and, for filters and IOD methods, a reference CR3BP and
a geocentric angles sensor shipped here, so they do not depend on any other plugin.
"""
from cistrack.testing.fixtures import NRHO_9_2_APOLUNE
from cistrack.testing.reference_dynamics import ReferenceCR3BP
from cistrack.testing.reference_sensor import GeocentricAnglesSensor
from cistrack.testing.check_results import CheckResult, ConformanceError, ConformanceReport
from cistrack.testing.suite import (KIND_CHECKS, BoundCheck, check_plugin, check_registered, infer_kind, iter_checks, parametrize_with_checks)

__all__ = [
    "check_plugin", "check_registered", "iter_checks", "parametrize_with_checks", "infer_kind",
    "CheckResult", "ConformanceError", "ConformanceReport", "BoundCheck", "KIND_CHECKS",
    "ReferenceCR3BP", "GeocentricAnglesSensor", "NRHO_9_2_APOLUNE",
]
