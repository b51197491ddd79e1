"""Observing sites: geodetic coordinates, and MPC observatory codes from a bundled table.

A :class:`Site` is a WGS84 geodetic position (latitude, East longitude, height above the
ellipsoid). MPC observatory codes are looked up in ``cistrack/data/mpc_observatories.csv``, a
bundled subset of the Minor Planet Center's list (code, East longitude, parallax constants
rho*cos(phi'), rho*sin(phi') in Earth equatorial radii); nothing is downloaded. Codes outside
the table are given to readers as explicit coordinates (their ``sites`` parameter).

The parallax constants are converted to geodetic coordinates exactly: the Earth-fixed position
(rho cos phi' cos lon, rho cos phi' sin lon, rho sin phi') x 6378.137 km is inverted to WGS84
latitude and height by Bowring's iteration (converged to < 1e-9 m).
"""
from __future__ import annotations

import csv
import math
from dataclasses import dataclass
from functools import lru_cache
from importlib import resources

from cistrack.errors import MeasurementError
from cistrack.astro.primaries import EARTH_RADIUS_KM

__all__ = ["Site", "observatory", "observatory_codes", "site_from_parallax", "EARTH_EQUATORIAL_RADIUS_KM"]

EARTH_EQUATORIAL_RADIUS_KM = EARTH_RADIUS_KM
"""WGS84 equatorial radius, km (also the unit of the MPC parallax constants)."""
_F = 1.0 / 298.257223563
_E2 = _F * (2.0 - _F)


@dataclass(frozen=True)
class Site:
    """A ground site. Angles in degrees (East longitude positive), height in metres (WGS84).

    ``Site(latitude_deg, longitude_deg, height_m, name="", code="")``; ``code`` is the MPC
    observatory code when the site came from one ("" otherwise).
    """

    latitude_deg: float
    longitude_deg: float
    height_m: float = 0.0
    name: str = ""
    code: str = ""

    def __post_init__(self) -> None:
        for attr in ("latitude_deg", "longitude_deg", "height_m"):
            v = getattr(self, attr)
            if not isinstance(v, (int, float)) or isinstance(v, bool) or not math.isfinite(v):
                raise MeasurementError(f"site {self.name!r}: {attr} = {v!r} must be a finite number")
        if not -90.0 <= self.latitude_deg <= 90.0:
            raise MeasurementError(f"site {self.name!r}: latitude_deg {self.latitude_deg} is outside [-90, 90]")
        if not -360.0 <= self.longitude_deg <= 360.0:
            raise MeasurementError(f"site {self.name!r}: longitude_deg {self.longitude_deg} is outside [-360, 360]")
        if not -12_000.0 <= self.height_m <= 100_000.0:
            raise MeasurementError(f"site {self.name!r}: height_m {self.height_m} is outside [-12000, 100000]")

    def ecef_km(self) -> tuple[float, float, float]:
        """Earth-fixed (WGS84) position, km."""
        lat, lon = math.radians(self.latitude_deg), math.radians(self.longitude_deg)
        n = EARTH_EQUATORIAL_RADIUS_KM / math.sqrt(1.0 - _E2 * math.sin(lat) ** 2)
        h = self.height_m / 1000.0
        return ((n + h) * math.cos(lat) * math.cos(lon), (n + h) * math.cos(lat) * math.sin(lon),
                (n * (1.0 - _E2) + h) * math.sin(lat))


def site_from_parallax(code: str, name: str, longitude_deg: float, rho_cos_phi: float,
                       rho_sin_phi: float) -> Site:
    """The geodetic site of MPC parallax constants (Earth equatorial radii)."""
    lon = longitude_deg - 360.0 if longitude_deg > 180.0 else longitude_deg
    p = rho_cos_phi * EARTH_EQUATORIAL_RADIUS_KM
    z = rho_sin_phi * EARTH_EQUATORIAL_RADIUS_KM
    if p == 0.0 and z == 0.0:
        raise MeasurementError(f"observatory {code} ({name}) is the geocentre, not a ground site")
    lat = math.atan2(z, p * (1.0 - _E2))
    h = 0.0
    for _ in range(50):
        n = EARTH_EQUATORIAL_RADIUS_KM / math.sqrt(1.0 - _E2 * math.sin(lat) ** 2)
        h_new = (p / math.cos(lat) - n) if abs(lat) < math.radians(80) else (z / math.sin(lat) - n * (1.0 - _E2))
        lat_new = math.atan2(z, p * (1.0 - _E2 * n / (n + h_new)))
        done = abs(lat_new - lat) < 1e-15 and abs(h_new - h) < 1e-12
        lat, h = lat_new, h_new
        if done:
            break
    return Site(name=name, latitude_deg=math.degrees(lat), longitude_deg=lon, height_m=h * 1000.0, code=code)


@lru_cache(maxsize=1)
def _table() -> dict[str, tuple[float, float, float, str]]:
    text = resources.files("cistrack").joinpath("data/mpc_observatories.csv").read_text(encoding="utf-8")
    rows = [r for r in csv.reader(line for line in text.splitlines() if line and not line.startswith("#"))]
    out = {}
    for r in rows[1:]:
        out[r[0]] = (float(r[1]), float(r[2]), float(r[3]), r[4])
    return out


def observatory_codes() -> list[str]:
    """The MPC observatory codes in the bundled table, sorted."""
    return sorted(_table())


def observatory(code: str) -> Site:
    """The ground site of MPC observatory ``code`` from the bundled table.

    Raises MeasurementError for a code not in the table (give its coordinates explicitly) or
    for the geocentre (500)."""
    try:
        lon, rc, rs, name = _table()[str(code)]
    except KeyError:
        raise MeasurementError(f"MPC observatory code {code!r} is not in cistrack's bundled table "
                               f"({len(_table())} codes); give its coordinates explicitly (reader "
                               f"parameter 'sites')") from None
    return site_from_parallax(str(code), name, lon, rc, rs)
