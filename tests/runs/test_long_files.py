"""Long measurement files (issue 17, item 5): measurements sharing a time tag make one filter step,
and results are written in part files of many rows whose merged tables do not depend on the
part size."""
from __future__ import annotations

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest

from cistrack.results.part_files import PartWriter, read_parts
from cistrack.plugins.readers.csv_file import write_measurements
from cistrack.results.store import read_manifest, read_steps
from cistrack.runs.pipeline import prepare_run, run_scenario
from cistrack.scenario.loading import load_scenario
from cistrack.astro.site_network import merge_sites
from cistrack.astro.sites import observatory

EPOCH = "2026-01-01T00:00:00Z"
SITES = ("695", "691")  # two Kitt Peak telescopes: they see the same passes


def _small(**over):
    base = {"duration_days": 1.4, "filter": {"n_particles": 300, "n_components": 2}, "iod": {"n_particles": 300}}
    return load_scenario("quick").with_overrides({**base, **over})


@pytest.fixture(scope="module")
def two_site_file(tmp_path_factory):
    """Both sites measure the quick scenario's truth at the same scheduled times."""
    from cistrack.plugin.registry import default_registry

    ctx, _ = prepare_run(_small(duration_days=4.0), seed=2)
    times = ctx.measurements.times
    states = ctx.truth.states_at(times)
    rng = np.random.default_rng(7)
    parts = []
    for code in SITES:
        site = observatory(code)
        sensor = default_registry().create("sensor", "ground-telescope", latitude_deg=site.latitude_deg,
                                           longitude_deg=site.longitude_deg, height_m=site.height_m,
                                           measure_range=True)
        parts.append((code, site, sensor.simulate(states, times, rng)))
    path = tmp_path_factory.mktemp("obs") / "two-sites.csv"
    write_measurements(path, merge_sites(parts), EPOCH)
    return path, times.size


@pytest.fixture(scope="module")
def runs_by_part_size(two_site_file, tmp_path_factory):
    path, _ = two_site_file
    out = {}
    for n in (1, 1000):
        d = tmp_path_factory.mktemp(f"rows{n}") / "run"
        res = run_scenario(_small(duration_days=4.0, measurements={"file": str(path)}), seed=2, output_dir=d,
                           rows_per_part=n)
        out[n] = (d, res)
    return out


def _without_timings(table):
    return table.drop_columns([c for c in table.column_names if c.startswith("time_")])


def _bits(table) -> bytes:
    """The table as Arrow IPC bytes: equal bytes are equal numbers bit for bit (NaN included)."""
    sink = pa.BufferOutputStream()
    with pa.ipc.new_stream(sink, table.schema) as w:
        w.write_table(table.combine_chunks())
    return sink.getvalue().to_pybytes()


def test_the_step_table_is_identical_for_one_row_per_part_and_many(runs_by_part_size):
    (d1, _), (dn, _) = runs_by_part_size[1], runs_by_part_size[1000]
    a, b = _without_timings(read_steps(d1)), _without_timings(read_steps(dn))
    assert a.num_rows > 10 and a.column_names == b.column_names
    assert _bits(a) == _bits(b)  # every number bit for bit; only the wall-clock timings differ
    assert _bits(pq.read_table(d1 / "estimates.parquet")) == _bits(pq.read_table(dn / "estimates.parquet"))


def test_the_manifest_counts_the_part_files(runs_by_part_size):
    (d1, r1), (dn, _) = runs_by_part_size[1], runs_by_part_size[1000]
    assert read_manifest(d1)["n_parts"] == len(r1.rows)
    assert read_manifest(dn)["n_parts"] == 1


def test_measurements_at_one_time_from_two_sites_make_one_update(two_site_file, runs_by_part_size):
    _, n_times = two_site_file
    d, res = runs_by_part_size[1000]
    steps = read_steps(d).to_pylist()
    updates = [r for r in steps if r["kind"] == "update"]
    epoch = res.context.iod_cloud.epoch
    assert len(res.context.measurements) == 2 * n_times
    assert len(updates) == int(np.sum(res.context.measurements.times[::2] > epoch + 1e-12))
    assert all(r["measurement_index"] % 2 == 0 for r in updates)  # the first of each pair
    est = pq.read_table(d / "estimates.parquet").to_pydict()
    dofs = {dof for kind, dof in zip(est["kind"], est["nis_dof"]) if kind == "update"}
    assert dofs == {4}  # two angles from each site, stacked


def test_a_part_is_written_per_rows_per_part_rows_and_the_rest_at_flush(tmp_path):
    w = PartWriter(tmp_path / "p", rows_per_part=3, seconds_per_part=3600)
    w.start()
    for k in range(7):
        w.add(k, {"step": k, "x": float(k)})
    assert len(w.parts()) == 2  # steps 0-2 and 3-5; step 6 waits
    w.flush()
    assert [p.name for p in w.parts()] == ["part-000000000.parquet", "part-000000003.parquet",
                                           "part-000000006.parquet"]
    assert read_parts(tmp_path / "p").column("step").to_pylist() == list(range(7))


def test_a_part_is_written_once_its_seconds_have_passed(tmp_path):
    w = PartWriter(tmp_path / "p", rows_per_part=1000, seconds_per_part=1e-9)
    w.start()
    for k in range(3):
        w.add(k, {"step": k})
    assert len(w.parts()) == 3


def test_rows_with_different_keys_merge_as_if_each_were_its_own_part(tmp_path):
    rows = [{"step": 0, "a": 1.0}, {"step": 1, "a": 2.0, "b": 3.0}, {"step": 2, "b": 4.0}]
    one, many = PartWriter(tmp_path / "one", rows_per_part=1), PartWriter(tmp_path / "many", rows_per_part=10)
    for w in (one, many):
        w.start()
        for r in rows:
            w.add(r["step"], r)
        w.flush()
    assert read_parts(tmp_path / "one").equals(read_parts(tmp_path / "many"))


def _count_updates(monkeypatch, cls):
    calls = []
    real = cls.update

    def update(self, measurement):
        calls.append(measurement)
        return real(self, measurement)

    monkeypatch.setattr(cls, "update", update)
    return calls


@pytest.mark.parametrize("stacked", [True, False], ids=["stacked", "one-after-another"])
def test_a_filter_gets_one_stacked_update_per_time_or_the_parts_in_turn(two_site_file, monkeypatch, stacked):
    from cistrack.model.measurement import StackedMeasurement
    from cistrack.plugins.filters.ukf import UKFFilter

    path, _ = two_site_file
    monkeypatch.setattr(UKFFilter, "stacked_updates", stacked)
    calls = _count_updates(monkeypatch, UKFFilter)
    res = run_scenario(_small(duration_days=4.0, measurements={"file": str(path)}, filter={"name": "ukf"}), seed=2)
    n_updates = sum(1 for r in res.rows if r["kind"] == "update")
    if stacked:
        assert len(calls) == n_updates and all(isinstance(m, StackedMeasurement) and len(m.parts) == 2 for m in calls)
        assert {m.parts[0].site for m in calls} == {"695"} and {m.parts[1].site for m in calls} == {"691"}
    else:
        assert len(calls) == 2 * n_updates and not any(isinstance(m, StackedMeasurement) for m in calls)
    assert res.summary.status == "finished"


def test_a_stacked_measurement_is_its_parts_side_by_side_each_from_its_own_site(two_site_file):
    from cistrack.model.measurement import StackedMeasurement
    from cistrack.plugins.filters.measured_components import MeasuredComponents

    path, _ = two_site_file
    ctx, _ = prepare_run(_small(duration_days=4.0, measurements={"file": str(path)}), seed=2)
    a, b = ctx.measurements[0].angles_only(), ctx.measurements[1].angles_only()
    stack = StackedMeasurement((a, b))
    x = ctx.iod_cloud.states[:50]
    ma, mb, ms = (MeasuredComponents(ctx.sensor, m) for m in (a, b, stack))
    np.testing.assert_array_equal(ms.residuals_to_measurement(x),
                                  np.hstack([ma.residuals_to_measurement(x), mb.residuals_to_measurement(x)]))
    np.testing.assert_array_equal(ms.R[:2, :2], a.covariance)
    np.testing.assert_array_equal(ms.R[2:, 2:], b.covariance)
    assert not ms.R[:2, 2:].any() and ms.z.tolist() == [*a.z, *b.z]
    assert not np.allclose(ma.predict(x), mb.predict(x))  # two sites really see different angles
