"""The step table's stage timings: each stage's time holds the work done in it. The PGM clusters
its particles in its update (the prior's components); a prediction alone carries each particle's
component and clusters nothing."""
from __future__ import annotations

import time

from cistrack.plugin.registry import load_registry
from cistrack.plugins.clustering.kmeans import KMeansClusterer
from cistrack.runs.pipeline import run_scenario
from cistrack.scenario.loading import load_scenario

PAUSE_S = 0.05


class _PausingKMeans(KMeansClusterer):
    """The real k-means, after a pause of PAUSE_S: a clusterer whose time is known to be at least that."""

    calls = 0

    def cluster(self, x, rng):
        type(self).calls += 1
        time.sleep(PAUSE_S)
        return super().cluster(x, rng)


def _run_with_pausing_clusterer():
    reg = load_registry()
    reg.add("clustering", "pausing-kmeans", _PausingKMeans)
    scen = load_scenario("quick", reg, overrides={
        "duration_days": 1.4, "filter": {"n_particles": 200, "n_components": 2, "clusterer": "pausing-kmeans"},
        "iod": {"n_particles": 200}, "run": {"predict_every_hours": 3.0}})
    _PausingKMeans.calls = 0
    return run_scenario(scen, seed=2, registry=reg)


def test_the_pgm_clustering_counts_in_the_update_time():
    res = _run_with_pausing_clusterer()
    updates = [r for r in res.rows if r["kind"] == "update"]
    assert updates and _PausingKMeans.calls >= len(updates)
    assert min(r["time_update_s"] for r in updates) >= PAUSE_S


def test_a_pgm_prediction_alone_clusters_nothing():
    res = _run_with_pausing_clusterer()
    kinds = [r["kind"] for r in res.rows]
    assert "predict" in kinds
    assert _PausingKMeans.calls == kinds.count("update") + kinds.count("initial")
