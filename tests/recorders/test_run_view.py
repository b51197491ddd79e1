"""The run view's frame and the plotted series, read back from a recorded run.

The run view shows the scene from ``world/estimate_frame``: radial / along-track / cross-track
about the estimate, one unit per axis = the cloud's extent along it. These tests carry the logged particles into
that frame with the logged transform and check that the cloud sits on the origin with the
belief's spread at every event, and that the series are the log10 of the results table.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from cistrack.plugins.recorders.estimate_frame import CLOUD_QUANTILE, MAX_ASPECT, cloud_units_km, ric_axes
from cistrack.plugins.recorders.run_series import NEES_BAND, ranked_weights
from cistrack.units import LU_KM

from .rrd_reading import component, last_per_step, read_entities


@pytest.fixture(scope="module")
def entities(recorded_run):
    return read_entities(recorded_run.full_rrd)


def _by_event(rows):
    return sorted((r for r in rows if "event" in r.times), key=lambda r: r.times["event"])


def _frame(row) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(translation (3,) km, axes (3, 3), units (3,) km) of a logged frame transform, whose
    matrix is axes @ diag(units)."""
    mat = component(row, "Transform3D:mat3x3").reshape(3, 3).T  # stored column by column
    units = np.linalg.norm(mat, axis=0)
    return component(row, "Transform3D:translation").reshape(3), mat / units, units


def _total_position_covariance_km2(ev) -> np.ndarray:
    mean = ev.weights @ ev.means
    diff = ev.means - mean
    cov = np.einsum("m,mij->ij", ev.weights, ev.covariances) + np.einsum("m,mi,mj->ij", ev.weights, diff, diff)
    return cov[:3, :3] * LU_KM**2


def test_the_run_view_entities_are_recorded(entities):
    expected = {"/world/estimate_frame", "/world/estimate_frame/axes", "/world/estimate_frame/axis_labels",
                "/world/estimate_frame/line_of_sight",
                "/series/position/error", "/series/position/sigma_x", "/series/velocity/sigma_vz",
                "/series/nees/nees", "/series/nees/band_5", "/series/nees/band_95", "/components/ranked/1"}
    assert expected <= set(entities)


def test_the_frame_follows_the_estimate_with_radial_along_and_cross_track_axes(entities, recorded_run):
    mu = recorded_run.result.context.dynamics.mu
    earth_km = np.array([-mu, 0.0, 0.0]) * LU_KM
    rows = _by_event(entities["/world/estimate_frame"])
    assert len(rows) == len(recorded_run.log.events)
    for row, ev in zip(rows, recorded_run.log.events):
        origin, axes, _ = _frame(row)
        mean = ev.weights @ ev.means
        np.testing.assert_allclose(origin, mean[:3] * LU_KM, rtol=1e-6)
        np.testing.assert_allclose(axes.T @ axes, np.eye(3), atol=1e-5)
        assert np.linalg.det(axes) > 0
        np.testing.assert_allclose(axes, ric_axes(mean[:3] * LU_KM, mean[3:], earth_km), atol=1e-5)
        radial = (mean[:3] * LU_KM - earth_km) / np.linalg.norm(mean[:3] * LU_KM - earth_km)
        np.testing.assert_allclose(axes[:, 0], radial, atol=1e-5)
        assert axes[:, 2] @ np.cross(mean[:3] * LU_KM - earth_km, mean[3:]) > 0  # along r x v


def test_the_cloud_in_the_frame_is_centred_and_spans_one_unit_at_every_event(entities, recorded_run):
    frames = _by_event(entities["/world/estimate_frame"])
    clouds = _by_event(entities["/world/particles"])
    largest = []
    for frame, cloud, ev in zip(frames, clouds, recorded_run.log.events):
        origin, axes, units = _frame(frame)
        largest.append(units.max())
        assert units.max() / units.min() <= MAX_ASPECT * (1 + 1e-5)
        q = ((component(cloud, "Points3D:positions") - origin) @ axes) / units  # frame coordinates
        reach = np.quantile(np.abs(q), CLOUD_QUANTILE, axis=0)  # 1 along axes not widened for aspect
        assert reach.max() == pytest.approx(1.0, rel=1e-3) and np.all(reach <= 1.0 + 1e-3)
        assert np.all(np.abs(q.mean(axis=0)) < 0.2)  # the particles' centroid sits on the estimate
        # the spread along each axis, in km, is the belief's sigma along that axis
        sigma_km = np.sqrt(np.diag(axes.T @ _total_position_covariance_km2(ev) @ axes))
        np.testing.assert_allclose((q * units).std(axis=0), sigma_km, rtol=0.35)
    assert max(largest) / min(largest) > 1.5  # the frame's unit follows the cloud from event to event


def test_the_axes_are_one_unit_long_and_their_labels_give_the_unit_in_km(entities):
    frames = _by_event(entities["/world/estimate_frame"])
    arrows = _by_event(entities["/world/estimate_frame/axes"])
    labels = _by_event(entities["/world/estimate_frame/axis_labels"])
    assert len(frames) == len(arrows) == len(labels)
    for frame, arrow, label in zip(frames, arrows, labels):
        np.testing.assert_allclose(component(arrow, "Arrows3D:vectors"), np.eye(3))
        texts = label.components["Points3D:labels"]
        assert [t.split(" ")[0] for t in texts] == ["radial", "along-track", "cross-track"]
        shown = [float(t.split(" ")[1].lstrip("±").replace(",", "")) for t in texts]
        np.testing.assert_allclose(shown, _frame(frame)[2], rtol=0.01)


def test_the_line_of_sight_in_the_frame_is_a_short_segment_through_its_closest_point(entities, recorded_run):
    """2.5 frame units either side of the line's point closest to the estimate (in km), on the
    line drawn in the scene."""
    frames = {r.times["event"]: _frame(r) for r in _by_event(entities["/world/estimate_frame"])}
    scene = {r.times["event"]: r for r in _by_event(entities["/world/line_of_sight"])}
    rows = [r for r in _by_event(entities["/world/estimate_frame/line_of_sight"])
            if "LineStrips3D:strips" in r.components]
    assert len(rows) == sum(e.has_measurement for e in recorded_run.log.events) > 0
    for row in rows:
        origin, axes, units = frames[row.times["event"]]
        a, b = np.asarray(row.components["LineStrips3D:strips"][0], dtype=float)
        assert np.linalg.norm(b - a) == pytest.approx(5.0, rel=1e-4)
        mid_km, dir_km = axes @ (units * 0.5 * (a + b)), axes @ (units * (b - a))  # about the estimate
        assert abs(mid_km @ dir_km) / np.linalg.norm(dir_km) < 1e-4 * np.linalg.norm(dir_km)
        p, q = np.asarray(scene[row.times["event"]].components["LineStrips3D:strips"][0], dtype=float)
        off = mid_km + origin - p  # the segment lies on the scene's line of sight
        u = (q - p) / np.linalg.norm(q - p)
        assert np.linalg.norm(off - (off @ u) * u) < 1e-3 * np.linalg.norm(off) + 0.5


def test_ellipsoid_weight_labels_are_kept_but_not_drawn(entities):
    row = entities["/world/components"][0]
    assert row.components["Ellipsoids3D:labels"][0].startswith("w=")
    assert row.components["Ellipsoids3D:show_labels"] in (False, [False])


def _logged(entities, entity) -> dict[int, float]:
    return {s: float(component(r, "Scalars:scalars")[0]) for s, r in last_per_step(entities[entity]).items()}


@pytest.mark.parametrize("entity, column, factor", [
    ("/series/position/error", "pos_err_km", 1.0), ("/series/position/sigma_x", "sigma_x_km", 1.0),
    ("/series/position/sigma_z", "sigma_z_km", 1.0), ("/series/velocity/error", "vel_err_ms", 1.0),
    ("/series/velocity/sigma_vy", "sigma_vy_cms", 0.01), ("/series/nees/nees", "nees", 1.0),
])
def test_plotted_series_are_the_log10_of_the_results_table(entities, recorded_run, entity, column, factor):
    table = recorded_run.table
    expected = {s: math.log10(v * factor) for s, v in zip(table.column("step").to_pylist(),
                                                          table.column(column).to_pylist())
                if v is not None and np.isfinite(v) and v > 0}
    logged = _logged(entities, entity)
    assert logged.keys() == expected.keys()
    for s in expected:
        assert logged[s] == pytest.approx(expected[s], abs=1e-9)


def test_the_nees_band_is_drawn_beside_every_nees_value(entities):
    nees = last_per_step(entities["/series/nees/nees"])
    for entity, edge in zip(("/series/nees/band_5", "/series/nees/band_95"), NEES_BAND):
        logged = _logged(entities, entity)
        assert set(nees) <= set(logged)
        np.testing.assert_allclose(list(logged.values()), math.log10(edge))
    from scipy.stats import chi2

    np.testing.assert_allclose(NEES_BAND, chi2.ppf([0.05, 0.95], 6), rtol=1e-4)


def test_ranked_weights_are_the_sorted_mixture_weights(entities, recorded_run):
    with_metrics = [e for e in recorded_run.log.events if e.metrics]
    ranks = sorted((e for e in entities if e.startswith("/components/ranked/")), key=lambda e: int(e.rsplit("/", 1)[1]))
    n = max(len(e.weights) for e in with_metrics)
    assert len(ranks) == n
    rows = [_by_event([r for r in entities[e] if "Scalars:scalars" in r.components]) for e in ranks]
    seen = 0
    for i, ev in enumerate(with_metrics):
        seen = max(seen, len(ev.weights))
        expected = ranked_weights(ev.weights, seen)
        got = [float(component(rows[k][i - (len(with_metrics) - len(rows[k]))], "Scalars:scalars")[0])
               for k in range(seen)]
        np.testing.assert_allclose(got, expected, atol=1e-12)
        assert sum(got) == pytest.approx(1.0)


def test_frame_units_have_a_floor_and_use_the_covariance_for_a_point_cloud():
    assert np.all(cloud_units_km(np.zeros((5, 3))) > 0)
    np.testing.assert_allclose(cloud_units_km(np.zeros((5, 3)), np.diag([4.0, 1.0, 0.01])), [6.0, 3.0, 0.3])
    rng = np.random.default_rng(1)
    offsets = rng.standard_normal((2000, 3)) * [1000.0, 30.0, 0.0]  # a flat needle
    units = cloud_units_km(offsets)
    np.testing.assert_allclose(units[:2], np.quantile(np.abs(offsets[:, :2]), CLOUD_QUANTILE, axis=0))
    assert units[2] == pytest.approx(units[0] / MAX_ASPECT)


@pytest.mark.parametrize("velocity", [(0.0, 1.0, 0.0), (1.0, 0.0, 0.0), (0.0, 0.0, 0.0), (0.3, -0.2, 0.9)])
def test_ric_axes_are_a_proper_rotation_even_for_degenerate_velocities(velocity):
    axes = ric_axes(np.array([3.0e5, 1.0e4, -5.0e4]), np.array(velocity), np.zeros(3))
    np.testing.assert_allclose(axes.T @ axes, np.eye(3), atol=1e-12)
    assert np.linalg.det(axes) == pytest.approx(1.0)
