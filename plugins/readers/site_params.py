"""The ``sites`` parameter shared by the readers: explicit site coordinates by key.

``sites = {"KEY": {"latitude_deg": .., "longitude_deg": .., "height_m": .., "name": ..}}`` (or
``[lat, lon, height_m]``) declares sites that a file names by KEY; any other key is looked up as
an MPC observatory code in the bundled table.
"""
from __future__ import annotations

import math
from typing import Any

from cistrack.interfaces.component import check_positive
from cistrack.errors import MeasurementError
from cistrack.interfaces import Reader
from cistrack.astro.sites import Site, observatory

__all__ = ["parse_sites", "resolve_site", "site_columns"]


def parse_sites(owner, value: Any) -> dict[str, Site]:
    """Validate a reader's ``sites`` parameter into key -> Site (ParameterError naming the key)."""
    if value is None:
        return {}
    if not isinstance(value, dict):
        owner._fail("sites", value, "must be a table KEY -> {latitude_deg, longitude_deg, height_m} "
                                    "or KEY -> [lat, lon, height_m]")
    out = {}
    for key, spec in value.items():
        if isinstance(spec, Site):
            out[str(key)] = spec
            continue
        if isinstance(spec, (list, tuple)) and len(spec) == 3:
            spec = {"latitude_deg": spec[0], "longitude_deg": spec[1], "height_m": spec[2]}
        if not isinstance(spec, dict) or not {"latitude_deg", "longitude_deg", "height_m"} <= set(spec) \
                or not set(spec) <= {"latitude_deg", "longitude_deg", "height_m", "name"}:
            owner._fail("sites", {key: spec}, f"site {key!r} needs latitude_deg, longitude_deg, height_m "
                                              f"(and optionally name)")
        vals = [spec["latitude_deg"], spec["longitude_deg"], spec["height_m"]]
        if not all(isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) for v in vals):
            owner._fail("sites", {key: spec}, f"site {key!r}: coordinates must be finite numbers")
        try:
            out[str(key)] = Site(float(vals[0]), float(vals[1]), float(vals[2]), name=str(spec.get("name", key)))
        except MeasurementError as exc:
            owner._fail("sites", {key: spec}, str(exc))
    return out


def resolve_site(key: str, explicit: dict[str, Site]) -> Site:
    """The site of ``key``: an explicit site, else an MPC observatory code (MeasurementError)."""
    if key in explicit:
        return explicit[key]
    return observatory(key)


def site_columns(site: Site) -> tuple[str, str, str]:
    """Latitude, longitude, height as exact text (for writers that record coordinates)."""
    return repr(float(site.latitude_deg)), repr(float(site.longitude_deg)), repr(float(site.height_m))


class SiteReader(Reader):
    """A reader whose files name observatories: the parameters every such format shares.

    Parameters
    ----------
    sigma_arcsec : float
        1-sigma noise of each angle where the file gives none, arcsec.
    sites : dict or None
        Explicit sites for station codes outside the bundled MPC table: CODE ->
        {latitude_deg, longitude_deg, height_m[, name]}.
    """

    def __init__(self, sigma_arcsec: float = 1.5, sites: dict | None = None) -> None:
        self.sigma_arcsec = check_positive(self, "sigma_arcsec", sigma_arcsec)
        self._sites = parse_sites(self, sites)
        self.sites = sites
