"""Screenshots of a page in headless Chromium through the DevTools protocol (over a pipe).

``--screenshot`` alone captures before a WebGL/WebGPU page has drawn; the protocol lets us wait
for the page, then ask for the picture. The protocol runs over ``--remote-debugging-pipe``
(file descriptors 3 and 4, NUL-terminated JSON), so no WebSocket client is needed.

Run as a script for one picture of a recording as it opens (the README's start, middle and end
pictures come from :mod:`.viewer_shots`):
    .venv/bin/python tests/recorders/headless_browser.py RUN.rrd OUT.png
"""
from __future__ import annotations

import base64
import contextlib
import json
import os
import shutil
import subprocess
import tempfile
import time
from pathlib import Path

FLAGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking",
         "--disable-component-update", "--disable-sync", "--no-first-run",
         "--enable-unsafe-swiftshader", "--use-angle=swiftshader", "--hide-scrollbars"]


def find_chromium() -> str | None:
    for name in ("chromium", "chromium-browser", "google-chrome"):
        exe = shutil.which(name)
        if exe:
            return exe
    return None


class _Pipe:
    def __init__(self, proc: subprocess.Popen, to_browser: int, from_browser: int):
        self.proc, self.wfd, self.rfd = proc, to_browser, from_browser
        self.buf = b""
        self.next_id = 0

    def _read_message(self, deadline: float) -> dict:
        while b"\0" not in self.buf:
            if time.monotonic() > deadline:
                raise TimeoutError("no answer from Chromium")
            chunk = os.read(self.rfd, 1 << 20)
            if not chunk:
                raise RuntimeError(f"Chromium closed the pipe (exit {self.proc.poll()})")
            self.buf += chunk
        msg, self.buf = self.buf.split(b"\0", 1)
        return json.loads(msg)

    def call(self, method: str, params: dict | None = None, session: str | None = None,
             timeout_s: float = 60.0) -> dict:
        self.next_id += 1
        msg = {"id": self.next_id, "method": method, "params": params or {}}
        if session:
            msg["sessionId"] = session
        os.write(self.wfd, json.dumps(msg).encode() + b"\0")
        deadline = time.monotonic() + timeout_s
        while True:
            reply = self._read_message(deadline)
            if reply.get("id") == self.next_id:
                if "error" in reply:
                    raise RuntimeError(f"{method}: {reply['error']}")
                return reply.get("result", {})


_KEY_CODES = {"Home": 36, "End": 35, "ArrowLeft": 37, "ArrowRight": 39, " ": 32}
_MODIFIERS = {"Alt": 1, "Ctrl": 2, "Meta": 4, "Shift": 8}


def _press(pipe: _Pipe, session: str, chord: str) -> None:
    """Press and release a key chord such as "End" or "Ctrl+ArrowRight" in the page."""
    *mods, key = chord.split("+")
    flags = sum(_MODIFIERS[m] for m in mods)
    base = {"key": key, "code": "Space" if key == " " else key, "modifiers": flags,
            "windowsVirtualKeyCode": _KEY_CODES[key], "nativeVirtualKeyCode": _KEY_CODES[key]}
    pipe.call("Input.dispatchKeyEvent", {"type": "rawKeyDown", **base}, session)
    pipe.call("Input.dispatchKeyEvent", {"type": "keyUp", **base}, session)


class Page:
    """One page of a headless Chromium started by :func:`open_page`: press keys, take pictures."""

    def __init__(self, pipe: _Pipe, session: str, size: tuple[int, int] = (1600, 1000)):
        self._pipe, self._session, self._size = pipe, session, size

    def press(self, chord: str) -> None:
        """Press and release a key chord such as "End", " " or "Ctrl+ArrowRight"."""
        _press(self._pipe, self._session, chord)

    def run_command(self, words: str, wait_s: float = 3.0) -> None:
        """Run a command of the viewer's command palette: Ctrl+K opens it, ``words`` pick the
        command ("end of timeline" is "Go to end of timeline"), Enter runs it."""
        for kind, key, code, vk, mods, text in (("rawKeyDown", "k", "KeyK", 75, _MODIFIERS["Ctrl"], None),
                                                ("keyUp", "k", "KeyK", 75, _MODIFIERS["Ctrl"], None)):
            self._pipe.call("Input.dispatchKeyEvent", {"type": kind, "key": key, "code": code, "modifiers": mods,
                                                       "windowsVirtualKeyCode": vk, "nativeVirtualKeyCode": vk},
                            self._session)
        time.sleep(wait_s)
        self._pipe.call("Input.insertText", {"text": words}, self._session)
        time.sleep(wait_s)
        enter = {"key": "Enter", "code": "Enter", "windowsVirtualKeyCode": 13, "nativeVirtualKeyCode": 13}
        self._pipe.call("Input.dispatchKeyEvent", {"type": "keyDown", "text": "\r", **enter}, self._session)
        self._pipe.call("Input.dispatchKeyEvent", {"type": "keyUp", **enter}, self._session)

    def png(self, wait_s: float = 30.0) -> bytes:
        """A PNG of the page as it is drawn now (retried for up to ``wait_s`` seconds while the
        page that is loading is not yet there to draw)."""
        return self._capture({"format": "png"}, wait_s)

    def quick_picture(self, scale: float = 0.5, wait_s: float = 30.0) -> bytes:
        """A JPEG of the whole page at ``scale`` (0.5: 800 x 500 for the default page), encoded for
        speed: a fraction of a PNG's cost, so that polling it while the viewer loads takes little of
        the CPU the viewer needs. Chromium answers once the page draws its next frame."""
        w, h = self._size
        return self._capture({"format": "jpeg", "quality": 80, "optimizeForSpeed": True,
                              "clip": {"x": 0, "y": 0, "width": w, "height": h, "scale": scale}}, wait_s)

    def _capture(self, params: dict, wait_s: float) -> bytes:
        deadline = time.monotonic() + wait_s
        while True:
            try:
                data = self._pipe.call("Page.captureScreenshot", params, self._session, timeout_s=120.0)
                return base64.b64decode(data["data"])
            except RuntimeError:
                if time.monotonic() > deadline:
                    raise
                time.sleep(0.5)


@contextlib.contextmanager
def open_page(url: str, *, width: int = 1600, height: int = 1000, chromium: str | None = None):
    """Headless Chromium (software rendering) showing ``url`` in a ``width`` x ``height`` page;
    yields a :class:`Page` right after navigating (nothing waited for) and stops Chromium after."""
    exe = chromium or find_chromium()
    if exe is None:
        raise FileNotFoundError("chromium is not installed (Debian: apt-get install -y chromium)")
    profile = tempfile.mkdtemp(prefix="cistrack-chromium-")
    to_r, to_w = os.pipe()      # we write commands -> Chromium reads fd 3
    from_r, from_w = os.pipe()  # Chromium writes fd 4 -> we read
    proc = None
    try:
        def child_fds():
            os.dup2(to_r, 3)
            os.dup2(from_w, 4)

        proc = subprocess.Popen([exe, *FLAGS, f"--user-data-dir={profile}", "--remote-debugging-pipe",
                                 f"--window-size={width},{height}", "about:blank"],
                                stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                                preexec_fn=child_fds, pass_fds=(3, 4, to_r, from_w))
        os.close(to_r)
        os.close(from_w)
        pipe = _Pipe(proc, to_w, from_r)
        target = pipe.call("Target.createTarget", {"url": "about:blank"})["targetId"]
        session = pipe.call("Target.attachToTarget", {"targetId": target, "flatten": True})["sessionId"]
        pipe.call("Emulation.setDeviceMetricsOverride",
                  {"width": width, "height": height, "deviceScaleFactor": 1, "mobile": False}, session)
        pipe.call("Page.enable", {}, session)
        pipe.call("Page.navigate", {"url": url}, session)
        yield Page(pipe, session, (width, height))
    finally:
        if proc is not None:
            proc.terminate()
            try:
                proc.wait(timeout=10)
            except subprocess.TimeoutExpired:
                proc.kill()
        shutil.rmtree(profile, ignore_errors=True)


def screenshots(url: str, shots: list[tuple[str | Path, list[str]]], *, width: int = 1600,
                height: int = 1000, settle_s: float = 25.0, after_keys_s: float = 6.0,
                key_interval_s: float = 0.3, chromium: str | None = None) -> list[Path]:
    """Open ``url``, wait ``settle_s`` seconds for it to draw, then for each ``(png, keys)`` of
    ``shots`` press the key chords ``keys`` in order (e.g. ``["Ctrl+ArrowRight"]`` steps the
    viewer's time to the next logged time; ``"command:WORDS"`` runs a command of the viewer's palette,
    e.g. ``"command:end of timeline"``), wait ``after_keys_s`` seconds when keys were pressed, and
    write a PNG to ``png``. Key chords are ``key_interval_s`` apart."""
    written = []
    with open_page(url, width=width, height=height, chromium=chromium) as page:
        time.sleep(settle_s)
        for png, keys in shots:
            for chord in keys:
                if chord.startswith("command:"):
                    page.run_command(chord[len("command:"):])
                else:
                    page.press(chord)
                time.sleep(key_interval_s)
            if keys:
                time.sleep(after_keys_s)
            out = Path(png)
            out.parent.mkdir(parents=True, exist_ok=True)
            out.write_bytes(page.png())
            written.append(out)
    return written


def screenshot(url: str, out_png: str | Path, *, width: int = 1600, height: int = 1000,
               settle_s: float = 25.0, chromium: str | None = None) -> Path:
    """Open ``url``, wait ``settle_s`` seconds for it to draw, write a PNG to ``out_png``."""
    return screenshots(url, [(out_png, [])], width=width, height=height, settle_s=settle_s,
                       chromium=chromium)[0]


if __name__ == "__main__":
    import sys

    sys.path.insert(0, str(Path(__file__).resolve().parents[2]))
    from cistrack.plugins.recorders.web_viewer import serve_recording

    rrd, png = sys.argv[1], sys.argv[2]
    settle = float(sys.argv[3]) if len(sys.argv) > 3 else 25.0
    with serve_recording(rrd, web_port=9097) as served:
        print(served.url)
        print(screenshot(served.url, png, settle_s=settle))
