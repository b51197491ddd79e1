"""The recording opens in the web viewer as the README promises (headless Chromium, slow).

A short run is recorded, served with ``cistrack.plugins.recorders.web_viewer`` and opened at the
printed URL in headless Chromium; the DevTools screenshot must show the run, not the viewer's
welcome page: the 3-D view on its dark background with coloured particles and ellipsoids, and
every time-series panel with a curve across most of its width (the whole run, not a minute).
Needs Debian's ``chromium`` (``make test-all`` installs it); skipped without it.
"""
from __future__ import annotations

import socket
import subprocess
import sys

import numpy as np
import pytest

from .headless_browser import find_chromium, screenshot

pytestmark = pytest.mark.slow

N_SERIES_PANELS = 6  # error, sigma position, sigma velocity, entropy, NEES, component weights


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.fixture(scope="module")
def picture(tmp_path_factory) -> np.ndarray:
    if find_chromium() is None:
        pytest.skip("chromium is not installed (apt-get install -y chromium)")
    from PIL import Image

    from cistrack.plugins.recorders.web_viewer import serve_recording

    d = tmp_path_factory.mktemp("viewer")
    rrd = d / "quick.rrd"
    proc = subprocess.run([sys.executable, "-m", "cistrack.cli", "run", "quick", "--rerun", str(rrd),
                           "--out", str(d / "run"), "--quiet"], capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    with serve_recording(rrd, web_port=_free_port()) as served:
        png = screenshot(served.url, d / "viewer.png", settle_s=30.0)
    return np.asarray(Image.open(png).convert("RGB")).astype(int)


def _region(img: np.ndarray, x0: float, x1: float, y0: float, y1: float) -> np.ndarray:
    h, w, _ = img.shape
    return img[int(y0 * h):int(y1 * h), int(x0 * w):int(x1 * w)]


def _coloured(img: np.ndarray) -> np.ndarray:
    return (img.max(axis=2) - img.min(axis=2)) > 60


def test_the_3d_views_show_the_scene_not_the_welcome_page(picture):
    run_view = _region(picture, 0.02, 0.58, 0.08, 0.56)
    system_view = _region(picture, 0.02, 0.58, 0.64, 0.94)
    assert run_view.mean() < 110 and system_view.mean() < 110  # the dark 3-D background
    assert _coloured(run_view).mean() > 0.002  # particles coloured by component, ellipsoids


def test_every_time_series_panel_draws_and_most_span_the_run(picture):
    """A curve that falls to its axis early (velocity sigma) may look short; the others must
    span most of the panel, which a one-minute window at the cursor never does."""
    series = _region(picture, 0.62, 0.99, 0.04, 0.96)
    rows = np.array_split(np.arange(series.shape[0]), N_SERIES_PANELS)
    spreads = [float(_coloured(series[r[len(r) // 5]:r[-1]]).any(axis=0).mean()) for r in rows]
    assert min(spreads) > 0.05, f"a time-series panel is empty: {spreads}"
    assert sum(s > 0.5 for s in spreads) >= N_SERIES_PANELS - 1, f"curves do not span the run: {spreads}"
