"""The ``sites`` parameter shared by the readers: explicit site coordinates by key.

``sites = {"KEY": {"latitude_deg": .., "longitude_deg": .., "height_m": .., "name": ..}}`` (WGS84;
or ``[lat, lon, height_m]``), or ``{"longitude_deg": .., "rho_cos_phi": .., "rho_sin_phi": ..}``
(MPC parallax constants: East longitude in degrees, rho cos(phi') and rho sin(phi') in Earth
equatorial radii, converted exactly to WGS84) declares sites that a file names by KEY; any other
key is looked up as an MPC observatory code in the bundled list.
"""
from __future__ import annotations

import logging
import math
from dataclasses import replace
from typing import Any

from cistrack.interfaces.component import check_sigma_arcsec
from cistrack.errors import MeasurementError
from cistrack.interfaces import Reader
from cistrack.astro.sites import Site, observatory, site_from_parallax

__all__ = ["parse_sites", "resolve_site", "site_columns", "replaced_code", "place_text", "REPLACED_CODE_KM"]

_SITE_FIELDS = (("latitude_deg", "longitude_deg", "height_m"), ("longitude_deg", "rho_cos_phi", "rho_sin_phi"))
"""The two ways to give a site: WGS84 geodetic, or MPC parallax constants."""


def parse_sites(owner, value: Any) -> dict[str, Site]:
    """Validate a reader's ``sites`` parameter into key -> Site (ParameterError naming the key)."""
    if value is None:
        return {}
    if not isinstance(value, dict):
        owner._fail("sites", value, "must be a table KEY -> {latitude_deg, longitude_deg, height_m}, "
                                    "KEY -> {longitude_deg, rho_cos_phi, rho_sin_phi} or KEY -> [lat, lon, height_m]")
    out = {}
    for key, spec in value.items():
        if isinstance(spec, Site):
            out[str(key)] = spec
            continue
        if isinstance(spec, (list, tuple)) and len(spec) == 3:
            spec = {"latitude_deg": spec[0], "longitude_deg": spec[1], "height_m": spec[2]}
        given = set(spec) - {"name"} if isinstance(spec, dict) else set()
        fields = next((f for f in _SITE_FIELDS if given == set(f)), None)
        if fields is None:
            owner._fail("sites", {key: spec}, f"site {key!r} needs either latitude_deg, longitude_deg, "
                                              f"height_m (WGS84: degrees, metres) or longitude_deg, "
                                              f"rho_cos_phi, rho_sin_phi (MPC parallax constants: degrees, "
                                              f"Earth equatorial radii), and optionally name")
        vals = [spec[f] for f in fields]
        if not all(isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) for v in vals):
            owner._fail("sites", {key: spec}, f"site {key!r}: coordinates must be finite numbers")
        name = str(spec.get("name", key))
        try:
            if fields == _SITE_FIELDS[0]:
                out[str(key)] = Site(float(vals[0]), float(vals[1]), float(vals[2]), name=name)
            else:
                site = site_from_parallax(str(key), name, float(vals[0]), float(vals[1]), float(vals[2]))
                out[str(key)] = replace(site, code="")  # a declared site, not one from the MPC list
        except MeasurementError as exc:
            owner._fail("sites", {key: spec}, str(exc))
        _note_replaced_code(str(key), out[str(key)])
    return out


_NOTED: set[tuple] = set()

REPLACED_CODE_KM = 1.0
"""A site given under a bundled MPC observatory code further than this (km) from the code's own
place is said to replace it (the MPC's parallax constants place a site to some tens of metres)."""


def place_text(site: Site) -> str:
    """A site's place for a message: latitude, longitude (degrees) and height (m)."""
    return f"latitude {site.latitude_deg:g}, longitude {site.longitude_deg:g}, height {site.height_m:g} m"


def replaced_code(key: str, site: Site) -> str | None:
    """The bundled MPC observatory ``key``, its place and its distance from ``site``, for a message,
    when ``site`` lies more than :data:`REPLACED_CODE_KM` from it; None otherwise (also when ``key``
    is no bundled code)."""
    try:
        known = observatory(key)
    except MeasurementError:
        return None
    km = math.dist(known.ecef_km(), site.ecef_km())
    if km <= REPLACED_CODE_KM:
        return None
    return (f"the MPC observatory {key} ({known.name or 'bundled list'}: {known.latitude_deg:.4f}, "
            f"{known.longitude_deg:.4f}, {known.height_m:.0f} m; {km:,.1f} km away)")


def _note_replaced_code(key: str, site: Site) -> None:
    """Warn (logger ``cistrack.readers``, once per process) when ``key`` is also a bundled MPC
    observatory code whose place lies more than :data:`REPLACED_CODE_KM` from ``site``: the given
    coordinates replace the observatory's, which a typing mistake would otherwise hide."""
    known = replaced_code(key, site)
    noted = (key, site.latitude_deg, site.longitude_deg, site.height_m)
    if known is not None and noted not in _NOTED:
        _NOTED.add(noted)
        logging.getLogger("cistrack.readers").warning(
            f"sites: {key!r} is given at {place_text(site)}, which replaces {known} for these observations")


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
        1-sigma noise where the file gives none, arcsec; for RA/Dec on the sky (on RA x cos(Dec)
        and on Dec), for az/el on each angle.
    sites : dict or None
        Explicit sites for station codes outside the bundled MPC list: CODE ->
        {latitude_deg, longitude_deg, height_m[, name]} (WGS84, degrees and metres) or CODE ->
        {longitude_deg, rho_cos_phi, rho_sin_phi[, name]} (MPC parallax constants, degrees and
        Earth equatorial radii).
    designation : str or None
        Read only the observations of this object (permID / provID / artSat / trkSub, MPC designation,
        TDM PARTICIPANT_2); None: all, refused when the file names several objects.
    """

    def __init__(self, sigma_arcsec: float = 1.0, sites: dict | None = None,
                 designation: str | None = None) -> None:
        self.sigma_arcsec = check_sigma_arcsec(self, "sigma_arcsec", sigma_arcsec)
        self._sites = parse_sites(self, sites)
        self.sites = sites
        if designation is not None and (not isinstance(designation, str) or not designation.strip()):
            self._fail("designation", designation, "must be an object designation (non-empty text) or absent")
        self.designation = None if designation is None else designation.strip()


class DegreesCheckedReader(SiteReader):
    """A :class:`SiteReader` whose angles must be degrees (ADES, TDM), with ``check_degrees``:
    true refuses a file whose angles all read as radians
    (:func:`~cistrack.plugins.readers.obs_rows.check_degrees`)."""

    def __init__(self, sigma_arcsec: float = 1.0, sites: dict | None = None,
                 designation: str | None = None, check_degrees: bool = True) -> None:
        super().__init__(sigma_arcsec, sites, designation)
        if not isinstance(check_degrees, bool):
            self._fail("check_degrees", check_degrees, "must be true or false")
        self.check_degrees = check_degrees

    def checked_angles(self, path, rows: list, fields: tuple[str, str], standard: str, name: str) -> list:
        """``rows`` of ``path``, refused when ``check_degrees`` is on and their angles ``fields``
        read as radians where ``standard`` has degrees (``name``: the reader, as messages say it)."""
        from .obs_rows import check_degrees

        if self.check_degrees:
            check_degrees(path, rows, fields, standard, name)
        return rows

