"""Measurements from several sites, seen by the filters and IOD as one sensor.

A measurement set read from a file may name a site per measurement (``MeasurementSet.sites``).
:func:`build_site_network` places a copy of the scenario's sensor at each site (the sensor's
``latitude_deg``, ``longitude_deg``, ``height_m`` parameters) and :class:`SiteNetwork` hands
every call at time t to the sensor of the site that measured at t, so filters and IOD methods,
which call ``sensor.measure(states, t)`` at measurement times, work unchanged. A time that is
not a measurement time (a recorder drawing the observer between measurements) goes to the site
of the nearest measurement.
"""
from __future__ import annotations

from typing import Any

import numpy as np

from cistrack.interfaces.component import param_specs
from cistrack.errors import ConfigError, MeasurementError
from cistrack.interfaces import Sensor
from cistrack.model.measurement import KIND_NAMES, MeasurementSet

__all__ = ["SiteNetwork", "build_site_network"]

_SITE_PARAMS = ("latitude_deg", "longitude_deg", "height_m")


class SiteNetwork(Sensor):
    """One sensor per site; each call is answered by the sensor of the measurement at t.

    Parameters
    ----------
    members : dict site key -> Sensor (all measuring the same components)
    times : (K,) float      measurement times, TU, non-decreasing (rows at one time come from
                            different sites)
    sites : (K,) str        site key of each measurement

    A call at a time when several sites measured is answered by the first of them (in file
    order); filters ask :meth:`for_measurement` for the sensor of each measurement instead.
    """

    def __init__(self, members: dict, times: Any, sites: Any) -> None:
        if not members:
            raise ConfigError("a site network needs at least one site")
        self.members = dict(members)
        first = next(iter(self.members.values()))
        for key, m in self.members.items():
            if tuple(m.names) != tuple(first.names):
                raise ConfigError(f"site {key!r} measures {m.names}, another site {first.names}; "
                                  f"a site network needs one set of components")
        self.names = tuple(first.names)
        self.angular = tuple(first.angular)
        self.times = np.asarray(times, dtype=float).reshape(-1)
        self.sites = np.asarray(sites, dtype=str).reshape(-1)
        missing = sorted(set(self.sites.tolist()) - set(self.members))
        if missing:
            raise ConfigError(f"no sensor for sites {missing}")
        self._keys = list(self.members)
        self._code = np.array([self._keys.index(s) for s in self.sites], dtype=np.intp)
        self.registry_name = f"site network of {first.registry_name or type(first).__name__}"

    def _member_codes(self, t, n: int | None = None) -> np.ndarray:
        tt = np.asarray(t, dtype=float).reshape(-1)
        if self.times.size == 1:
            return np.zeros(tt.shape, dtype=np.intp)
        k = np.clip(np.searchsorted(self.times, tt), 1, self.times.size - 1)
        nearer_left = np.abs(tt - self.times[k - 1]) <= np.abs(self.times[k] - tt)
        return self._code[np.where(nearer_left, k - 1, k)]

    def subset(self, rows) -> "SiteNetwork":
        """The network answering for the measurements ``rows`` (index array) only: the same
        member sensors (nothing is built again)."""
        return SiteNetwork(self.members, self.times[rows], self.sites[rows])

    def for_measurement(self, measurement) -> Sensor:
        """The member sensor at ``measurement.site`` (itself for a measurement naming no site)."""
        site = getattr(measurement, "site", "")
        if not site:
            return self
        try:
            return self.members[site]
        except KeyError:
            raise MeasurementError(f"measurement {getattr(measurement, 'index', '?')} names site {site!r}, "
                                   f"which is not in the network (sites: {', '.join(self._keys)})") from None

    def _dispatch(self, method: str, t, *arrays, out_rows: int | None = None):
        """Call ``method(*arrays_subset, t_subset)`` on each member for the rows it owns."""
        tt = np.asarray(t, dtype=float)
        if tt.ndim == 0:
            code = int(self._member_codes(tt)[0])
            return getattr(self.members[self._keys[code]], method)(*arrays, float(tt))
        codes = self._member_codes(tt)
        result = None
        for c in np.unique(codes):
            rows = np.nonzero(codes == c)[0]
            part = getattr(self.members[self._keys[c]], method)(*[a[rows] for a in arrays], tt[rows])
            part = np.asarray(part)
            if result is None:
                result = np.zeros((tt.shape[0],) + part.shape[1:], dtype=part.dtype)
            result[rows] = part
        return result

    def measure(self, states, t):
        return self._dispatch("measure", t, np.atleast_2d(np.asarray(states, dtype=float)))

    def sigmas(self, states, t):
        return self._dispatch("sigmas", t, np.atleast_2d(np.asarray(states, dtype=float)))

    def visible(self, states, t):
        return self._dispatch("visible", t, np.atleast_2d(np.asarray(states, dtype=float)))

    def observer_position(self, t):
        tt = np.asarray(t, dtype=float)
        if tt.ndim == 0:
            return self._dispatch("observer_position", tt)
        codes = self._member_codes(tt)
        out = np.zeros((tt.shape[0], 3))
        for c in np.unique(codes):
            rows = np.nonzero(codes == c)[0]
            out[rows] = np.asarray(self.members[self._keys[c]].observer_position(tt[rows])).reshape(rows.size, 3)
        return out

    def line_of_sight(self, angles, t):
        a = np.atleast_2d(np.asarray(angles, dtype=float))
        return self._dispatch("line_of_sight", t, a)

    def inertial_frame(self):
        return next(iter(self.members.values())).inertial_frame()

    def passes(self, times, states):
        raise MeasurementError("a site network answers for measurements already taken; "
                               "plan passes with the sensor of one site")

    def simulate(self, states, times, rng):
        raise MeasurementError("a site network does not simulate; simulate with each site's sensor "
                               "and merge the sets")


def build_site_network(spec, registry, measurements: MeasurementSet) -> Sensor:
    """The scenario's sensor ``spec`` (a ComponentSpec) placed at every site of
    ``measurements``; a set without sites gets the sensor itself."""
    if measurements.sites is None:
        return spec.build(registry)
    factory = registry.get("sensor", spec.name).factory
    specs = param_specs(factory) if isinstance(factory, type) else {}
    if not all(p in specs for p in _SITE_PARAMS):
        raise ConfigError(f"{spec.where}: the measurements name their sites but sensor {spec.name!r} has no "
                          f"{', '.join(_SITE_PARAMS)} parameters to place it there")
    kinds = set(measurements.kinds.tolist()) if measurements.kinds is not None else set()
    members = {}
    for key in measurements.site_keys():
        site = measurements.site_table[key]
        params = {k: (v.build(registry) if hasattr(v, "build") and hasattr(v, "kind") else v)
                  for k, v in spec.params.items()}
        params.update(latitude_deg=float(site.latitude_deg), longitude_deg=float(site.longitude_deg),
                      height_m=float(site.height_m))
        if len(kinds) == 1 and "measurement" in specs and "measurement" not in spec.params:
            params["measurement"] = next(iter(kinds))  # a sensor that measures either type
        members[key] = registry.create("sensor", spec.name, **params)
    first = next(iter(members.values()))
    for kind in kinds:
        if tuple(first.names[:2]) != KIND_NAMES[kind]:
            raise ConfigError(f"{spec.where}: the measurements are {kind} ({', '.join(KIND_NAMES[kind])}) but "
                              f"sensor {spec.name!r} measures {', '.join(first.names)}; choose a sensor "
                              f"(or its parameters) measuring {kind}")
    return SiteNetwork(members, measurements.times, measurements.sites)


def one_per_time(measurements: MeasurementSet, sensor, say=lambda msg: None):
    """``(measurements, sensor)`` with one measurement per time tag, the first in file order, and
    the network answering for those: what the IOD is given (its fits assume one observer per
    time). Unchanged when no two measurements share a time."""
    groups = measurements.time_groups()
    if len(groups) == len(measurements):
        return measurements, sensor
    first = np.array([g[0] for g in groups])
    say(f"{len(measurements)} measurements at {len(groups)} times: the IOD uses the first site's at each "
        f"time, the filter all of them (one step per time)")
    return measurements.subset(first), sensor.subset(first)


def merge_sites(parts) -> MeasurementSet:
    """One time-ordered set from ``parts``: an iterable of (site key, Site, MeasurementSet of that
    site, all with the same component names). Measurements at the same time from two sites are
    kept, in the order of ``parts`` (a filter takes them in one step); two at the same time from
    one site are refused by the set."""
    parts = list(parts)
    if not parts:
        raise MeasurementError("no measurement sets to merge")
    names = tuple(parts[0][2].names)
    for key, _site, ms in parts:
        if tuple(ms.names) != names:
            raise MeasurementError(f"site {key!r} measured {ms.names}, another site {names}")
    times = np.concatenate([ms.times for _k, _s, ms in parts])
    order = np.argsort(times, kind="stable")
    values = np.concatenate([ms.values for _k, _s, ms in parts])[order]
    sigmas = np.concatenate([ms.sigmas for _k, _s, ms in parts])[order]
    sites = np.concatenate([np.full(len(ms), key) for key, _s, ms in parts])[order]
    kind = [k for k, pair in KIND_NAMES.items() if pair == names[:2]]
    kinds = np.full(times.size, kind[0]) if kind else None
    return MeasurementSet(times[order], values, sigmas, names, dict(parts[0][2].meta), sites, kinds,
                          {key: site for key, site, _ms in parts})
