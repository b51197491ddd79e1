"""cistrack view: the recording, and nothing else, is served on 127.0.0.1 to the viewer's page.

One real viewer (``serve_recording``, what ``cistrack view`` runs: the recording's HTTP server and
``rerun --serve-web``) serves a real recording from a folder that also holds other files and
symbolic links out of it; every check is a real HTTP request on 127.0.0.1, with the request
target sent as written (no client-side normalisation), and is made relative to the file URL the
viewer is given, so a server that served the folder would fail it.
"""
from __future__ import annotations

import http.client
import os
import socket
from dataclasses import dataclass
from pathlib import Path
from urllib.parse import parse_qs, urlparse

import numpy as np
import pytest

from cistrack.errors import CistrackError
from cistrack.plugins.recorders.viewer_process import find_viewer_executable
from cistrack.plugins.recorders.web_viewer import serve_recording

SIBLING_TEXT = "a note beside the recording, not for the browser\n"
OUTSIDE_TEXT = "a file outside the recording's folder\n"


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def write_small_recording(path: Path) -> None:
    """A real rerun recording: five steps of three points."""
    import rerun as rr

    rec = rr.RecordingStream("cistrack-web-viewer-test", recording_id="web-viewer-test")
    rec.save(str(path))
    for i in range(5):
        rec.set_time("step", sequence=i)
        rec.log("points", rr.Points3D(np.arange(9.0).reshape(3, 3) * (i + 1)))
    rec.flush()
    rec.disconnect()


@dataclass
class Reply:
    status: int
    headers: http.client.HTTPMessage
    body: bytes


def request(port: int, target: str, headers: dict[str, str] | None = None, method: str = "GET") -> Reply:
    """``method target`` sent as is to 127.0.0.1:``port`` (a ``Host`` in ``headers`` replaces the
    real one)."""
    conn = http.client.HTTPConnection("127.0.0.1", port, timeout=30)
    try:
        conn.request(method, target, headers=headers or {})
        resp = conn.getresponse()
        return Reply(resp.status, resp.headers, resp.read())
    finally:
        conn.close()


@dataclass
class Served:
    folder: Path
    rrd: Path
    url: str
    file_url: str
    web_port: int

    @property
    def file_port(self) -> int:
        return int(urlparse(self.file_url).port)

    @property
    def file_path(self) -> str:
        return urlparse(self.file_url).path

    @property
    def file_dir(self) -> str:
        """The file URL's folder part, without the final '/' ('' when the file is at the root)."""
        return self.file_path.rsplit("/", 1)[0]


@pytest.fixture(scope="module")
def served(tmp_path_factory) -> Served:
    if find_viewer_executable() is None:
        pytest.skip("the rerun viewer executable is not installed")
    root = tmp_path_factory.mktemp("view")
    outside = root / "outside"
    outside.mkdir()
    (outside / "secret.txt").write_text(OUTSIDE_TEXT)
    folder = root / "recordings"
    folder.mkdir()
    rrd = folder / "a run.rrd"
    write_small_recording(rrd)
    (folder / "notes.txt").write_text(SIBLING_TEXT)
    (folder / "other.rrd").write_bytes(rrd.read_bytes() + b"another recording")
    (folder / "outside").symlink_to(outside, target_is_directory=True)
    (folder / "escape.rrd").symlink_to(outside / "secret.txt")
    (folder / "etc").symlink_to("/etc", target_is_directory=True)
    with serve_recording(rrd, web_port=free_port()) as s:
        yield Served(folder, rrd, s.url, s.file_url, s.web_port)


def assert_refused(reply: Reply) -> None:
    assert reply.status == 404, reply.status
    assert SIBLING_TEXT.encode() not in reply.body and OUTSIDE_TEXT.encode() not in reply.body
    assert b"notes.txt" not in reply.body and b"a run.rrd" not in reply.body
    assert b"root:" not in reply.body  # /etc/passwd


def test_the_recording_is_served_with_its_exact_bytes(served):
    reply = request(served.file_port, served.file_path)
    assert reply.status == 200
    assert reply.body == served.rrd.read_bytes()
    assert int(reply.headers["Content-Length"]) == served.rrd.stat().st_size


def test_the_url_opens_the_viewer_on_the_chosen_port_with_the_recording(served):
    url = urlparse(served.url)
    assert (url.hostname, url.port) == ("127.0.0.1", served.web_port)
    assert parse_qs(url.query)["url"] == [served.file_url]
    assert urlparse(served.file_url).hostname == "127.0.0.1"
    assert request(served.web_port, "/").status == 200  # the web viewer's page


@pytest.mark.parametrize("where", ["root", "file folder"])
def test_the_folder_is_not_listed(served, where):
    assert_refused(request(served.file_port, "/" if where == "root" else served.file_dir + "/"))


@pytest.mark.parametrize("name", ["notes.txt", "other.rrd"])
def test_a_sibling_file_in_the_folder_is_not_served(served, name):
    assert_refused(request(served.file_port, f"{served.file_dir}/{name}"))
    assert_refused(request(served.file_port, f"/{name}"))


@pytest.mark.parametrize("name", ["outside/secret.txt", "escape.rrd", "etc/passwd"])
def test_a_symlink_out_of_the_folder_is_not_followed(served, name):
    assert_refused(request(served.file_port, f"{served.file_dir}/{name}"))
    assert_refused(request(served.file_port, f"/{name}"))


@pytest.mark.parametrize("tail", [
    "/../notes.txt", "/%2e%2e/notes.txt", "/..%2fnotes.txt", "/%2E%2E%2Fnotes.txt", "/.%2e/notes.txt",
    "/../../outside/secret.txt", "/%2e%2e/%2e%2e/outside/secret.txt", "/..\\notes.txt",
    "/./notes.txt", "//notes.txt", "/../../../../../../etc/passwd",
])
def test_path_traversal_is_refused(served, tail):
    assert_refused(request(served.file_port, served.file_path + tail))
    assert_refused(request(served.file_port, served.file_dir + tail))


def test_the_cors_grant_names_only_the_viewer_page(served):
    viewer_origin = f"http://127.0.0.1:{served.web_port}"
    reply = request(served.file_port, served.file_path, {"Origin": viewer_origin})
    assert reply.status == 200
    assert reply.headers.get_all("Access-Control-Allow-Origin") == [viewer_origin]


def test_a_request_from_another_page_gets_neither_the_file_nor_a_cors_grant(served):
    reply = request(served.file_port, served.file_path, {"Origin": "http://evil.example"})
    assert reply.status != 200 and reply.body == b""
    assert reply.headers.get("Access-Control-Allow-Origin") in (None, f"http://127.0.0.1:{served.web_port}")


def test_a_request_for_another_host_name_is_refused(served):
    """A site that rebinds its own name to 127.0.0.1 sends its name in Host: nothing for it."""
    reply = request(served.file_port, served.file_path, {"Host": f"rebound.example:{served.file_port}"})
    assert reply.status != 200 and reply.body == b""


@pytest.mark.parametrize("method", ["POST", "PUT", "DELETE", "OPTIONS"])
def test_only_get_and_head_are_answered(served, method):
    reply = request(served.file_port, served.file_path, method=method)
    assert reply.status >= 400 and reply.body == b""


def test_a_missing_or_foreign_file_is_refused(tmp_path):
    with pytest.raises(CistrackError, match="not found"):
        serve_recording(tmp_path / "missing.rrd")
    (tmp_path / "x.txt").write_text("x")
    with pytest.raises(CistrackError, match=r"\.rrd"):
        serve_recording(tmp_path / "x.txt")


def test_a_folder_named_like_a_recording_is_refused_as_not_a_file(tmp_path):
    os.mkdir(tmp_path / "folder.rrd")
    with pytest.raises(CistrackError, match="not a file"):
        serve_recording(tmp_path / "folder.rrd")
