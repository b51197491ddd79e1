"""cistrack view: the recording is served on 127.0.0.1 with CORS and the URL names it in ?url=."""
from __future__ import annotations

import socket
import urllib.request
from urllib.parse import parse_qs, urlparse

import pytest

from cistrack.plugins.recorders.rerun_recorder import find_viewer_executable
from cistrack.plugins.recorders.web_viewer import serve_recording


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def test_the_url_loads_the_served_recording(tmp_path):
    if find_viewer_executable() is None:
        pytest.skip("the rerun viewer executable is not installed")
    rrd = tmp_path / "a run.rrd"
    rrd.write_bytes(b"RRF2 not a real recording, only bytes to serve")
    port = _free_port()
    with serve_recording(rrd, web_port=port) as served:
        url = urlparse(served.url)
        assert (url.hostname, url.port) == ("127.0.0.1", port)
        file_url = parse_qs(url.query)["url"][0]
        assert file_url == served.file_url and urlparse(file_url).hostname == "127.0.0.1"
        with urllib.request.urlopen(file_url, timeout=10) as resp:
            assert resp.read() == rrd.read_bytes()
            assert resp.headers["Access-Control-Allow-Origin"] == "*"
        with urllib.request.urlopen(f"http://127.0.0.1:{port}/", timeout=10) as resp:
            assert resp.status == 200  # the web viewer's page


def test_a_missing_or_foreign_file_is_refused(tmp_path):
    from cistrack.errors import CistrackError

    with pytest.raises(CistrackError, match="not found"):
        serve_recording(tmp_path / "missing.rrd")
    (tmp_path / "x.txt").write_text("x")
    with pytest.raises(CistrackError, match=r"\.rrd"):
        serve_recording(tmp_path / "x.txt")
