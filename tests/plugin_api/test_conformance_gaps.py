"""The conformance suite catches a filter that changes the dynamics or sensor it is given, one that
reports impossible documented diagnostics, and a clusterer that returns more clusters than its
n_components (or max_components) allows."""
from __future__ import annotations

import numpy as np
import pytest

from cistrack.interfaces import Clusterer
from cistrack.interfaces.component import check_int
from cistrack.plugins.filters.ukf import UKFFilter
from cistrack.testing import ConformanceError, iter_checks


def _run_check(component, name: str) -> None:
    [check] = [c for n, c in iter_checks(component) if n == name]
    check()


class MutatesSensor(UKFFilter):
    """UKF that scales the float attributes of the sensor it is given."""

    def initialize(self, cloud, dynamics, sensor, rng):
        for key, value in list(vars(sensor).items()):
            if isinstance(value, float):
                setattr(sensor, key, value * 10)
        super().initialize(cloud, dynamics, sensor, rng)


class MutatesDynamics(UKFFilter):
    """UKF that changes the mass ratio of the dynamics it is given."""

    def initialize(self, cloud, dynamics, sensor, rng):
        dynamics.mu = dynamics.mu * 1.01
        super().initialize(cloud, dynamics, sensor, rng)


@pytest.mark.parametrize("cls, what", [(MutatesSensor, "sensor"), (MutatesDynamics, "dynamics")])
def test_a_filter_that_changes_its_sensor_or_dynamics_fails_inputs_not_mutated(cls, what):
    with pytest.raises(ConformanceError, match=f"the input '{what}' was modified in place"):
        _run_check(cls, "inputs_not_mutated")


def _bad_diagnostics(key: str, value: float) -> type:
    class BadDiagnostics(UKFFilter):
        """UKF reporting one impossible documented diagnostic."""

        @property
        def diagnostics(self):
            return {**super().diagnostics, key: value}

    return BadDiagnostics


@pytest.mark.parametrize("key, value", [("n_particles", -5.0), ("n_components", float("inf")),
                                        ("ess_before_resampling", float("nan")), ("unique_particles", "many")])
def test_an_impossible_documented_diagnostic_fails_the_lifecycle_check_naming_it(key, value):
    with pytest.raises(ConformanceError, match=rf"diagnostics\['{key}'\] after initialize\(\) is .*a finite number >= 0"):
        _run_check(_bad_diagnostics(key, value), "lifecycle_and_belief")


class Singletons(Clusterer):
    """Every particle its own cluster, whatever n_components says.

    Parameters
    ----------
    n_components : int
        Clusters wanted (ignored).
    """

    def __init__(self, n_components: int = 3):
        self.n_components = check_int(self, "n_components", n_components, minimum=1)

    def cluster(self, x, rng):
        return np.arange(x.shape[0])


class SingletonsUpTo(Clusterer):
    """Every particle its own cluster, whatever max_components says.

    Parameters
    ----------
    max_components : int
        Most clusters (ignored).
    """

    def __init__(self, max_components: int = 8):
        self.max_components = check_int(self, "max_components", max_components, minimum=1)

    def cluster(self, x, rng):
        return np.arange(x.shape[0])


@pytest.mark.parametrize("clusterer, said", [(Singletons(n_components=3), "given n_components=3"),
                                             (SingletonsUpTo(), "given max_components=8")])
def test_a_clusterer_returning_more_clusters_than_its_limit_fails_naming_it(clusterer, said):
    with pytest.raises(ConformanceError, match=f"{said}, cluster\\(\\) returned 200 clusters of 200 particles"):
        _run_check(clusterer, "respects_n_components")


class ChoosesItsOwnCount(Singletons):
    """Treats n_components as a hint (and here ignores it)."""

    chooses_n_components = True


def test_a_clusterer_that_says_it_chooses_the_count_is_not_held_to_n_components():
    _run_check(ChoosesItsOwnCount(n_components=3), "respects_n_components")
