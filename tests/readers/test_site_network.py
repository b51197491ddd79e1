"""Measurements of several sites, answered by the sensor of the site that measured."""
from __future__ import annotations

import numpy as np
import pytest

from cistrack.errors import ConfigError, MeasurementError
from cistrack.model.measurement import MeasurementSet
from cistrack.plugin.registry import default_registry
from cistrack.scenario.loading import ComponentSpec
from cistrack.astro.site_network import SiteNetwork, build_site_network, merge_sites
from cistrack.astro.sites import observatory


def _telescope(code):
    s = observatory(code)
    return default_registry().create("sensor", "ground-telescope", latitude_deg=s.latitude_deg,
                                     longitude_deg=s.longitude_deg, height_m=s.height_m)


@pytest.fixture(scope="module")
def network_and_members(nrho_arc):
    times, states = nrho_arc
    t = times[::20][:12]
    sites = np.array(["711", "809"] * 6)
    members = {"711": _telescope("711"), "809": _telescope("809")}
    return SiteNetwork(members, t, sites), members, t, sites, states[::20][:12]


def test_each_call_is_answered_by_the_site_that_measured_then(network_and_members):
    net, members, t, sites, x = network_and_members
    z = net.measure(x, t)
    for k in range(len(t)):
        np.testing.assert_allclose(z[k], members[sites[k]].measure(x[k:k + 1], t[k])[0], rtol=1e-14, atol=1e-15)
    np.testing.assert_array_equal(net.measure(x[3:4], t[3]), members[sites[3]].measure(x[3:4], t[3]))


def test_observer_and_line_of_sight_follow_the_site(network_and_members):
    net, members, t, sites, x = network_and_members
    obs = net.observer_position(t)
    los = net.line_of_sight(net.measure(x, t), t)
    for k in (0, 1, 5):
        np.testing.assert_array_equal(obs[k], members[sites[k]].observer_position(t[k]))
        np.testing.assert_allclose(los[k], members[sites[k]].line_of_sight(net.measure(x[k:k + 1], t[k]), t[k])[0])
    assert not np.allclose(obs[0], obs[1])  # the two sites really differ


def test_a_time_between_measurements_goes_to_the_nearest_measurement_site(network_and_members):
    net, members, t, sites, _ = network_and_members
    mid = t[0] + 0.1 * (t[1] - t[0])
    np.testing.assert_array_equal(net.observer_position(mid), members[sites[0]].observer_position(mid))


def test_merge_names_each_measurement_by_its_site(network_and_members):
    _, members, t, _, x = network_and_members
    rng = np.random.default_rng(0)
    a = members["711"].simulate(x[::2], t[::2], rng)
    b = members["809"].simulate(x[1::2], t[1::2], rng)
    ms = merge_sites([("711", observatory("711"), a), ("809", observatory("809"), b)])
    assert ms.sites.tolist() == ["711", "809"] * 6 and ms.kinds.tolist() == ["azel"] * 12
    np.testing.assert_array_equal(ms.values[0], a.values[0])
    with pytest.raises(MeasurementError, match="repeats site '711'"):
        merge_sites([("711", observatory("711"), a), ("711", observatory("711"), a)])


def test_merge_keeps_two_sites_measuring_at_the_same_time_in_the_order_given(network_and_members):
    _, members, t, _, x = network_and_members
    rng = np.random.default_rng(0)
    a = members["711"].simulate(x, t, rng)
    b = members["809"].simulate(x, t, rng)
    ms = merge_sites([("711", observatory("711"), a), ("809", observatory("809"), b)])
    assert ms.sites.tolist() == ["711", "809"] * 12 and len(ms.time_groups()) == 12
    np.testing.assert_array_equal(ms.values[1], b.values[0])


def test_for_measurement_answers_with_the_site_that_took_it(network_and_members):
    net, members, t, _, x = network_and_members
    rng = np.random.default_rng(0)
    ms = merge_sites([("711", observatory("711"), members["711"].simulate(x, t, rng)),
                      ("809", observatory("809"), members["809"].simulate(x, t, rng))])
    for i in (0, 1):  # the same time, two sites: each measurement predicted from its own site
        m = ms[i]
        np.testing.assert_array_equal(net.for_measurement(m).measure(x[:1], m.t), members[m.site].measure(x[:1], m.t))


def test_build_places_the_scenario_sensor_at_every_site(network_and_members):
    _, members, t, sites, x = network_and_members
    ms = MeasurementSet(t, np.zeros((12, 2)), np.ones((12, 2)), ("azimuth", "elevation"), sites=sites,
                        kinds=np.full(12, "azel"), site_table={"711": observatory("711"), "809": observatory("809")})
    spec = ComponentSpec("sensor", "ground-telescope", {"sigma_arcsec": 2.0}, "test")
    net = build_site_network(spec, default_registry(), ms)
    assert net.members["809"].latitude_deg == pytest.approx(observatory("809").latitude_deg)
    assert net.members["711"].sigma_arcsec == 2.0


def test_build_refuses_ra_dec_for_an_az_el_sensor(network_and_members):
    _, _, t, sites, _ = network_and_members
    ms = MeasurementSet(t, np.zeros((12, 2)), np.ones((12, 2)), ("right_ascension", "declination"), sites=sites,
                        kinds=np.full(12, "radec"), site_table={"711": observatory("711"), "809": observatory("809")})
    with pytest.raises(ConfigError, match="radec.*measures azimuth, elevation"):
        build_site_network(ComponentSpec("sensor", "ground-telescope", {}, "test"), default_registry(), ms)


def test_a_site_given_under_a_bundled_code_elsewhere_is_said_to_replace_it(caplog):
    from cistrack.plugins.readers.ades_psv import AdesPsvReader

    with caplog.at_level("WARNING", logger="cistrack.readers"):
        AdesPsvReader(sites={"809": {"latitude_deg": 1.5, "longitude_deg": 2.5, "height_m": 0.0}})
    assert "'809' is given at latitude 1.5" in caplog.text and "replaces the MPC observatory 809" in caplog.text


def test_a_site_given_where_its_bundled_code_is_says_nothing(caplog):
    from cistrack.astro.sites import observatory
    from cistrack.plugins.readers.ades_psv import AdesPsvReader

    la_silla = observatory("809")
    with caplog.at_level("WARNING", logger="cistrack.readers"):
        AdesPsvReader(sites={"809": [la_silla.latitude_deg, la_silla.longitude_deg, la_silla.height_m]})
    assert "replaces" not in caplog.text
