"""Observing sites: geodetic coordinates, and MPC observatory codes from a bundled table.

A :class:`Site` is a WGS84 geodetic position (latitude, East longitude, height above the
ellipsoid). MPC observatory codes are looked up in ``cistrack/data/mpc_observatories.csv``, the
Minor Planet Center's full list of observatory codes (code, East longitude, parallax constants
rho*cos(phi'), rho*sin(phi') in Earth equatorial radii, name; its header names the source and
date); nothing is downloaded. Codes of roving and space-based observers (no fixed parallax
constants in the list, e.g. 247, 250, C51) and the geocentre (500, 244) are refused with a
message saying so. Sites outside the list are given to readers as explicit coordinates (their
``sites`` parameter: WGS84 latitude/longitude/height, or parallax constants).

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

from cistrack.errors import MeasurementError, quoted
from cistrack.astro.primaries import EARTH_RADIUS_KM

__all__ = ["Site", "observatory", "observatory_codes", "site_from_parallax", "EARTH_EQUATORIAL_RADIUS_KM",
           "MIN_HEIGHT_M", "MAX_HEIGHT_M"]

EARTH_EQUATORIAL_RADIUS_KM = EARTH_RADIUS_KM
"""WGS84 equatorial radius, km (also the unit of the MPC parallax constants)."""
_F = 1.0 / 298.257223563
_E2 = _F * (2.0 - _F)


MIN_HEIGHT_M = -12_000.0
"""The lowest site height accepted, metres above the WGS84 ellipsoid: the MPC's rounded parallax
constants put some bundled observatories (506 Bendestorf, -9,254 m) kilometres below it."""
MAX_HEIGHT_M = 100_000.0
"""The highest site height accepted, metres (the edge of space)."""


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
        if not MIN_HEIGHT_M <= self.height_m <= MAX_HEIGHT_M:
            raise MeasurementError(f"site {self.name!r}: height_m {self.height_m} is outside "
                                   f"[{MIN_HEIGHT_M:.0f}, {MAX_HEIGHT_M:.0f}]")

    def ecef_km(self) -> tuple[float, float, float]:
        """Earth-fixed (WGS84) position, km."""
        lat, lon = math.radians(self.latitude_deg), math.radians(self.longitude_deg)
        n = EARTH_EQUATORIAL_RADIUS_KM / math.sqrt(1.0 - _E2 * math.sin(lat) ** 2)
        h = self.height_m / 1000.0
        return ((n + h) * math.cos(lat) * math.cos(lon), (n + h) * math.cos(lat) * math.sin(lon),
                (n * (1.0 - _E2) + h) * math.sin(lat))


def site_from_parallax(code: str, name: str, longitude_deg: float, rho_cos_phi: float,
                       rho_sin_phi: float) -> Site:
    """The WGS84 geodetic site of MPC parallax constants.

    ``longitude_deg``: East longitude, degrees (0 to 360, or -180 to 180); ``rho_cos_phi`` (>= 0)
    and ``rho_sin_phi``: rho cos(phi') and rho sin(phi'), the distance from the Earth's axis and
    from its equatorial plane in Earth equatorial radii (6378.137 km; phi' the geocentric
    latitude). Raises MeasurementError naming ``code`` for values that are not finite numbers,
    a negative rho cos(phi'), the geocentre, or a point whose height is outside the
    :class:`Site` bounds."""
    vals = {"longitude_deg": longitude_deg, "rho_cos_phi": rho_cos_phi, "rho_sin_phi": rho_sin_phi}
    for key, v in vals.items():
        if not isinstance(v, (int, float)) or isinstance(v, bool) or not math.isfinite(v):
            raise MeasurementError(f"observatory {code} ({name}): {key} = {v!r} must be a finite number")
    if not -360.0 <= longitude_deg <= 360.0:
        raise MeasurementError(f"observatory {code} ({name}): longitude_deg {longitude_deg} is outside [-360, 360]")
    if rho_cos_phi < 0.0:
        raise MeasurementError(f"observatory {code} ({name}): rho_cos_phi {rho_cos_phi} must be >= 0 "
                               f"(the distance from the Earth's axis, Earth radii)")
    lon = longitude_deg - 360.0 if longitude_deg > 180.0 else (
        longitude_deg + 360.0 if longitude_deg < -180.0 else longitude_deg)
    p = rho_cos_phi * EARTH_EQUATORIAL_RADIUS_KM
    z = rho_sin_phi * EARTH_EQUATORIAL_RADIUS_KM
    if p == 0.0 and z == 0.0:
        raise MeasurementError(f"observatory {code} ({name}) has parallax constants (0, 0): the geocentre, "
                               f"not a ground site")
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
def _table() -> dict[str, tuple[float, float, float, str] | tuple[None, None, None, str]]:
    """code -> (East longitude deg, rho cos phi', rho sin phi' in Earth radii, name); the three
    numbers are None for a roving or space-based observer (empty fields in the table)."""
    text = resources.files("cistrack").joinpath("data/mpc_observatories.csv").read_text(encoding="utf-8")
    rows = [r for r in csv.reader(line for line in text.splitlines() if line and not line.startswith("#"))]
    out: dict = {}
    for r in rows[1:]:
        out[r[0]] = ((None, None, None, r[4]) if not (r[1] or r[2] or r[3])
                     else (float(r[1]), float(r[2]), float(r[3]), r[4]))
    return out


def observatory_codes() -> list[str]:
    """The MPC observatory codes that :func:`observatory` resolves to a ground site, sorted
    (every code of the bundled list but roving and space-based observers and the geocentre)."""
    return sorted(c for c, (lon, rc, rs, _n) in _table().items() if rc is not None and (rc, rs) != (0.0, 0.0))


def _case_hint(code: str) -> str:
    """" (did you mean 'G96', NAME?)" when ``code`` in upper case is a code of the list (MPC codes
    are upper case: a lower-case 'g96' had been refused with no hint), else ""."""
    row = _table().get(code.upper())
    return f" (did you mean {code.upper()!r}, {row[3]}?)" if row is not None and code.upper() != code else ""


def observatory(code: str) -> Site:
    """The ground site of MPC observatory ``code`` from the bundled list.

    Raises MeasurementError for a code not in the list (give its coordinates explicitly), for a
    roving or space-based observer (no fixed parallax constants) and for the geocentre (500)."""
    try:
        lon, rc, rs, name = _table()[str(code)]
    except KeyError:
        raise MeasurementError(f"MPC observatory code {quoted(code)} is not in the MPC list bundled with "
                               f"cistrack ({len(_table())} codes){_case_hint(str(code))}; give its coordinates "
                               f"explicitly (reader parameter 'sites')") from None
    if lon is None or rc is None or rs is None:
        raise MeasurementError(f"MPC observatory code {code!r} ({name}) is a roving or space-based "
                               f"observer: the MPC list gives it no fixed parallax constants, and "
                               f"cistrack reads observations from fixed ground sites only (give a "
                               f"fixed site's coordinates in the reader parameter 'sites')")
    return site_from_parallax(str(code), name, lon, rc, rs)
