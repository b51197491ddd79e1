"""What a recorded run holds, read back with rerun's own reader and compared with what the run's
hooks received and with the results table."""
from __future__ import annotations

from datetime import timedelta

import numpy as np
import pytest
from rerun.chunk import RrdReader
from scipy.spatial.transform import Rotation

from cistrack.plugins.recorders.rerun_recorder import subsample_indices
from cistrack.plugins.recorders.scene import EARTH_RADIUS_KM, MOON_RADIUS_KM
from cistrack.units import LU_KM, TU_S

from .conftest import FEW_ELLIPSOIDS, N_PARTICLES, SMALL_MAX_POINTS
from .rrd_reading import component, last_per_step, read_entities


@pytest.fixture(scope="module")
def entities(recorded_run):
    return read_entities(recorded_run.full_rrd)


def _km32(states):
    return (np.asarray(states, dtype=float)[:, :3] * LU_KM).astype(np.float32)


def _by_event(rows):
    return sorted(rows, key=lambda r: r.times["event"])


def test_recording_has_the_scene_cloud_and_series_entities(entities):
    expected = {"/world/earth", "/world/moon", "/world/libration", "/world/truth/trajectory",
                "/world/truth/position", "/world/particles", "/world/components", "/world/estimate",
                "/world/observer", "/world/line_of_sight", "/components/weights", "/run/info",
                "/run/summary", "/metrics/entropy", "/metrics/pos_err_km", "/metrics/vel_err_ms",
                "/metrics/nees", "/metrics/sigma_x_km", "/metrics/sigma_vz_cms"}
    assert expected <= set(entities)


def test_recording_carries_a_default_blueprint(recorded_run):
    assert len(RrdReader(str(recorded_run.full_rrd)).blueprints()) == 1


def test_earth_and_moon_are_spheres_to_scale_at_the_primaries(entities, recorded_run):
    mu = recorded_run.result.context.dynamics.mu
    earth, moon = entities["/world/earth"][0], entities["/world/moon"][0]
    np.testing.assert_allclose(component(earth, "Ellipsoids3D:centers")[0], [-mu * LU_KM, 0, 0], rtol=1e-6)
    np.testing.assert_allclose(component(moon, "Ellipsoids3D:centers")[0], [(1 - mu) * LU_KM, 0, 0], rtol=1e-6)
    np.testing.assert_allclose(component(earth, "Ellipsoids3D:half_sizes")[0], [EARTH_RADIUS_KM] * 3, rtol=1e-6)
    np.testing.assert_allclose(component(moon, "Ellipsoids3D:half_sizes")[0], [MOON_RADIUS_KM] * 3, rtol=1e-6)


def test_libration_points_are_labelled_and_placed(entities):
    row = entities["/world/libration"][0]
    assert row.components["Points3D:labels"] == ["L1", "L2", "L3", "L4", "L5"]
    pos = component(row, "Points3D:positions")
    np.testing.assert_allclose(pos[:2, 0] / LU_KM, [0.8369151, 1.1556822], atol=1e-7)


def test_truth_trajectory_is_the_runs_dense_truth_in_km(entities, recorded_run):
    strip = np.asarray(entities["/world/truth/trajectory"][0].components["LineStrips3D:strips"][0])
    np.testing.assert_array_equal(strip.astype(np.float32), _km32(recorded_run.result.context.truth_states))


def test_one_particle_row_per_hook_call_covering_every_step(entities, recorded_run):
    rows = entities["/world/particles"]
    assert len(rows) == len(recorded_run.log.events)
    assert sorted(last_per_step(rows)) == sorted(recorded_run.table.column("step").to_pylist())


def test_particles_equal_the_filters_particles_in_km_at_every_event(entities, recorded_run):
    rows = _by_event(entities["/world/particles"])
    for row, ev in zip(rows, recorded_run.log.events):
        assert row.times["step"] == ev.index
        np.testing.assert_array_equal(component(row, "Points3D:positions").astype(np.float32), _km32(ev.states))


def test_particles_shown_at_a_step_are_the_posterior_of_that_step(entities, recorded_run):
    step = 3
    posterior = [e for e in recorded_run.log.events if e.index == step][-1]
    assert posterior.hook == "updated"
    row = last_per_step(entities["/world/particles"])[step]
    np.testing.assert_array_equal(component(row, "Points3D:positions").astype(np.float32),
                                  _km32(posterior.states))


def test_particles_are_coloured_by_component_label(entities, recorded_run):
    rows = _by_event(entities["/world/particles"])
    labelled = [(r, e) for r, e in zip(rows, recorded_run.log.events) if e.labels is not None]
    assert labelled, "the PGM filter labels its particles by component"
    for row, ev in labelled:
        np.testing.assert_array_equal(np.asarray(row.components["Points3D:class_ids"]), ev.labels)


def test_max_points_logs_the_seeded_subsample(recorded_run):
    rows = _by_event(read_entities(recorded_run.small_rrd)["/world/particles"])
    for row, ev in zip(rows, recorded_run.log.events):
        assert ev.states.shape[0] == N_PARTICLES
        keep = subsample_indices(N_PARTICLES, SMALL_MAX_POINTS, 0, labels=ev.labels)
        assert keep.shape == (SMALL_MAX_POINTS,)
        np.testing.assert_array_equal(component(row, "Points3D:positions").astype(np.float32),
                                      _km32(ev.states[keep]))


def test_max_points_keeps_particles_of_every_component(recorded_run):
    rows = _by_event(read_entities(recorded_run.small_rrd)["/world/particles"])
    labelled = [(r, e) for r, e in zip(rows, recorded_run.log.events) if e.labels is not None]
    assert labelled
    for row, ev in labelled:
        shown = np.asarray(row.components["Points3D:class_ids"])
        assert set(shown.tolist()) == set(np.asarray(ev.labels).tolist())


def test_max_ellipsoids_logs_the_heaviest_components_ellipsoids(recorded_run):
    rows = _by_event(read_entities(recorded_run.few_ellipsoids_rrd)["/world/components"])
    events = recorded_run.log.events
    assert len(rows) == len(events) and max(e.weights.size for e in events) > FEW_ELLIPSOIDS
    for row, ev in zip(rows, events):
        heaviest = sorted(np.argsort(-ev.weights, kind="stable")[:FEW_ELLIPSOIDS].tolist())
        assert [int(i) for i in row.components["Ellipsoids3D:class_ids"]] == heaviest
        np.testing.assert_allclose(component(row, "Ellipsoids3D:centers"), ev.means[heaviest, :3] * LU_KM,
                                   rtol=1e-6)


def _series_match_table(entities, table, entity_prefix, column_prefix, names):
    steps = table.column("step").to_pylist()
    for name in names:
        values = np.asarray(table.column(column_prefix + name).to_pylist(), dtype=float)
        logged = {s: component(r, "Scalars:scalars")[0]
                  for s, r in last_per_step(entities.get(f"{entity_prefix}/{name}", [])).items()}
        expected = {s: v for s, v in zip(steps, values) if np.isfinite(v)}
        assert logged == expected, name


def test_metric_series_equal_the_results_table(entities, recorded_run):
    names = sorted({k for e in recorded_run.log.events for k in e.metrics})
    assert {"entropy", "pos_err_km", "vel_err_ms", "nees", "sigma_x_km", "sigma_vz_cms"} <= set(names)
    _series_match_table(entities, recorded_run.table, "/metrics", "", names)


def test_diagnostic_series_equal_the_results_table(entities, recorded_run):
    names = [c[len("diag_"):] for c in recorded_run.table.column_names if c.startswith("diag_")]
    assert names, "the PGM filter reports diagnostics"
    _series_match_table(entities, recorded_run.table, "/diagnostics", "diag_", names)


def test_one_metrics_row_per_results_row(entities, recorded_run):
    rows = entities["/metrics/entropy"]
    assert [r.times["step"] for r in rows] == recorded_run.table.column("step").to_pylist()


def test_component_weights_series_are_the_mixture_weights(entities, recorded_run):
    with_metrics = [e for e in recorded_run.log.events if e.metrics]
    rows = _by_event(entities["/components/weights"])
    assert len(rows) == len(with_metrics)
    for row, ev in zip(rows, with_metrics):
        np.testing.assert_array_equal(component(row, "Scalars:scalars"), ev.weights)


def test_utc_timeline_is_epoch_plus_step_time(entities, recorded_run):
    epoch = recorded_run.result.context.epoch
    for row, ev in zip(_by_event(entities["/world/particles"]), recorded_run.log.events):
        expected = epoch + timedelta(seconds=ev.t * TU_S)
        expected_ns = int(round(expected.timestamp() * 1e6)) * 1000
        assert abs(row.times["utc"] - expected_ns) <= 1000


def test_ellipsoids_are_three_sigma_position_surfaces_of_the_components(entities, recorded_run):
    rows = _by_event(entities["/world/components"])
    rng = np.random.default_rng(0)
    for row, ev in zip(rows, recorded_run.log.events):
        centers = component(row, "Ellipsoids3D:centers")
        half = component(row, "Ellipsoids3D:half_sizes")
        quat = component(row, "Ellipsoids3D:quaternions")
        np.testing.assert_allclose(centers, ev.means[:, :3] * LU_KM, rtol=1e-6)
        u = rng.standard_normal((50, 3))
        u /= np.linalg.norm(u, axis=1, keepdims=True)
        for i in range(centers.shape[0]):
            surface_km = Rotation.from_quat(quat[i]).apply(u * half[i])
            p = ev.covariances[i, :3, :3] * LU_KM**2
            maha = np.sqrt(np.einsum("ni,ij,nj->n", surface_km, np.linalg.inv(p), surface_km))
            np.testing.assert_allclose(maha, 3.0, rtol=2e-3)


def test_line_of_sight_starts_at_the_observer_and_passes_by_the_truth(entities, recorded_run):
    sensor = recorded_run.result.context.sensor
    strips = [r for r in _by_event(entities["/world/line_of_sight"]) if "LineStrips3D:strips" in r.components]
    updates = [e for e in recorded_run.log.events if e.has_measurement]
    assert len(strips) == len(updates) > 0
    for row, ev in zip(strips, updates):
        a, b = np.asarray(row.components["LineStrips3D:strips"][0], dtype=float)
        np.testing.assert_allclose(a, sensor.observer_position(ev.t) * LU_KM, atol=0.1)
        d = (b - a) / np.linalg.norm(b - a)
        off = ev.truth[:3] * LU_KM - a
        miss_km = np.linalg.norm(off - (off @ d) * d)
        assert miss_km < 30.0  # 1.5 arcsec noise is ~3 km across at lunar distance
        assert np.linalg.norm(b - a) > off @ d  # the drawn line reaches past the target


def test_line_of_sight_is_cleared_on_steps_without_a_measurement(entities, recorded_run):
    rows = _by_event(entities["/world/line_of_sight"])
    for row, ev in zip(rows, recorded_run.log.events):
        assert ("Clear:is_recursive" in row.components) == (not ev.has_measurement)
