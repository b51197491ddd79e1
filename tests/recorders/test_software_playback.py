"""A browser that renders in software plays a run in about a minute too.

Rerun moves the time cursor by at most 0.1 s of each frame, so the web viewer on a software
renderer (about 1.5 s a frame) plays at a fifteenth of the recording's speed. A cistrack recording
carries what its blueprint was built from; ``cistrack view`` builds the same blueprint with the
speed for such a viewer and prints an opening page that sends a software-rendering browser to it.
Real recordings, a real server and rerun viewer, real HTTP; the browser checks are slow.
"""
from __future__ import annotations

import json
import re
import subprocess
import sys
import time
from pathlib import Path
from urllib.parse import urlparse

import numpy as np
import pytest
from rerun.chunk import RrdReader

from cistrack.plugins.recorders.blueprint import FRAME_CAP_S, PLAYBACK_S, SOFTWARE_FRAME_S, playback_speed
from cistrack.plugins.recorders.blueprint_inputs import PROPERTY, SCAN_CHUNKS, read_blueprint_inputs
from cistrack.plugins.recorders.run_extents import system_points_km, utc_range_s
from cistrack.plugins.recorders.viewer_process import find_viewer_executable
from cistrack.plugins.recorders.web_viewer import serve_recording
from cistrack.units import parse_utc

from .headless_browser import find_chromium, open_page
from .test_web_viewer import free_port, request, write_small_recording


@pytest.fixture(scope="module")
def served_run(recorded_run):
    if find_viewer_executable() is None:
        pytest.skip("the rerun viewer executable is not installed")
    with serve_recording(recorded_run.small_rrd, web_port=free_port()) as s:
        yield s


def get(url: str):
    """A real GET of ``url`` (on 127.0.0.1)."""
    u = urlparse(url)
    return request(u.port, u.path)


def page_targets(page: str) -> tuple[str, str | None]:
    """The two URLs the opening page's script chooses between (gpu, software)."""
    m = re.search(r'var gpu = ("[^"]*"), software = ("[^"]*"|null);', page)
    assert m, page
    return json.loads(m.group(1)), json.loads(m.group(2))


def _playback_speed_in(rbl: bytes, tmp_path) -> float:
    path = tmp_path / "served.rbl"
    path.write_bytes(rbl)
    reader = RrdReader(str(path))
    (store,) = reader.blueprints()
    for chunk in reader.stream(store=store):
        batch = chunk.to_record_batch()
        if chunk.entity_path == "/time_panel" and "TimePanelBlueprint:playback_speed" in batch.schema.names:
            return float(batch.column("TimePanelBlueprint:playback_speed").to_pylist()[0][0])
    raise AssertionError("the blueprint has no playback speed")


def test_a_recording_carries_the_inputs_of_its_blueprint(recorded_run):
    ctx = recorded_run.result.context
    inputs = read_blueprint_inputs(recorded_run.full_rrd)
    assert inputs is not None
    assert inputs.utc_range_s == pytest.approx(utc_range_s(ctx, parse_utc(ctx.epoch)))
    pts = system_points_km(ctx)
    np.testing.assert_allclose(inputs.system_box_km, [pts.min(axis=0), pts.max(axis=0)], rtol=1e-12)
    assert (inputs.watching, inputs.burns) == (True, False)


def test_the_inputs_are_among_the_recordings_first_chunks(recorded_run):
    """cistrack view does not read a large recording whole to find them."""
    for i, chunk in enumerate(RrdReader(str(recorded_run.full_rrd)).stream()):
        if chunk.entity_path == f"/__properties/{PROPERTY}":
            break
    assert i < 4 < SCAN_CHUNKS


@pytest.mark.parametrize("content", ["another program's recording", "a truncated recording", "not a recording"])
def test_a_file_without_the_inputs_gives_none(tmp_path, recorded_run, content):
    path = tmp_path / "x.rrd"
    if content == "another program's recording":
        write_small_recording(path)
    elif content == "a truncated recording":
        path.write_bytes(recorded_run.full_rrd.read_bytes()[:2000])
    else:
        path.write_bytes(b"RRF2 and then nothing a reader knows")
    assert read_blueprint_inputs(path) is None


def test_the_software_speed_plays_the_run_in_about_a_minute_at_a_software_frame_rate():
    span = (1.7e9, 1.7e9 + 5.5 * 86_400.0)
    speed = playback_speed(span, SOFTWARE_FRAME_S)
    frames = (span[1] - span[0]) / (speed * FRAME_CAP_S)  # the cursor moves speed * 0.1 s a frame
    assert frames * SOFTWARE_FRAME_S == pytest.approx(PLAYBACK_S)
    assert speed == pytest.approx(playback_speed(span) * SOFTWARE_FRAME_S / FRAME_CAP_S)


def test_the_served_software_blueprint_has_that_speed(served_run, recorded_run, tmp_path):
    inputs = read_blueprint_inputs(recorded_run.small_rrd)
    reply = get(served_run.blueprint_url)
    assert reply.status == 200
    assert _playback_speed_in(reply.body, tmp_path) == pytest.approx(playback_speed(inputs.utc_range_s,
                                                                                    SOFTWARE_FRAME_S))


def test_the_opening_page_names_the_viewer_and_its_software_variant(served_run):
    reply = get(served_run.page_url)
    assert reply.status == 200 and reply.headers["Content-Type"].startswith("text/html")
    page = reply.body.decode()
    assert page_targets(page) == (served_run.url, served_run.software_url)
    assert "location.replace" in page


def test_another_programs_recording_gets_no_software_variant(tmp_path):
    if find_viewer_executable() is None:
        pytest.skip("the rerun viewer executable is not installed")
    rrd = tmp_path / "other.rrd"
    write_small_recording(rrd)
    with serve_recording(rrd, web_port=free_port()) as s:
        assert s.software_url is None and s.blueprint_url is None
        page = get(s.page_url).body.decode()
        assert page_targets(page) == (s.url, None) and "software.rbl" not in page


def _blueprint_fetched(served, query: str) -> int:
    """Open the opening page (with ``query``) in headless Chromium; how often the software
    blueprint was then fetched."""
    rbl, rrd = urlparse(served.blueprint_url).path, urlparse(served.file_url).path
    with open_page(served.page_url + query):
        deadline = time.monotonic() + 60.0
        while time.monotonic() < deadline and rrd not in served.served:
            time.sleep(1.0)
        time.sleep(3.0)  # the viewer asks for both files at once
    return served.served.get(rbl, 0)


@pytest.mark.slow
@pytest.mark.parametrize("query, fetched", [("", True), ("?playback=gpu", False)])
def test_headless_chromium_is_sent_to_the_software_variant_unless_told(recorded_run, query, fetched):
    if find_chromium() is None:
        pytest.skip("chromium is not installed (apt-get install -y chromium)")
    if find_viewer_executable() is None:
        pytest.skip("the rerun viewer executable is not installed")
    with serve_recording(recorded_run.small_rrd, web_port=free_port()) as served:
        assert (_blueprint_fetched(served, query) > 0) is fetched
        assert served.served.get(urlparse(served.file_url).path, 0) >= 1


def test_an_odd_file_name_gets_a_working_page_and_blueprint(recorded_run, tmp_path):
    if find_viewer_executable() is None:
        pytest.skip("the rerun viewer executable is not installed")
    rrd = tmp_path / 'a run\'s "odd" <name>?#ü.rrd'
    rrd.write_bytes(recorded_run.small_rrd.read_bytes())
    with serve_recording(rrd, web_port=free_port()) as s:
        page = get(s.page_url)
        assert page.status == 200 and "<name>" not in page.body.decode()  # the title is escaped
        assert page_targets(page.body.decode()) == (s.url, s.software_url)
        assert get(s.blueprint_url).status == 200 and get(s.file_url).status == 200


def test_cistrack_view_prints_the_opening_page(recorded_run):
    cli = Path(sys.executable).with_name("cistrack")
    if find_viewer_executable() is None or not cli.exists():
        pytest.skip("the rerun viewer executable or the cistrack command is not installed")
    port = free_port()
    view = subprocess.Popen([str(cli), "view", str(recorded_run.small_rrd), "--port", str(port)],
                            stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
    try:
        url = view.stdout.readline().rsplit(" ", 1)[-1].strip()
        assert "without a GPU" in view.stdout.readline()
        reply = get(url)
        assert reply.status == 200 and reply.headers["Content-Type"].startswith("text/html")
        gpu, software = page_targets(reply.body.decode())
        assert urlparse(gpu).port == port and "software.rbl" in software
    finally:
        view.terminate()
        view.wait(timeout=20)
