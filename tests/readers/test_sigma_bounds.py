"""Angle sigmas, given to a reader, a simulated sensor or in a file, lie between a micro-arcsecond
and 180 degrees (SIGMA_ARCSEC_BOUNDS): outside them they are a unit or typing mistake, and the
fits weighted by them fail far from the cause."""
from __future__ import annotations

import pytest

from cistrack.errors import ParameterError
from cistrack.interfaces.component import SIGMA_ARCSEC_BOUNDS
from cistrack.plugin.registry import default_registry
from cistrack.plugins.readers.ades_psv import AdesPsvReader


@pytest.mark.parametrize("sigma", [1e300, 1e-30, 1e6])
def test_a_readers_sigma_outside_the_bounds_is_refused_by_name(sigma):
    with pytest.raises(ParameterError, match="'sigma_arcsec'.*arcsec"):
        AdesPsvReader(sigma_arcsec=sigma)


@pytest.mark.parametrize("sensor", ["ground-telescope", "space-telescope"])
def test_a_simulated_sensors_sigma_outside_the_bounds_is_refused_by_name(sensor):
    with pytest.raises(ParameterError, match="'sigma_arcsec'"):
        default_registry().create("sensor", sensor, sigma_arcsec=1e9)


@pytest.mark.parametrize("sigma", SIGMA_ARCSEC_BOUNDS)
def test_the_bounds_themselves_are_allowed(sigma):
    assert AdesPsvReader(sigma_arcsec=sigma).sigma_arcsec == sigma
