"""When an optical sensor can see a target: exclusion cones about bright bodies and a detection
model from the target's brightness. Ground and space telescopes judge a target alike with these.

Exclusion (limb-based): the target is excluded when the angle between the line of sight and the
direction to a body's centre is less than the body's apparent radius ``asin(R / d)`` plus the
configured exclusion angle, i.e. when it lies within ``exclusion_deg`` of the body's limb (or on
its disc). A negative exclusion angle turns the rule off for that body.

Detection: the target is a Lambertian (diffuse) sphere of diameter ``D`` and Bond-like albedo
``p`` lit by the Sun. Its visual magnitude at observer distance ``rho``, Sun distance ``r_s`` and
phase angle ``phi`` (Sun-target-observer) is

    m = m_sun - 2.5 log10( (2/3) p (D/2)^2 F(phi) / rho^2 ) + 5 log10(r_s / 1 AU),
    F(phi) = ((pi - phi) cos phi + sin phi) / pi,

with m_sun = -26.74 (V, at 1 AU). The target is detected when m <= ``limiting_magnitude``; at
full phase (phi = pi) F = 0 and the target is never detected. A 2 m sphere of albedo 0.2 at
lunar distance and zero phase is magnitude 18.4.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cistrack.astro.observer import AU_KM

__all__ = ["M_SUN_V", "ExclusionRules", "Photometry", "SkyRules", "sky_rules", "RULE_KEYS", "limb_margins", "phase_angle",
           "lambert_phase_function", "apparent_magnitude"]

M_SUN_V: float = -26.74
"""Apparent visual magnitude of the Sun at 1 AU."""


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def limb_margins(los_km: np.ndarray, body_km: np.ndarray, radius_km: float) -> np.ndarray:
    """Angle (N,) rad from the line of sight to a body's limb: the angle between ``los_km``
    (N, 3, observer -> target) and ``body_km`` (N, 3, observer -> body centre) minus the body's
    apparent radius. Negative: the line of sight crosses the disc. An observer inside the body
    has the whole sky on its disc (-pi)."""
    d = np.linalg.norm(body_km, axis=1)
    cosang = np.clip(np.einsum("ni,ni->n", _unit(los_km), _unit(body_km)), -1.0, 1.0)
    half = np.arcsin(np.clip(radius_km / d, 0.0, 1.0))
    return np.where(d > radius_km, np.arccos(cosang) - half, -np.pi)


def phase_angle(obs_to_target_km: np.ndarray, sun_to_target_km: np.ndarray) -> np.ndarray:
    """Sun-target-observer angle (N,) rad, from the two vectors (N, 3) pointing at the target."""
    c = np.einsum("ni,ni->n", _unit(obs_to_target_km), _unit(sun_to_target_km))
    return np.arccos(np.clip(c, -1.0, 1.0))


def lambert_phase_function(phi: np.ndarray) -> np.ndarray:
    """Diffuse sphere's phase function F(phi) = ((pi - phi) cos phi + sin phi) / pi, in [0, 1]."""
    p = np.asarray(phi, dtype=float)
    return np.clip(((np.pi - p) * np.cos(p) + np.sin(p)) / np.pi, 0.0, 1.0)


def apparent_magnitude(obs_to_target_km: np.ndarray, sun_to_target_km: np.ndarray,
                       diameter_m: float, albedo: float) -> np.ndarray:
    """Visual magnitude (N,) of a diffuse sphere (module docstring); +inf at full phase."""
    rho = np.linalg.norm(obs_to_target_km, axis=1) * 1000.0
    rs = np.linalg.norm(sun_to_target_km, axis=1)
    flux = (2.0 / 3.0) * albedo * (0.5 * diameter_m) ** 2 * lambert_phase_function(
        phase_angle(obs_to_target_km, sun_to_target_km)) / rho ** 2
    with np.errstate(divide="ignore"):
        return M_SUN_V - 2.5 * np.log10(flux) + 5.0 * np.log10(rs / AU_KM)


@dataclass(frozen=True)
class ExclusionRules:
    """Exclusion angles from the limbs of the Sun, Earth and Moon, degrees (negative: off)."""

    sun_deg: float = -1.0
    earth_deg: float = -1.0
    moon_deg: float = -1.0

    @property
    def active(self) -> bool:
        return self.sun_deg >= 0 or self.earth_deg >= 0 or self.moon_deg >= 0

    def allowed(self, los_km: np.ndarray, bodies_from_observer: dict[str, np.ndarray],
                radii_km: dict[str, float]) -> np.ndarray:
        """(N,) bool: the line of sight (N, 3) clears every active cone; ``bodies_from_observer``
        maps "sun", "earth", "moon" to observer -> body vectors (N, 3) km."""
        ok = np.ones(los_km.shape[0], dtype=bool)
        for body, deg in (("sun", self.sun_deg), ("earth", self.earth_deg), ("moon", self.moon_deg)):
            if deg >= 0:
                ok &= limb_margins(los_km, bodies_from_observer[body], radii_km[body]) >= np.radians(deg)
        return ok


@dataclass(frozen=True)
class Photometry:
    """The detection model: target diameter (m), albedo, limiting visual magnitude (<= 0: off)
    and the largest range at which the target is sought, km (<= 0: no limit)."""

    diameter_m: float = 2.0
    albedo: float = 0.2
    limiting_magnitude: float = 0.0
    max_range_km: float = 0.0

    @property
    def active(self) -> bool:
        return self.limiting_magnitude > 0 or self.max_range_km > 0

    def detected(self, obs_to_target_km: np.ndarray, sun_to_target_km: np.ndarray) -> np.ndarray:
        """(N,) bool: bright enough and close enough (vectors (N, 3) km pointing at the target)."""
        ok = np.ones(obs_to_target_km.shape[0], dtype=bool)
        if self.max_range_km > 0:
            ok &= np.linalg.norm(obs_to_target_km, axis=1) <= self.max_range_km
        if self.limiting_magnitude > 0:
            ok &= apparent_magnitude(obs_to_target_km, sun_to_target_km, self.diameter_m,
                                     self.albedo) <= self.limiting_magnitude
        return ok


RULE_KEYS: dict[str, tuple[float, float]] = {
    "sun_exclusion_deg": (-1.0, 180.0), "earth_exclusion_deg": (-1.0, 180.0), "moon_exclusion_deg": (-1.0, 180.0),
    "sun_max_elevation_deg": (-90.0, 90.0), "diameter_m": (1e-6, 1e6), "albedo": (1e-6, 1.0),
    "limiting_magnitude": (-30.0, 40.0), "max_range_km": (-1.0, 1e9)}
"""Keys of a ground telescope's ``visibility`` table and their allowed ranges (the space
telescope's parameters of the same names)."""


@dataclass(frozen=True)
class SkyRules:
    """Exclusion cones, detection model and, for a ground site, the darkest sky it needs: the
    Sun's elevation at most ``sun_max_elevation_deg`` (90: any time of day)."""

    exclusion: ExclusionRules = ExclusionRules()
    photometry: Photometry = Photometry()
    sun_max_elevation_deg: float = 90.0

    @property
    def active(self) -> bool:
        return self.exclusion.active or self.photometry.active or self.sun_max_elevation_deg < 90.0

    def allowed(self, los_km: np.ndarray, observer_km: np.ndarray, bodies_km: dict[str, np.ndarray],
                radii_km: dict[str, float], up: np.ndarray | None = None) -> np.ndarray:
        """(N,) bool for lines of sight ``los_km`` (N, 3) from observers at ``observer_km`` (N or 1,
        3) with the Sun, Earth and Moon at ``bodies_km`` (K = N or 1, 3), all in one frame, km;
        ``up`` (N or 1, 3) the site's local vertical (for the Sun's elevation), None in space."""
        rel = {k: np.broadcast_to(v - observer_km, los_km.shape) for k, v in bodies_km.items()}
        ok = self.exclusion.allowed(los_km, rel, radii_km)
        if self.photometry.active:
            ok &= self.photometry.detected(los_km, los_km - rel["sun"])
        if up is not None and self.sun_max_elevation_deg < 90.0:
            sin_el = np.einsum("ni,ni->n", np.broadcast_to(up, los_km.shape), _unit(rel["sun"]))
            ok &= sin_el <= np.sin(np.radians(self.sun_max_elevation_deg))
        return ok


def sky_rules(owner, table) -> SkyRules:
    """The rules of a sensor's ``visibility`` table (keys of :data:`RULE_KEYS`; absent keys are
    off, or the detection model's defaults); a bad key or value fails through ``owner._fail``."""
    if table is None:
        return SkyRules()
    if not isinstance(table, dict):
        owner._fail("visibility", table, "must be a table of " + ", ".join(RULE_KEYS))
    for key, value in table.items():
        if key not in RULE_KEYS:
            owner._fail("visibility", table, f"unknown key {key!r}; allowed: " + ", ".join(RULE_KEYS))
        lo, hi = RULE_KEYS[key]
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not lo <= float(value) <= hi:
            owner._fail("visibility", table, f"{key} = {value!r} must be a number in [{lo:g}, {hi:g}]")
    v = {k: float(x) for k, x in table.items()}
    return SkyRules(ExclusionRules(v.get("sun_exclusion_deg", -1.0), v.get("earth_exclusion_deg", -1.0),
                                   v.get("moon_exclusion_deg", -1.0)),
                    Photometry(v.get("diameter_m", 2.0), v.get("albedo", 0.2), v.get("limiting_magnitude", 0.0),
                               v.get("max_range_km", 0.0)),
                    v.get("sun_max_elevation_deg", 90.0))
