"""The real-sky sensor exports in GCRF: the Moon's synodic position maps to DE421's geocentric Moon."""
from __future__ import annotations

import numpy as np

from cistrack.astro.ephemeris import de421
from cistrack.plugin.registry import default_registry
from cistrack.units import TU_S


def test_real_telescope_places_the_moon_where_de421_has_it():
    sensor = default_registry().create("sensor", "real-telescope", epoch="2026-03-01T00:00:00Z")
    frame = sensor.inertial_frame()
    assert frame.name == "GCRF" and frame.ccsds and frame.center == "EARTH"
    t = np.array([0.0, 0.3, 1.1])
    moon_syn = sensor._frame.moon_synodic(t)
    states = np.concatenate([moon_syn, np.zeros_like(moon_syn)], axis=1)
    gcrs = frame.from_synodic(states, t)
    jd1, jd2 = sensor._frame.epoch_tdb
    pos, _vel = de421().moon(np.full(3, jd1), jd2 + t * TU_S / 86400.0)
    np.testing.assert_allclose(gcrs[:, :3], pos, atol=1e-6)
