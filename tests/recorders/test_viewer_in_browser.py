"""The recording reads in the web viewer as the README promises (headless Chromium, slow).

The quick scenario is recorded, served with ``cistrack.plugins.recorders.web_viewer`` and opened
in headless Chromium; screenshots at the start, middle and end of the run (see
:mod:`.viewer_shots`) must show the run, not the viewer's welcome page: the dark 3-D views, the
particle cloud and its ellipsoids filling the run view at every time (the IOD cloud spans Earth
to beyond L2, the converged one about a hundred km), time series that are not flattened onto their
axis, and every series panel with a curve across the run.

``CISTRACK_VIEWER_RRD=FILE.rrd`` checks that recording instead of a fresh one (a recording of
the recorder before the run view existed fails the cloud and series checks). Needs Debian's
``chromium`` (``make test-all`` installs it); skipped without it.
"""
from __future__ import annotations

import os
import subprocess
import sys

import numpy as np
import pytest

from .headless_browser import find_chromium
from .viewer_shots import SHOTS, cloud_mask, cloud_spread, particle_pixels, raised_fraction, region, take

pytestmark = pytest.mark.slow

N_SERIES_PANELS = 6  # position, velocity, entropy, NEES, component weights, maneuver detector


@pytest.fixture(scope="module")
def pictures(tmp_path_factory) -> dict[str, np.ndarray]:
    if find_chromium() is None:
        pytest.skip("chromium is not installed (apt-get install -y chromium)")
    from PIL import Image

    d = tmp_path_factory.mktemp("viewer")
    rrd = os.environ.get("CISTRACK_VIEWER_RRD")
    if not rrd:
        rrd = d / "quick.rrd"
        proc = subprocess.run([sys.executable, "-m", "cistrack.cli", "run", "quick", "--rerun", str(rrd),
                               "--out", str(d / "run"), "--quiet"], capture_output=True, text=True)
        assert proc.returncode == 0, proc.stderr
    pngs = take(rrd, d)
    return {name: np.asarray(Image.open(png).convert("RGB")).astype(int) for name, png in pngs.items()}


def _coloured(img: np.ndarray) -> np.ndarray:
    return (img.max(axis=2) - img.min(axis=2)) > 60


def test_the_3d_views_show_the_scene_not_the_welcome_page(pictures):
    img = pictures["start"]
    run_view = region(img, (0.02, 0.58, 0.08, 0.56))
    system_view = region(img, (0.02, 0.58, 0.64, 0.94))
    assert run_view.mean() < 110 and system_view.mean() < 110  # the dark 3-D background


@pytest.mark.parametrize("shot", SHOTS)
def test_the_cloud_fills_the_run_view_at_the_start_middle_and_end(pictures, shot):
    """Particles and ellipsoids of the first two components, spread over a good part of the view
    (a cloud framed on the IOD shrinks to a dot of a few pixels after the first pass)."""
    mask = cloud_mask(pictures[shot])
    assert mask.sum() > 800, f"{shot}: {mask.sum()} cloud pixels in the run view"
    assert cloud_spread(mask) > 0.3, f"{shot}: the cloud spans {cloud_spread(mask):.2f} of the run view"


@pytest.mark.parametrize("shot", SHOTS)
def test_particles_not_only_ellipsoids_are_drawn_at_the_start_middle_and_end(pictures, shot):
    """The shots of a viewer that had stopped drawing the particles (rerun 0.41, stepped in a
    fast burst) held 0 such pixels; shots of spread clouds with their particles 31 to 1,192
    (viewer_shots.KEY_INTERVAL_S, viewer_shots.particle_pixels)."""
    assert particle_pixels(pictures[shot]) > 20, f"{shot}: no particle drawn in the run view"


def test_the_position_series_is_not_flattened_onto_its_axis(pictures):
    assert raised_fraction(pictures["end"]) > 0.8


def test_every_time_series_panel_draws_and_most_span_the_run(pictures):
    series = region(pictures["end"], (0.62, 0.99, 0.04, 0.96))
    rows = np.array_split(np.arange(series.shape[0]), N_SERIES_PANELS)
    spreads = [float(_coloured(series[r[len(r) // 5]:r[-1]]).any(axis=0).mean()) for r in rows]
    assert min(spreads) > 0.05, f"a time-series panel is empty: {spreads}"
    assert sum(s > 0.5 for s in spreads) >= N_SERIES_PANELS - 1, f"curves do not span the run: {spreads}"
