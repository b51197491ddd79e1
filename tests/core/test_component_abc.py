"""Interfaces are enforced: a component missing an abstract method cannot be constructed."""
from __future__ import annotations

import pytest

from cistrack.interfaces.component import Component
from cistrack.interfaces import Clusterer, Dynamics, Filter, IODMethod, Sensor


class _NoMethodsFilter(Filter):
    pass


class _HalfFilter(Filter):
    def initialize(self, cloud, dynamics, sensor, rng):
        pass

    def predict(self, t):
        pass


def test_a_filter_without_methods_fails_to_construct():
    with pytest.raises(TypeError, match="abstract"):
        _NoMethodsFilter()


def test_a_filter_missing_update_and_belief_names_them():
    with pytest.raises(TypeError) as err:
        _HalfFilter()
    assert "update" in str(err.value) and "belief" in str(err.value)


@pytest.mark.parametrize("interface", [Dynamics, Sensor, IODMethod, Clusterer, Filter])
def test_every_interface_is_abstract(interface):
    assert issubclass(interface, Component) and interface.__abstractmethods__


def test_every_registered_component_class_implements_its_interface(registry):
    for kind in registry.kinds():
        for reg in registry.entries(kind):
            if isinstance(reg.factory, type) and issubclass(reg.factory, Component):
                assert not reg.factory.__abstractmethods__, f"{kind} {reg.name}: {sorted(reg.factory.__abstractmethods__)}"
