"""Where to point: a fitted orbit's topocentric RA/Dec from a ground site, with its uncertainty
ellipse on the sky (``cistrack predict DIR --site CODE ...``, docs/sky-predictions.md).

For each time the orbit (state and covariance at its epoch) is propagated with the dynamics it was
fitted with: the state by the dynamics, the covariance by the unscented transform (the fit state
and 12 sigma points through the nonlinear dynamics, :mod:`cistrack.least_squares.unscented_prediction`;
linearly where a sigma-point orbit hit a body). The ``real-telescope`` sensor at the site gives the
topocentric astrometric ICRF RA/Dec (light time, no aberration: as MPC and ADES report them) and
the range; its azel twin the elevation (apparent, no refraction). The sky-plane covariance of
(RA cos(Dec), Dec) is the state covariance mapped by the measurement's Jacobian (central
differences); its ellipse: 1-sigma semi-axes (arcsec) and the position angle of the major axis
(degrees from North through East); 3-sigma is three times those (the 2-D 3-sigma region holds
98.9 % of a Gaussian). Rates are central differences over +-30 s (within 30 s before an impact,
where the orbit ends, one-sided differences of the same order over the 60 s before); solar
elongation and lunar
distance are the angles from the site between the target and the Sun's and the Moon's centres
(DE421), degrees.

Needs dynamics in the real Earth-Moon frame (``ephemeris``): a CR3BP orbit has no place on the
real sky.
"""
from __future__ import annotations

import csv
import math
from dataclasses import dataclass
from typing import Any
from datetime import datetime, timezone
from pathlib import Path

import numpy as np

from cistrack import units
from cistrack.astro.ephemeris import DE421_YEARS
from cistrack.astro.sites import Site
from cistrack.errors import ConfigError, PropagationError, StateError
from cistrack.interfaces.dynamics import Dynamics
from cistrack.least_squares.trajectory import arc_states, arc_states_and_stms, ensemble_arc_states
from cistrack.least_squares.unscented_prediction import unscented_covariances
from cistrack.plugin.registry import Registry, default_registry

__all__ = ["SkyEphemeris", "sky_ephemeris", "sky_ephemeris_of", "predicted_orbit", "DirectoryOrbit", "orbit_of_directory", "CSV_COLUMNS",
           "RATE_SECONDS", "FIRST_YEAR", "LAST_YEAR"]

FIRST_YEAR, LAST_YEAR = DE421_YEARS
"""The whole years of the DE421 ephemeris (prediction times must lie within them)."""
RATE_SECONDS = 30.0
"""Half-width of the central differences of the rates, seconds."""
CSV_COLUMNS = ("utc", "ra_deg", "dec_deg", "ra_rate_arcsec_min", "dec_rate_arcsec_min", "range_km", "elevation_deg",
               "solar_elongation_deg", "lunar_distance_deg", "sigma_ra_arcsec", "sigma_dec_arcsec",
               "semi_major_1sigma_arcsec", "semi_minor_1sigma_arcsec", "position_angle_deg",
               "semi_major_3sigma_arcsec", "semi_minor_3sigma_arcsec", "linear_covariance", "line_reach_arcsec",
               "beyond_checked_horizon")
_ARCSEC = 180.0 * 3600.0 / math.pi


@dataclass(frozen=True)
class SkyEphemeris:
    """Sky predictions at K times (arrays (K,) unless said): see the module docstring.

    ``ra_rate`` is the rate of RA cos(Dec); ``covariance_arcsec2`` (K, 2, 2) is that of
    (RA cos(Dec), Dec); ``linear`` marks the times whose state covariance is the linear one;
    ``line_reach_arcsec`` (K,) is how far from the predicted position the orbits along the fit's
    bent line of variations lie (0 when it was not used: :func:`sky_ephemeris_of`);
    ``beyond_checked_horizon`` (K,) bool marks the times farther from a fit's arc than its orbits
    and covariance were checked for (:func:`cistrack.fitting.fit_export.beyond_checked_horizon`),
    None when not known (an orbit that is no fit's): the CSV column is then empty."""

    utc: list[str]
    t_tu: np.ndarray
    ra_deg: np.ndarray
    dec_deg: np.ndarray
    ra_rate_arcsec_min: np.ndarray
    dec_rate_arcsec_min: np.ndarray
    range_km: np.ndarray
    elevation_deg: np.ndarray
    solar_elongation_deg: np.ndarray
    lunar_distance_deg: np.ndarray
    covariance_arcsec2: np.ndarray
    linear: np.ndarray
    site: Site
    line_reach_arcsec: np.ndarray | None = None
    beyond_checked_horizon: np.ndarray | None = None

    def ellipse(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """1-sigma semi-major and semi-minor axes (K,) arcsec and the major axis' position angle
        (K,) degrees, North through East, in [0, 180)."""
        w, v = np.linalg.eigh(self.covariance_arcsec2)
        major = v[:, :, 1]                                           # (east, north) components
        pa = np.degrees(np.arctan2(major[:, 0], major[:, 1])) % 180.0
        return np.sqrt(np.clip(w[:, 1], 0, None)), np.sqrt(np.clip(w[:, 0], 0, None)), pa

    def mahalanobis2(self, ra_deg, dec_deg) -> np.ndarray:
        """Squared Mahalanobis distance (K,) of positions ``ra_deg``, ``dec_deg`` (K,) from the
        predicted ones under the sky covariance (inside the 3-sigma ellipse: <= 9; the 98.9 %
        region of a 2-D Gaussian is <= 11.83)."""
        dra = (np.asarray(ra_deg) - self.ra_deg + 180.0) % 360.0 - 180.0
        d = np.stack([dra * np.cos(np.radians(self.dec_deg)), np.asarray(dec_deg) - self.dec_deg], 1) * 3600.0
        return np.einsum("ki,kij,kj->k", d, np.linalg.inv(self.covariance_arcsec2), d)

    def rows(self) -> list[dict]:
        """One dict per time with :data:`CSV_COLUMNS`."""
        a, b, pa = self.ellipse()
        sig = np.sqrt(np.diagonal(self.covariance_arcsec2, axis1=1, axis2=2))
        cols = (self.ra_deg, self.dec_deg, self.ra_rate_arcsec_min, self.dec_rate_arcsec_min, self.range_km,
                self.elevation_deg, self.solar_elongation_deg, self.lunar_distance_deg, sig[:, 0], sig[:, 1], a, b, pa,
                3 * a, 3 * b)
        reach = np.zeros(len(self.utc)) if self.line_reach_arcsec is None else self.line_reach_arcsec
        beyond = [""] * len(self.utc) if self.beyond_checked_horizon is None else \
            [bool(b) for b in self.beyond_checked_horizon]
        return [dict(zip(CSV_COLUMNS, [self.utc[k]] + [float(c[k]) for c in cols]
                         + [bool(self.linear[k]), float(reach[k]), beyond[k]])) for k in range(len(self.utc))]

    def write_csv(self, path: str | Path) -> Path:
        """Write :meth:`rows` to ``path`` (CSV with a header of :data:`CSV_COLUMNS`); ConfigError, nothing
        written, when a number of them is NaN or infinite
        (:func:`cistrack.fitting.fit_export.refuse_non_finite`)."""
        from cistrack.fitting.fit_export import refuse_non_finite

        rows = self.rows()
        refuse_non_finite(np.array([[v for v in r.values() if isinstance(v, float)] for r in rows]), self.utc,
                          "the sky predictions")
        p = Path(path)
        with p.open("w", newline="") as fh:
            w = csv.DictWriter(fh, fieldnames=CSV_COLUMNS)
            w.writeheader()
            for row in rows:
                w.writerow({k: (f"{v:.9g}" if isinstance(v, float) else v) for k, v in row.items()})
        return p


def predicted_orbit(dynamics: Dynamics, state: np.ndarray, covariance: np.ndarray, t0: float,
                    times: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """States (K, 6), covariances (K, 6, 6) [LU, VU] at ``times`` (K,) TU, and (K,) bool where the
    covariance is linear (Phi P Phi^T) because the unscented one could not be made."""
    states, stms = arc_states_and_stms(dynamics, state, t0, times)
    cov = np.einsum("kij,jl,kml->kim", stms, covariance, stms)
    linear = np.ones(times.size, dtype=bool)
    try:
        sigma, ok = unscented_covariances(dynamics, state, covariance, t0, times)
        cov[ok], linear = sigma[ok], ~ok
    except StateError:
        pass
    return states, 0.5 * (cov + np.transpose(cov, (0, 2, 1))), linear


def _orbit_at(dynamics: Dynamics, state: np.ndarray, covariance: np.ndarray, t0: float, tt: np.ndarray,
              fit: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`predicted_orbit`, or with a ``fit`` that estimated parameters its states and the joint
    covariances."""
    from cistrack.least_squares.area_to_mass import joint_covariances

    joint = joint_covariances(dynamics, fit, tt) if fit is not None else None
    if joint is None:
        return predicted_orbit(dynamics, state, covariance, t0, tt)
    return arc_states(dynamics, state, t0, tt), joint[0], joint[1]


def _sensors(site: Site, epoch: datetime, registry: Registry):
    common = {"latitude_deg": site.latitude_deg, "longitude_deg": site.longitude_deg, "height_m": site.height_m,
              "epoch": units.format_utc(epoch), "elevation_mask_deg": -90.0}
    return (registry.create("sensor", "real-telescope", measurement="radec", measure_range=True, **common),
            registry.create("sensor", "real-telescope", measurement="azel", **common))


def _sky_jacobian(radec, states: np.ndarray, times: np.ndarray, dec: np.ndarray) -> np.ndarray:
    """d(RA cos(Dec), Dec)/d(state) (K, 2, 6) rad per LU/VU, central differences."""
    h = np.r_[[1e-8] * 3, [1e-7] * 3]
    pts = np.concatenate([states[:, None, :] + np.diag(h)[None], states[:, None, :] - np.diag(h)[None]], 1)
    z = radec.measure(pts.reshape(-1, 6), np.repeat(times, 12))[:, :2].reshape(-1, 12, 2)
    d = z[:, :6] - z[:, 6:]
    d[:, :, 0] = (d[:, :, 0] + math.pi) % (2 * math.pi) - math.pi
    d[:, :, 0] *= np.cos(dec)[:, None]
    return np.transpose(d / (2 * h)[None, :, None], (0, 2, 1))


def _rates(dynamics, radec, state, t0, times, dec) -> tuple[np.ndarray, np.ndarray]:
    """(RA cos(Dec), Dec) rates (K,) each, arcsec/min: central differences over +-h
    (:data:`RATE_SECONDS`), and at a time whose central stencil would cross an impact (h or less
    before it) the one-sided difference of the same order, (3 z(t) - 4 z(t-h) + z(t-2h)) / 2h."""
    h = float(units.seconds_to_tu(RATE_SECONDS))
    s = _rate_sides(dynamics, state, t0, times, h)                  # 0 central, -1 backward, +1 forward
    a = np.where(s == 0, times - h, times + s * h)
    b = np.where(s == 0, times + h, times + 2 * s * h)
    at = np.concatenate([times, a, b])
    z = radec.measure(arc_states(dynamics, state, t0, at), at)[:, :2].reshape(3, times.size, 2)
    da, db = z[1] - z[0], z[2] - z[0]
    da[:, 0], db[:, 0] = _wrapped(da[:, 0]), _wrapped(db[:, 0])
    diff = np.where((s == 0)[:, None], db - da, s[:, None] * (4 * da - db))   # both: 2h times the rate
    scale = _ARCSEC * 60.0 / (2 * RATE_SECONDS)
    return diff[:, 0] * np.cos(dec) * scale, diff[:, 1] * scale


def _wrapped(angle: np.ndarray) -> np.ndarray:
    """An angle difference (rad) wrapped into [-pi, pi)."""
    return (angle + math.pi) % (2 * math.pi) - math.pi


def _rate_sides(dynamics, state: np.ndarray, t0: float, times: np.ndarray, h: float) -> np.ndarray:
    """Which difference gives the rates at ``times`` (K,): -1 (backward) where t + h reaches an
    impact after ``t0``, +1 (forward) where t - h reaches one before it (an orbit propagated back
    into the body it left), 0 (central) elsewhere."""
    from cistrack.least_squares.events import first_impact

    side = np.zeros(times.size)
    margin = float(units.seconds_to_tu(1.0))
    late, early = float(times.max()) + h, float(times.min()) - h
    hit = first_impact(dynamics, state, t0, late) if late > t0 else None
    if hit is not None:
        side[times + h > hit[0] - margin] = -1.0
    hit = first_impact(dynamics, state, t0, early) if early < t0 else None
    if hit is not None:
        side[times - h < hit[0] + margin] = 1.0
    return side


def _angles_to_sun_and_moon(site: Site, epoch: datetime, times: np.ndarray, ra: np.ndarray,
                            dec: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Angles (K,) degrees from the target's direction to the Sun's and the Moon's seen from the site."""
    from cistrack.astro.earth_moon import EarthMoonFrame
    from cistrack.astro.ephemeris import de421
    from cistrack.astro.observer import ObserverGeometry

    frame = EarthMoonFrame.from_utc(epoch)
    jd = (np.full(times.size, frame.epoch_tdb[0]), frame.epoch_tdb[1] + frame.tdb_days(times))
    obs = ObserverGeometry(site, epoch).state(times * units.TU_S).position_km
    u = np.stack([np.cos(dec) * np.cos(ra), np.cos(dec) * np.sin(ra), np.sin(dec)], 1)
    out = []
    for body in (de421().sun(*jd)[0], de421().moon(*jd)[0]):
        b = body - obs
        cosang = np.sum(u * b, 1) / np.linalg.norm(b, axis=1)
        out.append(np.degrees(np.arccos(np.clip(cosang, -1.0, 1.0))))
    return out[0], out[1]


def _checked(dynamics: Dynamics, times, epoch: datetime | str) -> np.ndarray:
    """``times`` as a (K,) float array; StateError naming ``times`` unless they are finite and
    within the years of the DE421 ephemeris (``epoch``: the UTC of t = 0); ConfigError for dynamics
    with no place on the real sky."""
    if getattr(dynamics, "frame", None) is None:
        raise ConfigError(f"sky predictions need dynamics in the real Earth-Moon frame ('ephemeris'); these are "
                          f"'{getattr(dynamics, 'name', type(dynamics).__name__)}', whose orbit has no place on the real sky")
    try:
        tt = np.atleast_1d(np.asarray(times, dtype=float)).reshape(-1)
    except (TypeError, ValueError):
        raise StateError(f"sky predictions: times must be one or more finite numbers (TU since the scenario's "
                         f"epoch), got {str(times)[:60]}") from None
    if tt.size == 0 or not np.all(np.isfinite(tt)):
        raise StateError("sky predictions: times must be one or more finite numbers (TU)")
    when = units.parse_utc(epoch)
    first, last = (float(units.seconds_to_tu(units.elapsed_seconds(when, datetime(y, 1, 1, tzinfo=timezone.utc))))
                   for y in (FIRST_YEAR, LAST_YEAR + 1))
    outside = tt[(tt < first) | (tt >= last)]
    if outside.size:
        raise StateError(f"sky predictions: times: {outside[0]:.6g} TU (since {units.format_utc(when)[:19]}Z) is "
                         f"outside the years {FIRST_YEAR} to {LAST_YEAR} of the DE421 ephemeris the sky positions "
                         f"need; give times from {first:.6g} to {last:.6g} TU")
    return tt


def sky_ephemeris(dynamics: Dynamics, state: np.ndarray, covariance: np.ndarray, t0: float, times,
                  site: Site, epoch: datetime | str, registry: Registry | None = None) -> SkyEphemeris:
    """Sky predictions (see the module docstring) of the orbit ``state`` (6,) and ``covariance``
    (6, 6) [LU, VU] at ``t0`` (TU) at ``times`` (K,) TU from ``site``; ``epoch``: the UTC of t = 0
    (the dynamics' and scenario's)."""
    tt = _checked(dynamics, times, epoch)
    x = np.asarray(state, float)
    return _sky(dynamics, (x, t0), predicted_orbit(dynamics, x, np.asarray(covariance, float), t0, tt), tt, site,
                epoch, registry)


def sky_ephemeris_of(orbit: "DirectoryOrbit", times, site: Site, registry: Registry | None = None) -> SkyEphemeris:
    """:func:`sky_ephemeris` of a results directory's orbit (:func:`orbit_of_directory`). When the
    orbit's fit estimated solve-for parameters (the area-to-mass ratio) the state covariances are
    carried from the joint covariance of state and parameters
    (:func:`cistrack.least_squares.area_to_mass.joint_covariances`), so that the parameters'
    uncertainty widens the ellipses away from the fit epoch, as in the export."""
    tt = _checked(orbit.dynamics, times, orbit.epoch)
    x = np.asarray(orbit.state, float)
    predicted = _orbit_at(orbit.dynamics, x, np.asarray(orbit.covariance, float), orbit.t0, tt, orbit.fit)
    sky = _sky(orbit.dynamics, (x, orbit.t0), predicted, tt, site, orbit.epoch, registry)
    return sky if orbit.line is None else _holding_line(sky, orbit, tt, registry)


def _holding_line(sky: SkyEphemeris, orbit: "DirectoryOrbit", tt: np.ndarray, registry: Registry | None) -> SkyEphemeris:
    """``sky`` with each time's covariance widened along the sky offsets d of the orbits of
    ``orbit.line`` (C + s M, M their mean d d^T, s the least that puts every d within the 3-sigma
    ellipse) and their farthest offset as ``line_reach_arcsec``. A line orbit that cannot be
    propagated over the times (it hits a body) is left out."""
    from dataclasses import replace

    from cistrack.least_squares.line_of_variations import widened_to_hold

    radec, _ = _sensors(sky.site, units.parse_utc(orbit.epoch), registry or default_registry())
    try:
        states, alive = ensemble_arc_states(orbit.dynamics, orbit.line, orbit.t0, tt)   # (K, M, 6), (M,)
    except (PropagationError, StateError):
        return sky
    if not np.any(alive):
        return sky
    k, m = tt.size, int(np.sum(alive))
    z = radec.measure(states[:, alive].reshape(k * m, 6), np.repeat(tt, m)).reshape(k, m, -1)
    ra, dec = np.radians(sky.ra_deg)[:, None], np.radians(sky.dec_deg)[:, None]
    d = np.stack([_wrapped(z[:, :, 0] - ra) * np.cos(dec), z[:, :, 1] - dec], 2) * _ARCSEC   # (K, M, 2) arcsec
    try:
        cov = np.array([widened_to_hold(c, dk) for c, dk in zip(sky.covariance_arcsec2, d)])
    except np.linalg.LinAlgError:
        return sky
    return replace(sky, covariance_arcsec2=cov, line_reach_arcsec=np.max(np.linalg.norm(d, axis=2), axis=1))


def _sky(dynamics: Dynamics, start: tuple, predicted: tuple, tt: np.ndarray, site: Site, epoch: datetime | str,
         registry: Registry | None) -> SkyEphemeris:
    """The sky predictions of the orbit ``start`` = (state (6,), t0) whose states, covariances and
    linear flags at ``tt`` are ``predicted``."""
    state, t0 = start
    states, covs, linear = predicted
    when = units.parse_utc(epoch)
    radec, azel = _sensors(site, when, registry or default_registry())
    z = radec.measure(states, tt)
    ra, dec = z[:, 0], z[:, 1]
    jac = _sky_jacobian(radec, states, tt, dec)
    sky = np.einsum("kij,kjl,kml->kim", jac, covs, jac) * _ARCSEC ** 2
    ra_rate, dec_rate = _rates(dynamics, radec, np.asarray(state, float), t0, tt, dec)
    sun, moon = _angles_to_sun_and_moon(site, when, tt, ra, dec)
    utc = [units.format_utc(units.tu_to_utc(when, float(t)))[:19] + "Z" for t in tt]
    return SkyEphemeris(utc, tt, np.degrees(ra), np.degrees(dec), ra_rate, dec_rate, z[:, 2] * units.LU_KM,
                        np.degrees(azel.measure(states, tt)[:, 1]), sun, moon, 0.5 * (sky + np.transpose(sky, (0, 2, 1))),
                        linear, site)


@dataclass(frozen=True)
class DirectoryOrbit:
    """The orbit a results directory holds: ``state`` (6,) and ``covariance`` (6, 6) [LU, VU] at
    ``t0`` (TU since ``epoch``, a UTC datetime), the ``dynamics`` it was made with, its ``name``
    and ``source`` (what the state is: the least-squares fit or the filter's last estimate)."""

    state: np.ndarray
    covariance: np.ndarray
    t0: float
    epoch: datetime
    dynamics: Dynamics
    name: str
    source: str
    fit: Any = None
    """The fit record as a FitResult when the fit estimated solve-for parameters (for
    :func:`sky_ephemeris`'s ``fit``), else None."""
    line: np.ndarray | None = None
    """States (M, 6) [LU, VU] at ``t0`` of the fit's line of variations within 3 sigma (chi-square
    within 9 of its lowest, times the noise scale squared when above 1) when the line bends away
    from the covariance, else None: :func:`sky_ephemeris_of` widens the ellipses to hold them."""


def orbit_of_directory(directory: str | Path, registry: Registry | None = None) -> DirectoryOrbit:
    """The orbit of a ``cistrack fit`` directory (``fit.json``: the least-squares state and its
    covariance as exported, times the noise scale squared when above 1, and the dynamics with the
    area-to-mass ratio it estimated, if it did) or of a ``cistrack run``
    directory (the filter's estimate at its last step, when the run finished without diverging:
    what `cistrack export` exports); ConfigError naming the directory otherwise."""
    from cistrack.fitting.fit_export import _result as fit_result
    from cistrack.fitting.fit_export import check_scenario_epoch, covariance_scale, fit_refusal, is_fit_directory, line_states
    from cistrack.fitting.fit_record import read_fit_record
    from cistrack.results.dir_lock import check_no_writer
    from cistrack.runs.export import scenario_of

    d = Path(directory)
    if not d.is_dir():
        raise ConfigError(f"{d}: no such directory; give the --out directory of 'cistrack fit' or 'cistrack run'")
    check_no_writer(d, "prediction")
    reg = registry or default_registry()
    rec = read_fit_record(d) if is_fit_directory(d) else None
    why = fit_refusal(rec) if rec is not None else None
    if why is not None:  # said before anything else: a failed fit may have no scenario.toml
        raise ConfigError(f"{d}: no orbit to predict from: {why}")
    scen = scenario_of(d, reg)
    dyn = scen.build("dynamics", reg)
    if rec is not None:
        check_scenario_epoch(d, rec, scen)
        cov = np.asarray(rec["covariance"], dtype=float) * covariance_scale(rec)
        amr = rec.get("area_to_mass")
        fit = None
        if isinstance(amr, dict) and amr.get("estimated"):                # predict with the fitted C_R A/m
            dyn = dyn.with_parameters(area_to_mass_m2_kg=float(amr["value_m2_kg"]))
            fit = fit_result(rec)                                         # and its uncertainty
        return DirectoryOrbit(np.asarray(rec["state"], dtype=float), cov, float(rec["epoch_tu"]), scen.epoch, dyn,
                              str(rec.get("designation") or scen.name), "least-squares fit", fit,
                              line_states(d, rec))
    return _run_orbit(d, scen, dyn)


def _run_orbit(d: Path, scen, dyn) -> DirectoryOrbit:
    from cistrack.results.estimates import KM_SCALE, usable_estimates
    from cistrack.runs.export import export_refusal

    why = export_refusal(d)  # the rule 'cistrack export' follows: no orbit from a run that did not finish
    if why is not None:
        raise ConfigError(f"{d}: no orbit to predict from: {why}")

    try:
        est = usable_estimates(d)
    except FileNotFoundError:
        raise ConfigError(f"{d}: neither fit.json nor estimates.parquet; give the --out directory of 'cistrack fit' "
                          "or 'cistrack run'") from None
    mean = np.asarray(est.mean_km[-1], dtype=float) / KM_SCALE
    cov = np.asarray(est.covariance_km[-1], dtype=float) / np.multiply.outer(KM_SCALE, KM_SCALE)
    return DirectoryOrbit(mean, cov, float(est.t_tu[-1]), scen.epoch, dyn, scen.name,
                          f"filter estimate at step {int(est.step[-1])}")
