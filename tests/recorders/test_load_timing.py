"""The load timing of :mod:`.viewer_shots` (``viewer_shots.py RUN.rrd --load-only``): pictures that
show the same count as one, a missing curve does not; in headless Chromium (slow) a recording's
load time is measured from the first drawn picture to the settled one."""
from __future__ import annotations

import math

import numpy as np
import pytest

from .headless_browser import find_chromium
from .viewer_shots import same_picture, timings


def _picture() -> np.ndarray:
    rng = np.random.default_rng(5)
    return rng.integers(0, 256, size=(500, 800, 3)).astype(np.uint8)


def test_pictures_differing_by_encoding_noise_are_the_same():
    a = _picture()
    noise = np.random.default_rng(6).integers(-30, 31, size=a.shape)
    assert same_picture(a, np.clip(a.astype(int) + noise, 0, 255))


def test_a_picture_missing_a_curve_is_not_the_same():
    a = np.full((500, 800, 3), 255, dtype=np.uint8)
    b = a.copy()
    b[200, 100:400] = (214, 39, 40)  # a red curve one pixel wide, 300 long
    assert not same_picture(a, b)


@pytest.mark.slow
def test_load_timing_of_a_recording_in_the_browser(recorded_run):
    if find_chromium() is None:
        pytest.skip("chromium is not installed (apt-get install -y chromium)")
    out = timings(recorded_run.small_rrd, max_load_s=120.0, play=False)
    assert math.isfinite(out["viewer_up_s"]) and out["viewer_up_s"] <= out["load_s"] < 120.0
