"""How well a fit determines the orbit, in words.

From the fit (its covariance times the noise scale squared when that exceeds 1, as the export
does), the observations it used and the dynamics:

- **sessions, days and sites**: observing sessions are runs of observations without a gap of
  :data:`SESSION_GAP_HOURS` (3 h, the IOD's night); the arc's length in days; the observatories;
- **range and its sigma**: at the observation nearest the fit epoch, the line of sight is the
  direction the two angles do not see (the cross product of the position rows of their Jacobian)
  and the range is 1 / (the smaller row norm) (a declination or elevation row has norm 1 / range);
  the range's 1-sigma is sqrt(u^T P u) with u the line of sight and P the position covariance;
- **reacquisition horizon**: :data:`N_DRAWS` orbits drawn from the covariance (a seeded
  generator) are propagated every :data:`HORIZON_STEP_DAYS` after the last observation, out to
  :data:`HORIZON_DAYS`; the horizon is the last time at which no more than :data:`LOST_SHARE`
  (1 %) of them lie more than :data:`FIELD_RADIUS_DEG` (0.5 degree: a 1-degree field, a small
  telescope with a CMOS camera) from the fitted orbit's direction seen from the Earth's centre,
  or have hit a body. After it a telescope pointed at the prediction may miss the object:
  "observe again within N days". Where the fit's line of variations bends away from its
  covariance, the orbits are drawn along the line instead. Drawn orbits, not a propagated covariance: from one night of the
  9:2 NRHO (one site), 24 % of 2,000 such orbits hit the Moon at the next perilune, 1.8 days on,
  which the unscented covariance (its 13 sigma-point orbits miss the Moon) does not show: its
  3-sigma stays under 0.5 degree for 13 days.

- **covariance horizon**: the same drawn orbits against the fit's covariance carried to each
  step as an export carries it (unscented, :func:`cistrack.least_squares.prediction.predict_orbit`):
  it holds them while at most :data:`COVARIANCE_TAIL_SHARE` of them lie outside its 99 % ellipsoid
  (chi-square 16.81 of 6 dof; 1 % when it holds). Where the flow bends across the covariance, its
  tails no longer hold what the arc allows though its core does: from one night of a DRO (one site,
  5.7 hours) the share passed 2 % 0.75 days after the last observation, 3.4 % by 1.25 days, and the
  truth went from Mahalanobis^2 11 to 47 inside the 1.5-day reacquisition horizon. Exports warn
  past it. Not measured (None) when the orbits are drawn along the line of variations.

The fit is **poorly determined** when the horizon is under :data:`POOR_HORIZON_DAYS` (2 days:
the object must be found again within a night or two), when the range's 1-sigma exceeds
:data:`POOR_RANGE_FRACTION` of the range (1e-4: 38 km at the Moon's distance; the transverse
velocity taken from the angular rate then errs by as large a share of itself, 0.1 m/s at 1 km/s,
about 9 km of drift a day), or when the fit itself flagged a direction as nearly unobservable;
otherwise **well determined**. The range is called unconstrained above
:data:`UNCONSTRAINED_RANGE_FRACTION` (1e-2). Measured on simulated 9:2 NRHO campaigns (1.0
arcsec): one night from one site gives 390 km (1e-3); two weeks from three sites 0.8 km (2e-6).

One **lone tracklet** (RA/Dec of one site within :data:`LONE_TRACKLET_HOURS`) determines no orbit
at all: :func:`is_lone_tracklet` says so, :func:`sky_motion` gives its place and rates on the sky
and :func:`lone_tracklet_report` the words ``cistrack fit`` prints instead of a fit.
"""
from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from cistrack import units
from cistrack.fitting.residual_ladder import fitted_dynamics
from cistrack.least_squares.measurement_model import MeasurementModel
from cistrack.least_squares.observability import condition_text
from cistrack.least_squares.result import sigma_factor
from cistrack.least_squares.trajectory import arc_states_and_stms
from cistrack.model.measurement import MeasurementSet

__all__ = ["Determination", "determination", "SESSION_GAP_HOURS", "FIELD_RADIUS_DEG", "HORIZON_DAYS",
           "HORIZON_STEP_DAYS", "N_DRAWS", "LOST_SHARE", "POOR_HORIZON_DAYS", "POOR_RANGE_FRACTION",
           "UNCONSTRAINED_RANGE_FRACTION", "DRAW_SEED", "COVARIANCE_TAIL_SHARE", "LONE_TRACKLET_HOURS", "is_lone_tracklet", "sky_motion",
           "lone_tracklet_report"]

SESSION_GAP_HOURS = 3.0
FIELD_RADIUS_DEG = 0.5
HORIZON_DAYS = 30.0
HORIZON_STEP_DAYS = 0.25
N_DRAWS = 1000
LOST_SHARE = 0.01
DRAW_SEED = 4900
COVARIANCE_TAIL_SHARE = 0.02
"""The carried covariance holds the drawn orbits while at most this share of them lie outside its
99 % ellipsoid: 1 % when it holds, 2 % three standard errors of :data:`N_DRAWS` draws above it."""
TAIL_CHI2 = 16.81
"""The 99 % quantile of chi-square with 6 degrees of freedom."""
"""Seed of the generator that draws the orbits when none is given (same fit, same words)."""
POOR_HORIZON_DAYS = 2.0
POOR_RANGE_FRACTION = 1e-4
UNCONSTRAINED_RANGE_FRACTION = 1e-2


@dataclass(frozen=True)
class Determination:
    """How well a fit is determined.

    well : bool                 True: "well determined"; False: "poorly determined"
    sentence : str              the verdict and its reasons in one line
    sessions, sites : int       observing sessions (3-hour gaps) and observatories used
    arc_days : float            first to last used observation, days
    range_km, range_sigma_km : float   range at the fit epoch's observation and its 1-sigma, km
    horizon_days : float        days after the last observation that 99 % of the orbits the fit
                                allows stay within the field (HORIZON_DAYS or more: inf)
    horizon_note : str          "" when the field decides; else that drawn orbits, or the fitted
                                one, hit a body
    condition_number : float    the fit's
    covariance_horizon_days : float   days after the last observation that the carried covariance
                                holds the drawn orbits (inf: throughout the horizon's grid; nan: not
                                measured, orbits drawn along the line of variations)
    """

    well: bool
    sentence: str
    sessions: int
    sites: int
    arc_days: float
    range_km: float
    range_sigma_km: float
    horizon_days: float
    horizon_note: str
    condition_number: float
    covariance_horizon_days: float = float("nan")

    def as_dict(self) -> dict:
        """For ``fit.json`` (its ``determination`` key): numbers, inf and nan as None."""
        out = {k: getattr(self, k) for k in self.__dataclass_fields__}
        return {k: (None if isinstance(v, float) and not np.isfinite(v) else v) for k, v in out.items()}


def _scaled(fit):
    s = sigma_factor(fit.noise_scale)
    return replace(fit, covariance=fit.covariance * s * s) if s > 1.0 else fit


def _sessions(times: np.ndarray) -> int:
    return int(np.sum(np.diff(times) > units.hours_to_tu(SESSION_GAP_HOURS))) + 1


def _range_and_sigma(fit, dynamics, sensor, used: MeasurementSet) -> tuple[float, float]:
    """(range km, its 1-sigma km) at the used observation nearest the fit epoch."""
    i = int(np.argmin(np.abs(used.times - fit.epoch)))
    one = used.subset(np.array([i]))
    state, phi = arc_states_and_stms(dynamics, fit.state, fit.epoch, one.times)
    h = MeasurementModel(sensor, one).jacobian(state)[0][:, :3]        # (m, 3) rad / LU
    u = np.cross(h[0], h[1])
    u = u / np.linalg.norm(u)
    rng = 1.0 / float(np.min(np.linalg.norm(h, axis=1)))
    p = (phi[0] @ fit.covariance @ phi[0].T)[:3, :3]
    return rng * units.LU_KM, float(np.sqrt(max(u @ p @ u, 0.0))) * units.LU_KM


def _bodies_hit(dynamics, prop, k: int, grid: np.ndarray) -> str:
    """Names of the bodies that drawn orbits hit by ``grid[k]``."""
    hit = prop.impact_time <= grid[k]
    idx = sorted(set(prop.impact_body[hit].tolist()))
    return " and the ".join(dynamics.bodies[b].name if 0 <= b < len(dynamics.bodies) else f"body {b}" for b in idx)


def _drawn(fit, rng: np.random.Generator, line: tuple | None) -> np.ndarray:
    """N_DRAWS orbits (N, 6): from the covariance, or along the ``line`` (points, weakest direction)."""
    if line is None:
        return rng.multivariate_normal(fit.state, fit.covariance, size=N_DRAWS, method="eigh")
    from cistrack.least_squares.line_of_variations import sample_line

    points, direction = line
    return sample_line(points, N_DRAWS, rng, float(points[1].sigma - points[0].sigma), direction)


def _outside(fit, dynamics, grid: np.ndarray, rng: np.random.Generator, line: tuple | None = None):
    """(share of drawn orbits outside the field or hit (K,), share hit (K,), propagation)."""
    draws = _drawn(fit, rng, line)
    prop = dynamics.propagate(np.vstack([fit.state[None], draws]), fit.epoch, grid)
    earth = np.array([dynamics.primary("Earth").position_at(t) for t in grid])        # (K, 3)
    rel = prop.states[:, :, :3] - earth[:, None, :]                                    # (K, 1 + N, 3)
    u = rel / np.linalg.norm(rel, axis=2, keepdims=True)
    cos = np.clip(np.einsum("kni,ki->kn", u[:, 1:], u[:, 0]), -1.0, 1.0)
    hit = prop.impact_time[None, 1:] <= grid[:, None]
    out = hit | (np.arccos(cos) > np.radians(FIELD_RADIUS_DEG))
    return out.mean(axis=1), hit.mean(axis=1), prop


def _horizon_grid(fit, t_last: float) -> np.ndarray:
    """The horizon's times (TU): every HORIZON_STEP_DAYS after ``t_last`` out to HORIZON_DAYS, after the fit epoch."""
    step = float(units.days_to_tu(HORIZON_STEP_DAYS))
    grid = t_last + step * np.arange(1, int(round(HORIZON_DAYS / HORIZON_STEP_DAYS)) + 1)
    return grid[grid > fit.epoch]


def _steps_before(grid: np.ndarray, k: int, t_last: float) -> float:
    """Days from ``t_last`` to the step before ``grid[k]``, a whole number of steps (not 5e-16)."""
    days = float(units.tu_to_days(grid[k] - t_last)) - HORIZON_STEP_DAYS
    return max(round(days / HORIZON_STEP_DAYS) * HORIZON_STEP_DAYS, 0.0)


def _horizon(fit, dynamics, t_last: float, grid: np.ndarray, drawn: tuple) -> tuple[float, str]:
    """(days after ``t_last`` that at least 1 - LOST_SHARE of the drawn orbits stay within the
    field, note); ``drawn`` is :func:`_outside` on ``grid``, which starts at ``t_last`` and ends at
    HORIZON_DAYS or where the fitted orbit hits a body."""
    share, hit, prop = drawn
    gone = np.nonzero(share > LOST_SHARE)[0]
    nominal = prop.impact_time[0]
    if gone.size and grid[gone[0]] <= nominal:
        k = gone[0]
        days = _steps_before(grid, k, t_last)
        if hit[k] > 0.5 * share[k]:
            return days, f"orbits within the covariance hit the {_bodies_hit(dynamics, prop, k, grid)}"
        return days, ""
    if np.isfinite(nominal):
        b = int(prop.impact_body[0])
        name = dynamics.bodies[b].name if 0 <= b < len(dynamics.bodies) else f"body {b}"
        days = float(units.tu_to_days(nominal - t_last))
        return days, f"the fitted orbit hits the {name} {days:.3g} days after the last observation"
    return float("inf"), ""


def _covariance_horizon(fit, dynamics, t_last: float, grid: np.ndarray, prop) -> float:
    """Days after ``t_last`` that the fit's covariance carried to ``grid`` (unscented) holds the drawn
    orbits of ``prop`` (its first orbit the fitted one): at most COVARIANCE_TAIL_SHARE of them (those
    that hit a body among them) outside its 99 % ellipsoid; inf when it holds at every step before
    the fitted orbit hits a body, nan when it cannot be carried."""
    from cistrack.errors import PropagationError
    from cistrack.least_squares.prediction import predict_orbit

    alive = grid < prop.impact_time[0]
    if not alive.any():
        return float("nan")
    try:
        p = predict_orbit(fit, dynamics, grid[alive])
        e = prop.states[:, 1:][alive] - p.states[:, None, :]                      # (K, N, 6)
        m2 = np.einsum("kni,kni->kn", e, np.linalg.solve(p.covariances, np.transpose(e, (0, 2, 1))).transpose(0, 2, 1))
    except (PropagationError, np.linalg.LinAlgError):
        return float("nan")
    hit = prop.impact_time[None, 1:] <= grid[alive][:, None]
    share = np.mean(hit | ~(m2 <= TAIL_CHI2), axis=1)
    bad = np.nonzero(share > COVARIANCE_TAIL_SHARE)[0]
    return _steps_before(grid[alive], int(bad[0]), t_last) if bad.size else float("inf")


def _count(n: int, one: str, many: str) -> str:
    return f"{'one' if n == 1 else n} {one if n == 1 else many}"


def _coverage(sessions: int, sites: int, arc_days: float) -> str:
    span = f"{arc_days * 24:.3g} h" if arc_days < 1 else f"{arc_days:.3g} days"
    what = _count(sessions, "night", "sessions")
    return f"{what} ({span}) from {_count(sites, 'site', 'sites')}"


def _range_words(rng_km: float, sigma_km: float) -> str:
    frac = sigma_km / rng_km
    share = f"1-sigma {sigma_km:.3g} km along the line of sight, {100 * frac:.2g} % of the range"
    if frac > UNCONSTRAINED_RANGE_FRACTION:
        return f"the range is unconstrained ({share})"
    if frac > POOR_RANGE_FRACTION:
        return f"the range is weakly constrained ({share})"
    return f"range {share}"


def _horizon_words(days: float, note: str) -> str:
    field = f"{2 * FIELD_RADIUS_DEG:g}-degree field"
    if np.isinf(days):
        return f"the orbits it allows stay within a {field} for more than {HORIZON_DAYS:g} days"
    if note.startswith("the fitted orbit"):
        return f"the orbits it allows stay within a {field} until {note}"
    why = note or f"{100 * LOST_SHARE:g} % of the orbits it allows then leave a {field}"
    if days < 0.5 * HORIZON_STEP_DAYS:  # the first step of the grid already lost them
        return (f"the orbits it allows spread beyond a {field} within {24 * HORIZON_STEP_DAYS:g} hours of the last "
                f"observation ({why}): the arc does not say where to look")
    return f"observe again within {days:.2g} days ({why})"


def determination(fit, dynamics, sensor, measurements: MeasurementSet,
                  rng: np.random.Generator | None = None, line: list | None = None) -> Determination:
    """How well ``fit`` (a FitResult) determines the orbit (module docstring).

    ``measurements`` are the observations it was fitted to (times TU; its rejected rows, as the
    fit's residual table marks them, are left out), ``sensor`` predicts them (a site network for
    several sites), ``dynamics`` propagates the orbit (with the fit's solve-for parameters) and
    ``rng`` draws the orbits of the horizon
    (default: a generator seeded with :data:`DRAW_SEED`); with ``line``, the fit's line of
    variations (two or more :class:`~cistrack.least_squares.line_of_variations.LovPoint`, spaced
    evenly), they are drawn along it (:func:`~cistrack.least_squares.line_of_variations.sample_line`)
    instead of from the covariance: where the line bends, the covariance does not hold the orbits
    the arc allows.
    """
    from cistrack.least_squares.line_of_variations import weakest_direction

    along = (line, weakest_direction(fit.covariance)) if line is not None and len(line) > 1 else None
    fit = _scaled(fit)
    dynamics = fitted_dynamics(dynamics, fit)
    rng = np.random.default_rng(DRAW_SEED) if rng is None else rng
    used = measurements.subset(~np.asarray(fit.residuals.rejected, dtype=bool))
    sessions, sites = _sessions(used.times), len(used.site_keys())
    arc_days = float(units.tu_to_days(used.times[-1] - used.times[0]))
    rng_km, sigma = _range_and_sigma(fit, dynamics, sensor, used)
    days, note, cov_days = _horizons(fit, dynamics, float(used.times[-1]), rng, along)
    poor = (days < POOR_HORIZON_DAYS and not note.startswith("the fitted orbit")) \
        or sigma / rng_km > POOR_RANGE_FRACTION or bool(fit.unobservable)
    parts = [_coverage(sessions, sites, arc_days), _range_words(rng_km, sigma), _horizon_words(days, note)]
    if cov_days < days:
        parts.append(_covariance_words(cov_days))
    if fit.unobservable:
        parts.append(condition_text(fit.condition_number))
    sentence = ("poorly determined: " if poor else "well determined: ") + "; ".join(parts)
    return Determination(not poor, sentence, sessions, sites, arc_days, rng_km, sigma, days, note,
                         float(fit.condition_number), cov_days)


def _horizons(fit, dynamics, t_last: float, rng: np.random.Generator, along: tuple | None) -> tuple[float, str, float]:
    """(horizon days, its note, covariance horizon days) of one set of drawn orbits; the covariance
    horizon is nan for orbits drawn ``along`` the line of variations (the covariance is not their law)."""
    grid = _horizon_grid(fit, t_last)
    drawn = _outside(fit, dynamics, grid, rng, along)
    days, note = _horizon(fit, dynamics, t_last, grid, drawn)
    cov_days = float("nan") if along is not None else _covariance_horizon(fit, dynamics, t_last, grid, drawn[2])
    return days, note, cov_days


def _covariance_words(days: float) -> str:
    when = f"within {24 * HORIZON_STEP_DAYS:g} hours" if days < 0.5 * HORIZON_STEP_DAYS else f"after {days:.2g} days"
    return (f"its covariance carried forward understates their spread {when} (over {100 * COVARIANCE_TAIL_SHARE:g} % "
            "of them then lie outside its 99 % ellipsoid)")


LONE_TRACKLET_HOURS = 2.0
"""Angles of one site spanning at most this long (hours; the ranging IOD's longest tracklet) are one
tracklet: its two angles and their rates leave the range and the range rate free (the admissible
region), so no orbit is determined and ``cistrack fit`` makes none."""


def is_lone_tracklet(measurements: MeasurementSet) -> bool:
    """Whether ``measurements`` are one tracklet: angles of one site (RA/Dec or azimuth/elevation
    alike: either is two angles) spanning at most :data:`LONE_TRACKLET_HOURS` (two sites the same
    night see a parallax: not one tracklet)."""
    ms = measurements
    if len(ms) == 0 or len(set(ms.site_at(i) for i in range(len(ms)))) > 1:
        return False
    # a span of exactly LONE_TRACKLET_HOURS reads back from TU a few picoseconds longer: a millisecond of slack
    return float(units.tu_to_hours(float(ms.times[-1] - ms.times[0]))) <= LONE_TRACKLET_HOURS + 1e-3 / 3600.0


def sky_motion(measurements: MeasurementSet, epoch) -> dict:
    """The tracklet's place and motion on the sky: its first and last UTC, site, count and span,
    RA and Dec (deg) at its mean time and their rates (a straight line in time through the
    observations, RA unwrapped): RA x cos(Dec) and Dec in arcsec per minute, the total rate (arcsec
    per minute and deg per day) and its position angle (deg, east of north); the rates and the angle
    are None when every observation has the same time (no motion is measured). ``angles`` is
    ``"radec"``; an azimuth/elevation tracklet gives :func:`_local_sky` instead."""
    ms = measurements
    if any(ms.kind_at(i) == "azel" for i in range(len(ms))):
        return _local_sky(ms, epoch)
    t = np.asarray(ms.times, dtype=float)
    minutes = float(units.tu_to_hours(1.0)) * 60.0 * (t - t.mean())
    ra, dec = np.unwrap(ms.values[:, 0]), ms.values[:, 1]
    if len(ms) >= 2 and np.ptp(minutes) > 0:
        (ra_rate, ra0), (dec_rate, dec0) = np.polyfit(minutes, ra, 1), np.polyfit(minutes, dec, 1)
    else:
        ra_rate, ra0, dec_rate, dec0 = 0.0, float(ra.mean()), 0.0, float(dec.mean())
    east = float(ra_rate * np.cos(dec0)) / units.ARCSEC_RAD
    north = float(dec_rate) / units.ARCSEC_RAD
    total = float(np.hypot(east, north))
    utc = [units.format_utc(units.tu_to_utc(epoch, float(v))) for v in (t[0], t[-1])]
    moved = bool(np.ptp(minutes) > 0)  # one time: a place, no motion (the rates are None)
    return {"first_utc": utc[0], "last_utc": utc[1], "site": ms.site_at(0), "n_observations": int(len(ms)),
            "angles": "radec", "span_minutes": float(np.ptp(minutes)), "ra_deg": float(np.degrees(ra0) % 360.0),
            "dec_deg": float(np.degrees(dec0)), "ra_cos_dec_rate_arcsec_min": east if moved else None,
            "dec_rate_arcsec_min": north if moved else None, "rate_arcsec_min": total if moved else None,
            "rate_deg_day": total * 1440.0 / 3600.0 if moved else None,
            "position_angle_deg": float(np.degrees(np.arctan2(east, north)) % 360.0) if moved else None}


def _local_sky(ms: MeasurementSet, epoch) -> dict:
    """:func:`sky_motion`'s keys for an azimuth/elevation tracklet: ``angles`` ``"azel"``,
    ``azimuth_deg`` and ``elevation_deg`` (deg) at its mean time, and no RA/Dec or rates (None): the
    rates of azimuth and elevation mix the Earth's rotation with the object's own motion."""
    t = np.asarray(ms.times, dtype=float)
    az, el = np.unwrap(ms.values[:, 0]), ms.values[:, 1]
    utc = [units.format_utc(units.tu_to_utc(epoch, float(v))) for v in (t[0], t[-1])]
    span = float(units.tu_to_hours(1.0)) * 60.0 * float(np.ptp(t))
    return {"first_utc": utc[0], "last_utc": utc[1], "site": ms.site_at(0), "n_observations": int(len(ms)),
            "angles": "azel", "span_minutes": span, "azimuth_deg": float(np.degrees(az.mean()) % 360.0),
            "elevation_deg": float(np.degrees(el.mean())), "ra_deg": None, "dec_deg": None,
            "ra_cos_dec_rate_arcsec_min": None, "dec_rate_arcsec_min": None, "rate_arcsec_min": None,
            "rate_deg_day": None, "position_angle_deg": None}


def lone_tracklet_report(measurements: MeasurementSet, region: dict, epoch, curve: dict | None = None) -> dict:
    """What one tracklet gives when it cannot determine an orbit: ``sentence`` (why, in words),
    ``tracklet`` (:func:`sky_motion`, with the ranging IOD's ``misfit_sigma`` and ``consistent`` of
    its exposures about their own curve when ``curve`` gives them) and ``admissible_region``
    (``region``: the ranging IOD's ``range_km``, ``range_rate_kms``, ``max_c3_km2_s2``; or
    ``why_none``)."""
    sky = sky_motion(measurements, epoch)
    sky.update({k: curve[k] for k in ("misfit_sigma", "consistent") if curve and k in curve})
    where = ""
    if "range_km" in region:
        lo, hi = region["range_km"]
        rlo, rhi = region["range_rate_kms"]
        floor = " (the search's lower bound)" if lo <= region.get("range_bounds_km", [0.0])[0] * (1 + 1e-9) else ""
        where = (f"; the admissible region (geocentric C3 <= {region['max_c3_km2_s2']:g} km^2/s^2) allows ranges "
                 f"from {lo:,.0f}{floor} to {hi:,.0f} km and range rates from {rlo:+.3g} to {rhi:+.3g} km/s")
    sentence = (f"one tracklet does not determine an orbit: {sky['n_observations']} observations over "
                f"{sky['span_minutes']:.0f} min from site {sky['site'] or '(the sensor)'} give two angles and their "
                f"rates, not the range and the range rate{where}; observe the object again on another night (or "
                "from another site) and fit all the observations together")
    if sky.get("consistent") is False:
        sentence += (f"; its exposures miss their own curve by {sky['misfit_sigma']:.0f} sigma (a gross outlier "
                     "among them?)")
    return {"sentence": sentence, "tracklet": sky, "admissible_region": dict(region)}
