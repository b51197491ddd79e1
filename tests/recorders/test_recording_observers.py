"""A network run in the viewer: every observer, its lines of sight and a space telescope's
exclusion cones (plugins/recorders/observers_view.py), read back from the recording."""
from __future__ import annotations

import numpy as np
import pytest

from cistrack.plugin.registry import load_registry
from cistrack.runs.pipeline import run_scenario
from cistrack.scenario.loading import load_scenario
from cistrack.units import LU_KM

from .rrd_reading import component, last_per_step, read_entities

SMALL = {"iod": {"n_particles": 300}, "filter": {"n_particles": 300, "n_components": 3}, "duration_days": 1.5}


@pytest.fixture(scope="module")
def network_recording(tmp_path_factory):
    reg = load_registry()
    path = tmp_path_factory.mktemp("rec") / "net.rrd"
    rec = reg.create("recorder", "rerun", path=str(path), max_points=50)
    res = run_scenario(load_scenario("example-1-ground-space", overrides=SMALL, registry=reg), seed=2,
                       registry=reg, observers=[rec], keep_steps=True)
    return read_entities(path), res


def test_every_observer_is_drawn_where_its_sensor_puts_it(network_recording):
    entities, res = network_recording
    for key, sensor in res.context.sensor.members.items():
        rows = last_per_step(entities[f"/world/observers/{key}"])
        step = res.steps[-1]
        got = component(rows[step.index], "Points3D:positions")[0]
        np.testing.assert_allclose(got, sensor.observer_position(step.t) * LU_KM, rtol=1e-6)


def test_lines_of_sight_are_drawn_for_the_observer_that_measured(network_recording):
    entities, res = network_recording
    for key in ("texas", "dro"):
        rows = last_per_step(entities[f"/world/observers/{key}/line_of_sight"])
        measured = [s.index for s in res.steps if s.group and any(m.site == key for m in s.group)]
        assert measured and all("LineStrips3D:strips" in rows[i].components for i in measured)


def test_exclusion_cone_rims_make_the_cone_angle_with_the_body_direction(network_recording):
    entities, res = network_recording
    dro = res.context.sensor.members["dro"]
    step = res.steps[-1]
    cones = dro.exclusion_cones(step.t)
    assert set(cones) == {"sun", "earth", "moon"}
    apex = dro.observer_position(step.t) * LU_KM
    for body, (axis, half) in cones.items():
        row = last_per_step(entities[f"/world/observers/dro/exclusion/{body}"])[step.index]
        rim = np.asarray(row.components["LineStrips3D:strips"][0], dtype=float) - apex
        ang = np.arccos(np.clip(rim @ axis / np.linalg.norm(rim, axis=1), -1, 1))
        np.testing.assert_allclose(ang, half, atol=1e-5)


def test_a_ground_observer_name_is_not_drawn_over_the_earth_but_a_space_observer_name_is(network_recording):
    entities, res = network_recording
    step = res.steps[-1]
    shown = {key: bool(component(last_per_step(entities[f"/world/observers/{key}"])[step.index],
                                 "Points3D:show_labels")[0])
             for key in ("texas", "dro")}
    assert shown == {"texas": False, "dro": True}
