"""An HTTP server on 127.0.0.1 that serves one recording file and nothing else.

The rerun web viewer's page (hosted by ``rerun --serve-web`` on 127.0.0.1:<web port>) loads the
recording with one cross-origin ``GET`` of the URL it is given: mode ``cors``, header ``Accept:
*/*``, ``Origin: http://127.0.0.1:<web port>``, no credentials, no ``Range``, no preflight (rerun
0.41's viewer, seen in Chromium; without the CORS grant it shows "Failed to fetch"). So the server
answers exactly that:

* ``GET`` (and ``HEAD``) of one path, ``/<random token>/<file name>``, compared as sent (no
  decoding, no normalisation), sends the file's bytes; every other path is 404 with an empty body:
  no listing, no sibling files, no ``..`` however encoded, no symbolic links (the file is opened
  with ``O_NOFOLLOW`` from the path resolved when serving began, and must be a regular file);
* the CORS grant names the viewer page's origin only (``Access-Control-Allow-Origin:
  http://127.0.0.1:<web port>``, never ``*``), and ``Cross-Origin-Resource-Policy: same-site`` keeps
  pages of other sites from embedding the response;
* a request whose ``Host`` is not ``127.0.0.1:<port>`` (a name rebound to 127.0.0.1 by another
  site) or whose ``Origin`` is another page's is refused (403); other methods are refused (405).

The file is read at each request, so a recording written again in place is served as it is now.
Besides the file, the server answers the exact paths added with :meth:`RecordingServer.add_page`
(``/<same token>/<name>``, a query after it allowed) with bytes made in memory: ``cistrack
view``'s opening page and the blueprint for a software renderer (:mod:`.web_viewer`); never a
file of the folder.
"""
from __future__ import annotations

import os
import secrets
import stat
import sys
import threading
from collections import Counter
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from pathlib import Path
from urllib.parse import quote

from .ports import LOOPBACK

__all__ = ["RecordingServer"]

_CHUNK = 1 << 20


class _RecordingHandler(BaseHTTPRequestHandler):
    """Answers ``GET``/``HEAD`` of the server's one path with the recording; refuses the rest."""

    server: "RecordingServer"

    def version_string(self) -> str:  # the Server header: no Python version
        return "cistrack"

    def do_GET(self) -> None:
        self._answer(send_body=True)

    def do_HEAD(self) -> None:
        self._answer(send_body=False)

    def _refuse_method(self) -> None:
        self._empty(405, {"Allow": "GET, HEAD"})

    do_POST = do_PUT = do_DELETE = do_PATCH = do_OPTIONS = do_TRACE = do_CONNECT = _refuse_method

    def _answer(self, send_body: bool) -> None:
        srv = self.server
        if self.headers.get("Host") != srv.authority:
            return self._empty(403)
        origin = self.headers.get("Origin")
        if origin is not None and origin != srv.viewer_origin:
            return self._empty(403)
        page_path = self.path.split("?", 1)[0]  # a page may be given a query (the opening page's ?playback=)
        page = srv.pages.get(page_path)
        if page is not None:
            srv.served[page_path] += 1
            return self._send_page(*page, send_body=send_body)
        if self.path != srv.url_path:
            return self._empty(404)
        try:
            fd = os.open(srv.file, os.O_RDONLY | getattr(os, "O_NOFOLLOW", 0) | getattr(os, "O_NONBLOCK", 0))
        except OSError:
            return self._empty(404)
        with os.fdopen(fd, "rb", buffering=0) as fh:
            info = os.fstat(fh.fileno())
            if not stat.S_ISREG(info.st_mode):
                return self._empty(404)
            srv.served[self.path] += 1
            self.send_response(200)
            self.send_header("Content-Type", "application/octet-stream")
            self.send_header("Content-Length", str(info.st_size))
            self._common_headers()
            self.end_headers()
            if send_body:
                left = info.st_size
                while left > 0:
                    chunk = fh.read(min(_CHUNK, left))
                    if not chunk:
                        break
                    self.wfile.write(chunk)
                    left -= len(chunk)

    def _send_page(self, content_type: str, body: bytes, send_body: bool) -> None:
        self.send_response(200)
        self.send_header("Content-Type", content_type)
        self.send_header("Content-Length", str(len(body)))
        self._common_headers()
        self.end_headers()
        if send_body:
            self.wfile.write(body)

    def _common_headers(self) -> None:
        self.send_header("Access-Control-Allow-Origin", self.server.viewer_origin)
        self.send_header("Cross-Origin-Resource-Policy", "same-site")
        self.send_header("X-Content-Type-Options", "nosniff")
        self.send_header("Cache-Control", "no-store")

    def _empty(self, status: int, headers: dict[str, str] | None = None) -> None:
        self.send_response(status)
        for k, v in (headers or {}).items():
            self.send_header(k, v)
        self.send_header("Content-Length", "0")
        self.send_header("Cache-Control", "no-store")
        self.end_headers()

    def log_message(self, *args) -> None:  # quiet: the command prints the URL, not every request
        pass


class RecordingServer(ThreadingHTTPServer):
    """Serves ``file`` (an existing regular file, resolved once here) at :attr:`url` to the page
    at ``viewer_origin``; :meth:`start` serves in a background thread, :meth:`close` stops it."""

    daemon_threads = True

    def __init__(self, file: str | Path, viewer_origin: str) -> None:
        self.file = str(Path(file).resolve(strict=True))
        self.viewer_origin = viewer_origin
        self._token = secrets.token_urlsafe(18)
        self.url_path = f"/{self._token}/{quote(Path(self.file).name, safe='')}"
        self.pages: dict[str, tuple[str, bytes]] = {}
        self.served: Counter[str] = Counter()
        """How many times each path was answered with content (the file or a page)."""
        super().__init__((LOOPBACK, 0), _RecordingHandler)
        self.authority = f"{LOOPBACK}:{self.server_address[1]}"
        self._thread: threading.Thread | None = None

    @property
    def url(self) -> str:
        """The recording's address (the only file this server sends)."""
        return f"http://{self.authority}{self.url_path}"

    def add_page(self, name: str, content_type: str, body: bytes) -> str:
        """Answer ``/<token>/<name>`` with ``body``; returns its URL. ``name`` must differ from the
        recording's file name."""
        path = f"/{self._token}/{quote(name, safe='')}"
        if path == self.url_path:
            raise ValueError(f"a page may not take the recording's own name {name!r}")
        self.pages[path] = (content_type, bytes(body))
        return self.pages_url(name)

    def pages_url(self, name: str) -> str:
        """The URL of the page ``name`` (:meth:`add_page`)."""
        return f"http://{self.authority}/{self._token}/{quote(name, safe='')}"

    def handle_error(self, request, client_address) -> None:
        """A browser that stops reading mid-file (a closed tab) is not worth a traceback."""
        if isinstance(sys.exc_info()[1], ConnectionError):
            return
        super().handle_error(request, client_address)

    def start(self) -> "RecordingServer":
        self._thread = threading.Thread(target=self.serve_forever, name="cistrack-rrd-http", daemon=True)
        self._thread.start()
        return self

    def close(self) -> None:
        if self._thread is not None:
            self.shutdown()
            self._thread = None
        self.server_close()
