"""Each component of a run is constructed once (issue 12): counted by wrapping the ``__init__`` of
every component class, so a copy made anywhere (a filter copying its clusterer to change a
parameter) counts too, whatever kind it is."""
from __future__ import annotations

import functools
from collections import Counter
from contextlib import contextmanager

import pytest

from cistrack.interfaces.component import Component
from cistrack.plugin.registry import default_registry
from cistrack.runs.pipeline import run_scenario
from cistrack.scenario.loading import load_scenario


def _subclasses(cls):
    for sub in cls.__subclasses__():
        yield sub
        yield from _subclasses(sub)


def _counting(init, owner, counts):
    @functools.wraps(init)  # keeps the signature: components are still described by it
    def wrapper(self, *args, **kwargs):
        if next(c for c in type(self).__mro__ if "__init__" in c.__dict__) is owner:  # the outermost init only
            counts[type(self)] += 1
        return init(self, *args, **kwargs)
    return wrapper


@contextmanager
def counting_constructions():
    """Count every construction of a Component subclass, by class, while the block runs: each
    ``__init__`` of a component class is wrapped, and put back afterwards."""
    default_registry()  # every installed component class imported, so that each is counted
    counts: Counter = Counter()
    originals = {cls: cls.__dict__["__init__"] for cls in set(_subclasses(Component)) if "__init__" in cls.__dict__}
    for cls, init in originals.items():
        cls.__init__ = _counting(init, cls, counts)
    try:
        yield counts
    finally:
        for cls, init in originals.items():
            cls.__init__ = init


SMALL = {"duration_days": 1.4, "iod": {"n_particles": 200}, "run": {"predict_every_hours": 3.0}}


@pytest.mark.parametrize("filter_table", [
    {"n_particles": 200, "n_components": 2},                                    # clusterer at its default
    {"n_particles": 200, "n_components": 2, "clusterer": "kmeans"},             # named
    {"n_particles": 200, "n_components": 2, "clusterer": {"name": "gmm"}},      # a table
    {"n_particles": 200, "n_components": 3, "clusterer": {"name": "kmeans", "n_components": 3}},
], ids=["default-clusterer", "named-clusterer", "clusterer-table", "clusterer-sets-its-own"])
def test_loading_and_running_constructs_every_component_once(filter_table):
    with counting_constructions() as counts:
        scen = load_scenario("quick", overrides={**SMALL, "filter": filter_table})
        res = run_scenario(scen, seed=1)
    kinds = Counter(cls.kind for cls in counts)
    assert {"dynamics", "sensor", "schedule", "iod", "filter", "clustering"} <= set(kinds)
    twice = {cls.__name__: n for cls, n in counts.items() if n != 1 and cls.kind != "orbit"}
    assert twice == {}, f"constructed more than once: {twice}"
    clusterer = res.context.filter._clusterer
    assert clusterer.n_components == filter_table["n_components"]  # the instance built is the one used


def test_the_pgm_hands_its_n_components_to_the_clusterer_it_is_built_with():
    scen = load_scenario("quick", overrides={**SMALL, "filter": {"n_particles": 200, "n_components": 5}})
    filt = scen.build("filter")
    assert filt.clusterer.n_components == 5 and "n_components" not in scen.raw["filter"].get("clusterer", {})
