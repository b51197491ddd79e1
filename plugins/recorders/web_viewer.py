"""Open a recording in a browser: the rerun web viewer plus the .rrd served on 127.0.0.1.

``cistrack view FILE.rrd`` (and the slow browser test) use :func:`serve_recording`: a small HTTP
server sends the file (with a CORS header, so the viewer's page may fetch it), ``rerun
--serve-web`` hosts the web viewer, and the URL ``http://127.0.0.1:<web port>/?url=<file URL>``
opens the viewer with the recording loaded (the plain viewer address opens its welcome page).
Both servers listen on 127.0.0.1 only.
"""
from __future__ import annotations

import functools
import subprocess
import threading
from dataclasses import dataclass, field
from http.server import SimpleHTTPRequestHandler, ThreadingHTTPServer
from pathlib import Path
from urllib.parse import quote

from cistrack.errors import CistrackError

from .viewer_process import LOOPBACK, ViewerUnavailableError, find_viewer_executable
from .viewer_process import wait_for_port as _wait_for_port

__all__ = ["ServedRecording", "serve_recording", "viewer_url"]


def viewer_url(web_port: int, file_url: str) -> str:
    """The web viewer's address with the recording at ``file_url`` to load."""
    return f"http://{LOOPBACK}:{web_port}/?url={quote(file_url, safe='')}"


class _OneFileHandler(SimpleHTTPRequestHandler):
    """Serves the files of one directory, read-only, with CORS for the viewer's page."""

    def end_headers(self) -> None:
        self.send_header("Access-Control-Allow-Origin", "*")
        super().end_headers()

    def log_message(self, *args) -> None:  # quiet: the command prints the URL, not every request
        pass


@dataclass
class ServedRecording:
    """A recording being served; :meth:`close` stops both servers."""

    url: str
    file_url: str
    web_port: int
    _http: ThreadingHTTPServer = field(repr=False)
    _viewer: subprocess.Popen = field(repr=False)

    def close(self) -> None:
        self._http.shutdown()
        self._http.server_close()
        if self._viewer.poll() is None:
            self._viewer.terminate()
            try:
                self._viewer.wait(timeout=10)
            except subprocess.TimeoutExpired:
                self._viewer.kill()

    def __enter__(self) -> "ServedRecording":
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def serve_recording(path: str | Path, web_port: int = 9090, timeout_s: float = 30.0) -> ServedRecording:
    """Serve ``path`` (an .rrd file) and the rerun web viewer on 127.0.0.1; returns the URL to open."""
    rrd = Path(path).resolve()
    if not rrd.is_file():
        raise CistrackError(f"recording not found: {path}")
    if rrd.suffix != ".rrd":
        raise CistrackError(f"{path}: expected a rerun recording (.rrd)")
    exe = find_viewer_executable()
    if exe is None:
        raise ViewerUnavailableError("the rerun viewer is not installed (it ships with rerun-sdk: "
                                     "pip install rerun-sdk); cannot host the web viewer")
    handler = functools.partial(_OneFileHandler, directory=str(rrd.parent))
    http = ThreadingHTTPServer((LOOPBACK, 0), handler)
    threading.Thread(target=http.serve_forever, name="cistrack-rrd-http", daemon=True).start()
    file_url = f"http://{LOOPBACK}:{http.server_address[1]}/{quote(rrd.name)}"
    viewer = subprocess.Popen([exe, "--serve-web", "--bind", LOOPBACK, "--web-viewer-port", str(web_port),
                               file_url], stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                              stderr=subprocess.PIPE)
    if not _wait_for_port(web_port, viewer, timeout_s):
        err = viewer.stderr.read().decode(errors="replace").strip()[-800:] if viewer.poll() is not None else ""
        viewer.kill()
        http.shutdown()
        http.server_close()
        raise ViewerUnavailableError(f"the rerun web viewer did not start on {LOOPBACK}:{web_port}"
                                     + (f": {err}" if err else ""))
    return ServedRecording(viewer_url(web_port, file_url), file_url, web_port, http, viewer)
