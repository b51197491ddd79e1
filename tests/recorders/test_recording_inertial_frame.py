"""A recording in the inertial frame (recorder parameter frame = "inertial"): every logged state is
the sensor's inertial placement of the run's synodic state, the Earth sits at the origin and the
Moon is logged where it is at each step."""
from __future__ import annotations

import numpy as np
import pytest

from cistrack.errors import ParameterError
from cistrack.plugin.registry import load_registry
from cistrack.runs.pipeline import run_scenario
from cistrack.units import LU_KM

from .conftest import EventLog, small_scenario
from .rrd_reading import component, read_entities


@pytest.fixture(scope="module")
def inertial_run(tmp_path_factory):
    reg = load_registry()
    scen = small_scenario(reg)
    d = tmp_path_factory.mktemp("inertial")
    rec = reg.create("recorder", "rerun", path=str(d / "inertial.rrd"), max_points=100_000, frame="inertial")
    log = EventLog()
    res = run_scenario(scen, registry=reg, observers=[rec, log], output_dir=d / "out")
    return read_entities(d / "inertial.rrd"), res, log


def test_particles_are_the_sensors_inertial_placement_of_the_filters_particles(inertial_run):
    entities, res, log = inertial_run
    frame = res.context.sensor.inertial_frame()
    rows = sorted(entities["/world/particles"], key=lambda r: r.times["event"])
    assert len(rows) == len(log.events)
    for row, ev in zip(rows, log.events):
        want = frame.from_synodic(ev.states, np.full(len(ev.states), ev.t))[:, :3]
        got = component(row, "Points3D:positions")
        np.testing.assert_allclose(got, want, rtol=1e-6, atol=1.0)  # float32 km


def test_earth_at_the_origin_moon_where_it_is_and_no_libration_points(inertial_run):
    entities, res, log = inertial_run
    earth = component(entities["/world/earth"][0], "Ellipsoids3D:centers")
    np.testing.assert_array_equal(earth, np.zeros((1, 3)))
    assert "/world/libration" not in entities
    moons = entities["/world/moon"]
    assert len(moons) == len(log.events)
    frame = res.context.sensor.inertial_frame()
    ev = log.events[-1]
    moon_syn = res.context.dynamics.primary("Moon").position_at(ev.t)
    want = frame.from_synodic(np.concatenate([moon_syn, np.zeros(3)])[None], np.array([ev.t]))[0, :3]
    last = max(moons, key=lambda r: r.times["event"])
    np.testing.assert_allclose(component(last, "Ellipsoids3D:centers")[0], want, rtol=1e-6)
    assert 350_000 < np.linalg.norm(want) < 410_000 and abs(np.linalg.norm(want) - LU_KM) < 30_000


def test_an_unknown_frame_is_refused_by_name():
    with pytest.raises(ParameterError, match="frame"):
        load_registry().create("recorder", "rerun", path="x.rrd", frame="ecliptic")


def test_a_scenario_chooses_the_recording_frame():
    from cistrack.errors import ConfigError
    from cistrack.scenario.loading import load_scenario, parse_scenario

    reg = load_registry()
    assert load_scenario("example-1-ephemeris", reg).recording_frame == "inertial"
    assert load_scenario("example-1", reg).recording_frame == "synodic"
    data = dict(load_scenario("quick", reg).raw)
    data["run"] = {**data.get("run", {}), "recording_frame": "ecliptic"}
    with pytest.raises(ConfigError, match="recording_frame"):
        parse_scenario(data, registry=reg)
