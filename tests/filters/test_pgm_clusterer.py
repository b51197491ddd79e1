"""How the PGM gets its clusterer: built through the run's registry, n_components in one place."""
from __future__ import annotations

import pytest

from cistrack.errors import ParameterError
from cistrack.plugins.filters.pgm import resolve_clusterer
from cistrack.scenario.loading import load_scenario


def test_a_default_clusterer_name_is_built_through_the_scenarios_registry(registry):
    scen = load_scenario("quick", registry)
    spec = scen.components["filter"].params["clusterer"]
    assert spec.kind == "clustering"
    pgm = scen.build("filter", registry)
    assert not isinstance(pgm.clusterer, str) and pgm.clusterer.kind == "clustering"


def test_the_filters_n_components_reaches_a_clusterer_left_at_its_default(registry):
    km = registry.create("clustering", "kmeans")
    default = km.n_components
    resolved = resolve_clusterer(km, default + 1, registry)
    assert resolved.n_components == default + 1
    assert km.n_components == default, "the caller's instance is not modified"


def test_a_clusterer_with_its_own_different_n_components_is_refused(registry):
    km = registry.create("clustering", "kmeans")
    own = km.n_components + 2
    km2 = registry.create("clustering", "kmeans", n_components=own)
    with pytest.raises(ParameterError, match="n_components"):
        resolve_clusterer(km2, own + 1, registry)


def test_agreeing_values_keep_the_instance(registry):
    km = registry.create("clustering", "kmeans", n_components=5)
    assert resolve_clusterer(km, 5, registry) is km
