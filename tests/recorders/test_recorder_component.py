"""The recorder as a component: registration, parameters, sinks (file per run, local server,
viewer), pickling."""
from __future__ import annotations

import dataclasses
import pickle
import socket
import time

import psutil
import pytest

from cistrack.errors import ParameterError
from cistrack.plugins.recorders.rerun_recorder import LOOPBACK, RerunRecorder, ViewerUnavailableError

from .rrd_reading import read_entities


def _free_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.bind((LOOPBACK, 0))
        return s.getsockname()[1]


def _listening(port: int) -> list[str]:
    return [c.laddr.ip for c in psutil.Process().net_connections(kind="inet")
            if c.status == psutil.CONN_LISTEN and c.laddr.port == port]


def test_registry_builds_the_recorder_with_the_cli_parameters(registry, tmp_path):
    rec = registry.create("recorder", "rerun", path=str(tmp_path / "a.rrd"), serve=False, spawn=False,
                          max_points=1000)
    assert isinstance(rec, RerunRecorder)
    assert rec.get_params()["max_points"] == 1000


@pytest.mark.parametrize("params, name", [
    ({"path": "x.rrd", "max_points": 0}, "max_points"),
    ({"path": "x.rrd", "max_points": 2.5}, "max_points"),
    ({"path": "x.rrd", "serve": "yes"}, "serve"),
    ({"path": "x.rrd", "ellipsoid_sigma": -1.0}, "ellipsoid_sigma"),
    ({"path": "x.rrd", "serve_port": 70000}, "serve_port"),
    ({"path": 3}, "path"),
    ({"path": "x.rrd", "max_ellipsoids": -1}, "max_ellipsoids"),
    ({"path": "x.rrd", "max_ellipsoids": 1.5}, "max_ellipsoids"),
])
def test_bad_parameters_are_named(params, name):
    with pytest.raises(ParameterError, match=name):
        RerunRecorder(**params)


def test_a_recorder_with_nowhere_to_record_is_refused():
    with pytest.raises(ParameterError, match="nothing to record"):
        RerunRecorder()


def test_spawn_without_a_display_fails_with_a_clear_message(monkeypatch):
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    with pytest.raises(ViewerUnavailableError, match="display"):
        RerunRecorder(spawn=True)


def test_recorder_pickles_without_its_stream(tmp_path):
    rec = RerunRecorder(path=str(tmp_path / "a.rrd"), max_points=7)
    clone = pickle.loads(pickle.dumps(rec))
    assert clone.get_params() == rec.get_params()


def test_server_listens_on_loopback_only_and_stops_on_close(recorded_run):
    port = _free_port()
    rec = RerunRecorder(serve=True, serve_port=port)
    rec.cistrack_run_started(run=recorded_run.result.context)
    try:
        assert _listening(port) == [LOOPBACK]
        assert rec.server_uri == f"rerun+http://127.0.0.1:{port}/proxy"
        rec.cistrack_run_finished(run=recorded_run.result.context, summary=recorded_run.result.summary)
        assert _listening(port) == [LOOPBACK], "the server outlives the run until close()"
    finally:
        rec.close()
    deadline = time.monotonic() + 10.0
    while _listening(port) and time.monotonic() < deadline:
        time.sleep(0.05)
    assert _listening(port) == []


def test_a_directory_path_writes_one_recording_per_run(recorded_run, tmp_path):
    ctx = recorded_run.result.context
    rec = RerunRecorder(path=str(tmp_path))
    for rid in ("run-a", "run-b"):
        run = dataclasses.replace(ctx, run_id=rid)
        rec.cistrack_run_started(run=run)
        rec.cistrack_run_finished(run=run, summary=recorded_run.result.summary)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run-a.rrd", "run-b.rrd"]
    for p in tmp_path.iterdir():
        assert "/world/libration" in read_entities(p)


def test_a_single_file_path_refuses_a_second_run(recorded_run, tmp_path):
    ctx = recorded_run.result.context
    rec = RerunRecorder(path=str(tmp_path / "one.rrd"))
    rec.cistrack_run_started(run=ctx)
    rec.cistrack_run_finished(run=ctx, summary=recorded_run.result.summary)
    with pytest.raises(ParameterError, match="run_id"):
        rec.cistrack_run_started(run=dataclasses.replace(ctx, run_id="other"))


def test_a_disk_that_runs_short_during_the_run_stops_the_recording_and_the_run_goes_on(tmp_path, monkeypatch):
    from cistrack.plugin.registry import load_registry
    from cistrack.plugins.recorders import rerun_recorder
    from cistrack.plugins.recorders.recording_check import recording_problem
    from cistrack.runs.pipeline import run_scenario

    from .conftest import small_scenario

    reg = load_registry()
    rec = reg.create("recorder", "rerun", path=str(tmp_path / "run.rrd"))
    calls = {"n": 0}

    def filling_disk(folder):  # the operating system's answer: room for five steps, then under 1 MB
        calls["n"] += 1
        return 10**9 if calls["n"] <= 5 else 900_000

    monkeypatch.setattr(rerun_recorder, "_free_bytes", filling_disk)
    with pytest.warns(RuntimeWarning, match=r"run\.rrd stopped at step \d+: under 16 MB free"):
        res = run_scenario(small_scenario(reg), registry=reg, observers=[rec])
    assert res.summary.status == "finished", res.summary.failure
    assert recording_problem(tmp_path / "run.rrd") is None  # flushed and closed: a whole file, shorter
    steps = {r.times.get("step") for r in read_entities(tmp_path / "run.rrd").get("/world/particles", [])}
    assert 0 < len(steps) <= 5
