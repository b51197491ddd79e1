"""A third-party observer that moves, written against the documented interfaces only: it passes
the conformance suite, a scenario hands it the run's dynamics, and the suite catches an observer
whose path depends on the order of the times asked."""
from __future__ import annotations

import numpy as np
import pytest

from cistrack.api import Dynamics, MeasurementSet, Sensor
from cistrack.plugin.registry import load_registry
from cistrack.scenario.loading import parse_scenario
from cistrack.testing import check_plugin
from cistrack.testing.check_results import ConformanceError

GEO_KM, LU_KM, TU_S = 42_164.0, 384_400.0, 375_149.0


class GeoTelescope(Sensor):
    """RA/Dec (equatorial model axes) from an observer starting on a geostationary-radius circle
    and moved by the run's dynamics (one propagate call per request)."""

    names = ("right_ascension", "declination")
    angular = (True, False)

    def __init__(self, sigma_arcsec: float = 1.0, dynamics: Dynamics | str | None = None) -> None:
        if dynamics is None:
            from cistrack.plugins.dynamics.cr3bp import CR3BP
            dynamics = CR3BP()
        self.sigma_arcsec, self.dynamics = self.check_positive("sigma_arcsec", sigma_arcsec), dynamics
        mu, r = 0.01215058, GEO_KM / LU_KM
        v = np.sqrt((1 - mu) / r) - r                   # circular inertial speed, minus the frame's turn
        self._x0 = np.array([-mu + r, 0.0, 0.0, 0.0, v, 0.0])

    def check_positive(self, name, value):
        from cistrack.interfaces.component import check_positive
        return check_positive(self, name, value)

    def observer_position(self, t):
        tt = np.atleast_1d(np.asarray(t, dtype=float))
        uniq, inv = np.unique(tt, return_inverse=True)
        out = np.tile(self._x0[:3], (uniq.size, 1))
        later = uniq > 0
        if later.any():
            out[later] = self.dynamics.propagate(self._x0[None], 0.0, uniq[later]).states[:, 0, :3]
        pos = out[inv.reshape(-1)]
        return pos[0] if np.ndim(t) == 0 else pos

    def _rot(self, t, n):
        a = np.broadcast_to(np.asarray(t, dtype=float), (n,))
        c, s = np.cos(a), np.sin(a)
        return np.stack([np.stack([c, -s, 0 * c], -1), np.stack([s, c, 0 * c], -1),
                         np.stack([0 * c, 0 * c, 1 + 0 * c], -1)], 1)

    def measure(self, states, t):
        x = np.asarray(states, dtype=float)
        if x.ndim != 2 or x.shape[1] != 6 or not np.all(np.isfinite(x)):
            from cistrack.errors import MeasurementError
            raise MeasurementError(f"sensor 'geo-telescope': states must be finite (N, 6), got {x.shape}")
        p = np.einsum("nij,nj->ni", self._rot(t, x.shape[0]), x[:, :3] - self.observer_position(t))
        return np.stack([np.mod(np.arctan2(p[:, 1], p[:, 0]), 2 * np.pi),
                         np.arctan2(p[:, 2], np.hypot(p[:, 0], p[:, 1]))], 1)

    def sigmas(self, states, t):
        z = self.measure(states, t)
        s = np.full(z.shape, self.sigma_arcsec * np.pi / 648000)
        s[:, 0] /= np.cos(z[:, 1])
        return s

    def visible(self, states, t):
        return np.ones(np.asarray(states).shape[0], dtype=bool)

    def line_of_sight(self, angles, t):
        a = np.asarray(angles, dtype=float)
        u = np.stack([np.cos(a[:, 1]) * np.cos(a[:, 0]), np.cos(a[:, 1]) * np.sin(a[:, 0]), np.sin(a[:, 1])], 1)
        return np.einsum("nji,nj->ni", self._rot(t, a.shape[0]), u)

    def simulate(self, states, times, rng):
        z, s = self.measure(states, times), self.sigmas(states, times)
        v = z + rng.standard_normal(z.shape) * s
        v[:, 0] = np.mod(v[:, 0], 2 * np.pi)
        return MeasurementSet(np.asarray(times, dtype=float), v, s, self.names, {"sensor": "geo-telescope"})


class ForgetfulGeoTelescope(GeoTelescope):
    """Broken on purpose: the observer's path shifts with how many times it was asked before."""

    def __init__(self, sigma_arcsec: float = 1.0, dynamics: Dynamics | str | None = None) -> None:
        super().__init__(sigma_arcsec, dynamics)
        self._asked = 0

    def observer_position(self, t):
        self._asked += 1
        return super().observer_position(t) + 1e-9 * self._asked


def test_a_moving_third_party_sensor_passes_the_conformance_suite():
    assert check_plugin(GeoTelescope)


def test_the_suite_catches_an_observer_path_that_depends_on_what_was_asked_before():
    with pytest.raises(ConformanceError, match="observer_path_consistent"):
        check_plugin(ForgetfulGeoTelescope)


def test_a_scenario_hands_the_third_party_sensor_its_truth_dynamics():
    reg = load_registry()
    reg.add("sensor", "geo-telescope", GeoTelescope)
    scen = parse_scenario({
        "name": "geo", "duration_days": 2.0, "truth": {"orbit": "nrho-9-2", "dynamics": {"name": "cr3bp", "rtol": 1e-11}},
        "dynamics": {"name": "cr3bp"}, "sensor": {"name": "geo-telescope"}, "schedule": {"name": "every"},
        "iod": {"name": "uniform-range"}, "filter": {"name": "ukf"}}, registry=reg)
    sensor = scen.build("sensor", reg)
    assert isinstance(sensor, GeoTelescope) and sensor.dynamics.rtol == 1e-11
