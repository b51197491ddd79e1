"""The PGM hands its clusterer the particles read-only (a view, not a copy): a clusterer that
writes into its input fails the filter naming the clusterer, instead of moving the filter's
particles (a clusterer centring its input in place had sent every particle to the barycentre, and
the run had blamed the PGM: "every particle hit a body"). A clusterer that raises its own exception
is named the same way (the run had blamed the PGM for it)."""
from __future__ import annotations

import numpy as np
import pytest

from cistrack.errors import FilterError
from cistrack.plugin.registry import load_registry
from cistrack.plugins.clustering.kmeans import KMeansClusterer
from cistrack.runs.pipeline import run_scenario
from cistrack.scenario.loading import load_scenario


class CentresInPlace(KMeansClusterer):
    """k-means that first centres its input in place (the bug)."""

    def cluster(self, x, rng):
        x -= x.mean(axis=0)
        return super().cluster(x, rng)


class RecordsWriteable(KMeansClusterer):
    """k-means that records whether each input it is handed could be written."""

    seen: list = []

    def cluster(self, x, rng):
        type(self).seen.append(bool(x.flags.writeable))
        return super().cluster(x, rng)


class RaisesLater(KMeansClusterer):
    """k-means that raises its own RuntimeError from its third call on."""

    calls = 0

    def cluster(self, x, rng):
        type(self).calls += 1
        if type(self).calls >= 3:
            raise RuntimeError("clusterer bug")
        return super().cluster(x, rng)


def _run(cls):
    reg = load_registry(autoload_third_party=False)
    reg.add("clustering", "h-clusterer", cls, "hplug", "0.1", "hplug")
    scen = load_scenario("quick", reg, overrides={
        "duration_days": 1.4, "filter": {"n_particles": 200, "n_components": 2, "clusterer": "h-clusterer"},
        "iod": {"n_particles": 200}})
    return run_scenario(scen, seed=1, registry=reg)


def test_a_clusterer_writing_into_its_input_fails_the_filter_naming_the_clusterer():
    with pytest.raises(FilterError, match=r"^filter 'pgm': clusterer 'h-clusterer': cluster\(\) tried to write into "
                                          r"the particles it was given \(.*read-only\); a clusterer must not change "
                                          r"its input"):
        _run(CentresInPlace)


def test_the_clusterer_is_handed_read_only_particles_at_every_step():
    RecordsWriteable.seen = []
    res = _run(RecordsWriteable)
    assert res.summary.status == "finished"
    assert RecordsWriteable.seen and not np.any(RecordsWriteable.seen)


def test_a_clusterer_raising_its_own_exception_mid_run_ends_it_filter_failed_naming_the_clusterer():
    RaisesLater.calls = 0
    res = _run(RaisesLater)
    assert res.summary.status == "filter-failed"
    assert res.summary.failure.startswith("FilterError: filter 'pgm': clusterer 'h-clusterer': cluster() raised "
                                          "RuntimeError: clusterer bug")
