"""Scenarios with several observers ([sensors.<key>] tables): ground and space measurements fused
in one run, the IOD from one observer's arc, refusals at validation."""
from __future__ import annotations

import numpy as np
import pytest

from cistrack.errors import ConfigError
from cistrack.runs.pipeline import prepare_run, run_scenario
from cistrack.scenario.loading import load_scenario

SMALL = {"iod": {"n_particles": 400}, "filter": {"n_particles": 400, "n_components": 3}, "duration_days": 2.5}


@pytest.fixture(scope="module")
def network_run():
    return run_scenario(load_scenario("example-1-ground-space", overrides=SMALL), seed=3, keep_steps=True)


def test_measurements_of_every_observer_reach_the_filter(network_run):
    ms = network_run.context.measurements
    assert set(ms.sites.tolist()) == {"texas", "dro"}
    updated = {m.site for s in network_run.steps for m in s.group}
    assert network_run.summary.status == "finished"
    assert updated == {"texas", "dro"}


def test_each_measurement_is_predicted_from_its_own_observer(network_run):
    ctx = network_run.context
    ms = ctx.measurements
    for i in (int(np.flatnonzero(ms.sites == "texas")[0]), int(np.flatnonzero(ms.sites == "dro")[0])):
        m = ms[i]
        own = ctx.sensor.for_measurement(m)
        assert own is ctx.sensor.members[m.site]
        z = own.measure(ctx.truth.states_at(m.t), m.t)[0]
        assert np.all(np.abs(own.residual(m.z, z)[:2]) < 6 * np.sqrt(np.diag(m.covariance))[:2])


def test_the_iod_works_from_the_named_observer():
    scen = load_scenario("example-1-ground-space", overrides=SMALL)
    ctx, _ = prepare_run(scen, seed=3)
    dro = ctx.measurements.times[ctx.measurements.sites == "dro"]
    assert ctx.iod_cloud.epoch in set(dro.tolist())


def test_an_observer_keeps_its_measurements_when_another_is_added_after_it():
    one = load_scenario("example-1-ground-space", overrides={**SMALL, "run": {"iod_observer": "dro"}})
    raw = dict(one.raw)
    raw_sensors = {"dro": raw["sensors"]["dro"]}
    alone = load_scenario("example-1-ground-space", overrides={**SMALL, "sensors": raw_sensors,
                                                               "run": {"iod_observer": "dro"}})
    a, _ = prepare_run(alone, seed=5)
    b, _ = prepare_run(load_scenario("example-1-ground-space", overrides={
        **SMALL, "sensors": {**raw_sensors, "texas": raw["sensors"]["texas"]}, "run": {"iod_observer": "dro"}}), seed=5)
    first = b.measurements.subset(b.measurements.sites == "dro")
    assert np.array_equal(a.measurements.values, first.values)


def test_observers_measuring_different_components_are_refused():
    with pytest.raises(ConfigError, match=r"\[sensors.dro\] measures right_ascension.*\[sensors.texas\] azimuth"):
        load_scenario("example-1-ground-space", overrides={"sensors": {
            "texas": {"name": "ground-telescope", "measure_range": True},
            "dro": {"name": "space-telescope", "measure_range": True}}})


def test_sensor_and_sensors_together_are_refused():
    with pytest.raises(ConfigError, match="not both"):
        load_scenario("example-1-ground-space", overrides={"sensor": {"name": "ground-telescope"}})


def test_an_unknown_iod_observer_is_refused():
    with pytest.raises(ConfigError, match="iod_observer"):
        load_scenario("example-1-ground-space", overrides={"run": {"iod_observer": "goldstone"}})


@pytest.mark.parametrize("sensors, match", [({}, "one table per observer"),
                                            ({"dro": "space-telescope"}, "one table per observer")])
def test_sensors_must_hold_one_table_per_observer(sensors, match):
    with pytest.raises(ConfigError, match=match):
        load_scenario("example-1-ground-space", overrides={"sensors": sensors})


def test_a_scenario_without_any_sensor_is_refused_naming_both_forms():
    raw = dict(load_scenario("example-1").raw)
    raw.pop("sensor")
    from cistrack.scenario.loading import parse_scenario
    with pytest.raises(ConfigError, match=r"missing table \[sensor\].*\[sensors.<key>\]"):
        parse_scenario(raw)


def test_an_iod_observer_that_measured_nothing_is_named_with_its_default_and_the_setting_that_helps():
    raw = load_scenario("example-1-ground-space").raw
    blind = {**raw["sensors"]["texas"], "latitude_deg": -89.0}  # the target never rises there
    scenario = load_scenario("example-1-ground-space", overrides={**SMALL, "run": {"iod_observer": "texas"},
                                                                  "sensors": {"texas": blind, "dro": raw["sensors"]["dro"]}})
    with pytest.raises(ConfigError, match=r"the IOD works from observer 'texas' \(\[run\] iod_observer, by default the "
                                          r"first \[sensors\] table\), which took no measurements; .*set \[run\] "
                                          r"iod_observer = 'dro'"):
        prepare_run(scenario, seed=2)


def test_a_space_telescope_whose_orbit_hits_earth_is_named_by_its_file_and_table_among_alike_ones():
    raw = load_scenario("example-1-ground-space").raw
    dro = {k: v for k, v in raw["sensors"]["dro"].items() if k not in ("orbit", "phase")}
    sensors = {**raw["sensors"], "dro2": {**dro, "state_km": [0.0] * 6}}  # at the barycentre, inside the Earth
    scenario = load_scenario("example-1-ground-space", overrides={**SMALL, "sensors": sensors})
    with pytest.raises(ConfigError, match=r"\[sensors\.dro2\]: sensor 'space-telescope': the observer's orbit hits "
                                          r"Earth at t = 0\.000 days") as info:
        prepare_run(scenario, seed=2)
    assert str(info.value).startswith(f"{scenario.source}: [sensors.dro2]: ")


def test_a_lone_space_telescope_whose_orbit_hits_earth_is_named_by_its_file_and_table(tmp_path):
    path = tmp_path / "one_space.toml"
    path.write_text('name = "one-space"\nepoch = "2026-01-01T00:00:00Z"\nseed = 1\nduration_days = 2.0\n'
                    '[truth]\norbit = "nrho-9-2"\n[dynamics]\nname = "cr3bp"\n'
                    '[sensor]\nname = "space-telescope"\nstate_km = [0, 0, 0, 0, 0, 0]\nmeasure_range = true\n'
                    '[schedule]\nname = "paper-example-1"\n[iod]\nname = "noisy-range"\nn_particles = 200\n'
                    '[filter]\nname = "pgm"\nn_particles = 200\nn_components = 2\n')
    with pytest.raises(ConfigError, match=r"\[sensor\]: sensor 'space-telescope': the observer's orbit hits Earth") as info:
        prepare_run(load_scenario(str(path)), seed=2)
    assert str(info.value).startswith(f"{path}: [sensor]: ")
