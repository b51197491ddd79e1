"""The page ``cistrack view`` prints: it picks the viewer URL for the browser that opens it.

Rerun moves the time cursor by at most :data:`.blueprint.FRAME_CAP_S` of each frame, so a browser
that renders in software (no GPU: SwiftShader, llvmpipe, a remote desktop's basic driver) plays a
run about 15 times slower than the recording's speed intends. The page asks the browser's WebGL
which renderer it has and goes on (``location.replace``) to the viewer with the recording alone,
or, on a software renderer, with the recording and a blueprint whose playback speed is set for
:data:`.blueprint.SOFTWARE_FRAME_S` seconds per frame. ``?playback=software`` or
``?playback=gpu`` after the page's URL chooses instead.
"""
from __future__ import annotations

import html
import json
import tempfile
from pathlib import Path

from .blueprint import SOFTWARE_FRAME_S
from .blueprint_inputs import BlueprintInputs

__all__ = ["SOFTWARE_RENDERERS", "opening_page", "software_blueprint"]

SOFTWARE_RENDERERS = r"swiftshader|llvmpipe|softpipe|lavapipe|software|basic render"
"""What, in the WebGL renderer's name (case ignored), marks a software renderer; a browser without
WebGL counts as one too."""

_PAGE = """<!doctype html>
<html lang="en"><head><meta charset="utf-8"><title>cistrack view: {title}</title></head>
<body style="font-family: sans-serif">
<p id="what">Opening the rerun viewer for {title}&hellip;</p>
<noscript><p>Without JavaScript, choose: <a href="{gpu_attr}">the viewer</a>{software_link}.</p></noscript>
<script>
(function () {{
  var gpu = {gpu_js}, software = {software_js};
  function renderer() {{
    try {{
      var gl = document.createElement("canvas").getContext("webgl2")
            || document.createElement("canvas").getContext("webgl");
      if (!gl) return "";
      var ext = gl.getExtension("WEBGL_debug_renderer_info");
      return String(gl.getParameter(ext ? ext.UNMASKED_RENDERER_WEBGL : gl.RENDERER));
    }} catch (e) {{ return ""; }}
  }}
  var asked = new URLSearchParams(location.search).get("playback");
  var name = asked ? "" : renderer();
  var slow = asked ? asked === "software" : (name === "" || /{pattern}/i.test(name));
  document.getElementById("what").textContent = slow && software
    ? "Software renderer (" + (name || "asked for") + "): opening the viewer with playback set for it."
    : "Opening the rerun viewer.";
  location.replace(slow && software ? software : gpu);
}})();
</script>
</body></html>
"""


def _js(url: str | None) -> str:
    """A JavaScript string literal (or null) safe inside a <script> element."""
    return json.dumps(url).replace("<", "\\u003c").replace(">", "\\u003e").replace("&", "\\u0026")


def opening_page(title: str, gpu_url: str, software_url: str | None) -> bytes:
    """The HTML of the opening page (UTF-8): it goes on to ``gpu_url``, or to ``software_url``
    (when there is one) in a browser that renders in software."""
    link = "" if software_url is None else f', or <a href="{html.escape(software_url)}">for a software renderer</a>'
    return _PAGE.format(title=html.escape(title), gpu_attr=html.escape(gpu_url), software_link=link,
                        gpu_js=_js(gpu_url), software_js=_js(software_url), pattern=SOFTWARE_RENDERERS).encode()


def software_blueprint(inputs: BlueprintInputs, application_id: str) -> bytes:
    """A blueprint file (.rbl bytes) for ``application_id``: the recording's default blueprint with
    the playback speed of a viewer drawing a frame every :data:`.blueprint.SOFTWARE_FRAME_S` s."""
    with tempfile.TemporaryDirectory(prefix="cistrack-blueprint-") as tmp:
        path = Path(tmp) / "software.rbl"
        inputs.blueprint(frame_s=SOFTWARE_FRAME_S).save(application_id, str(path))
        return path.read_bytes()
