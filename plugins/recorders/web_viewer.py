"""Open a recording in a browser: the rerun web viewer plus the .rrd served on 127.0.0.1.

``cistrack view FILE.rrd`` (and the slow browser test) use :func:`serve_recording`: a
:class:`~.recording_server.RecordingServer` serves that one file (and nothing else) to the viewer's
page, ``rerun --serve-web`` hosts the web viewer, and the URL
``http://127.0.0.1:<web port>/?url=<file URL>`` opens the viewer with the recording loaded (the plain
viewer address opens its welcome page). Both servers listen on 127.0.0.1 only.

``cistrack view`` prints :attr:`ServedRecording.page_url`, an opening page on the recording's
server (:mod:`.opening_page`) that goes on to that URL, or, in a browser that renders in software,
to :attr:`ServedRecording.software_url`: the recording with a second blueprint
(``/<token>/<name>.software.rbl``, built from the inputs the recording carries,
:mod:`.blueprint_inputs`) whose playback speed is set for such a viewer. A recording without those
inputs (another program's, an older cistrack's) has no software URL and plays at its own speed.

The web port is checked before anything starts (an integer from 1 to 65535, not in use by another
process), and the URL is returned only once the viewer we started is the process listening on it,
so it never opens another process's viewer. The viewer process dies with the process that started
it, even one killed with SIGKILL (Linux: :func:`.viewer_process.parent_death_preexec`), so it never
keeps the port after ``cistrack view`` is gone.
"""
from __future__ import annotations

import logging
import subprocess
import tempfile
from dataclasses import dataclass, field
from pathlib import Path
from urllib.parse import quote

from cistrack.errors import CistrackError
from cistrack.interfaces.limits import check_port

from .blueprint import APPLICATION_ID
from .recording_check import recording_problem
from .blueprint_inputs import read_blueprint_inputs
from .opening_page import opening_page, software_blueprint
from .ports import LOOPBACK, PortInUseError, ensure_port_free, in_use_message
from .recording_server import RecordingServer
from .viewer_process import ViewerUnavailableError, find_viewer_executable, parent_death_preexec
from .viewer_process import wait_for_port as _wait_for_port

__all__ = ["ServedRecording", "serve_recording", "viewer_url"]

_LOG = logging.getLogger("cistrack.recorders")


def viewer_url(web_port: int, *file_urls: str) -> str:
    """The web viewer's address with the files at ``file_urls`` (a recording, then blueprints) to load."""
    query = "&".join(f"url={quote(u, safe='')}" for u in file_urls)
    return f"http://{LOOPBACK}:{web_port}/?{query}"


@dataclass
class ServedRecording:
    """A recording being served; :meth:`close` stops both servers. ``url`` opens the viewer with the
    recording; ``software_url`` (or None) with the blueprint at ``blueprint_url`` (for a software
    renderer) too; ``page_url`` is the opening page that chooses between them."""

    url: str
    file_url: str
    web_port: int
    _http: RecordingServer = field(repr=False)
    _viewer: subprocess.Popen = field(repr=False)
    page_url: str = ""
    software_url: str | None = None
    blueprint_url: str | None = None

    @property
    def served(self) -> dict[str, int]:
        """How many times each URL path of the recording's server was answered with content."""
        return dict(self._http.served)

    def close(self) -> None:
        self._http.close()
        if self._viewer.poll() is None:
            self._viewer.terminate()
            try:
                self._viewer.wait(timeout=10)
            except subprocess.TimeoutExpired:
                self._viewer.kill()
                self._viewer.wait()

    def __enter__(self) -> "ServedRecording":
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def _stop(viewer: subprocess.Popen) -> None:
    if viewer.poll() is None:
        viewer.kill()
    viewer.wait()


def _add_pages(http: RecordingServer, rrd: Path, web_port: int) -> tuple[str, str | None, str | None]:
    """Add the software renderer's blueprint (when the recording carries its inputs) and the
    opening page to ``http``; returns the viewer URL, the software renderer's and the blueprint's
    (both None without inputs)."""
    url, software_url, rbl = viewer_url(web_port, http.url), None, None
    inputs = read_blueprint_inputs(rrd)
    blueprint = None
    if inputs is not None:
        try:
            blueprint = software_blueprint(inputs, APPLICATION_ID)
        except Exception as exc:  # the software variant is an extra: without it the recording plays as written
            _LOG.debug("no software renderer's blueprint for %s: %s", rrd, exc)
    if blueprint is not None:
        rbl = http.add_page(f"{rrd.stem}.software.rbl", "application/octet-stream", blueprint)
        software_url = viewer_url(web_port, http.url, rbl)
    http.add_page("view", "text/html; charset=utf-8", opening_page(rrd.name, url, software_url))
    return url, software_url, rbl


def serve_recording(path: str | Path, web_port: int = 9090, timeout_s: float = 30.0,
                    option: str = "--port") -> ServedRecording:
    """Serve ``path`` (an .rrd file) and the rerun web viewer on 127.0.0.1; returns the URL to open.

    ``option`` names what chose ``web_port`` in errors: a port outside 1-65535 is a
    :class:`~cistrack.errors.ConfigError`, one held by another process a
    :class:`~.ports.PortInUseError`, both raised before anything starts."""
    rrd = Path(path)
    if not rrd.is_file():
        raise CistrackError(f"recording not found: {path}" if not rrd.exists()
                            else f"{path}: not a file; expected a rerun recording (.rrd)")
    rrd = rrd.resolve()
    if rrd.suffix != ".rrd":
        raise CistrackError(f"{path}: expected a rerun recording (.rrd)")
    problem = recording_problem(rrd)
    if problem:
        _LOG.warning(f"warning: {problem}")
    web_port = check_port(web_port, option)
    ensure_port_free(web_port, option)
    exe = find_viewer_executable()
    if exe is None:
        raise ViewerUnavailableError("the rerun viewer is not installed (it ships with rerun-sdk: "
                                     "pip install rerun-sdk); cannot host the web viewer")
    http = RecordingServer(rrd, viewer_origin=f"http://{LOOPBACK}:{web_port}")
    try:
        url, software_url, rbl = _add_pages(http, rrd, web_port)
    except BaseException:
        http.server_close()
        raise
    http.start()
    # the viewer's log goes to a file: a pipe nobody reads would block it once full
    with tempfile.TemporaryFile() as log:
        viewer = subprocess.Popen([exe, "--serve-web", "--bind", LOOPBACK, "--web-viewer-port", str(web_port),
                                   http.url], stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=log,
                                  preexec_fn=parent_death_preexec())
        if _wait_for_port(web_port, viewer, timeout_s):
            return ServedRecording(url, http.url, web_port, http, viewer, page_url=http.pages_url("view"),
                                   software_url=software_url, blueprint_url=rbl)
        _stop(viewer)
        http.close()
        log.seek(0)
        err = log.read().decode(errors="replace").strip()[-800:]
    if "address already in use" in err.lower() or "os error 98" in err.lower():
        raise PortInUseError(in_use_message(web_port, option))
    raise ViewerUnavailableError(f"the rerun web viewer did not start on {LOOPBACK}:{web_port}"
                                 + (f": {err}" if err else ""))
