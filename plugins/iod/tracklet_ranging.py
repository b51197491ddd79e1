"""IOD from what telescopes deliver: tracklets of 3 or more observations, on one or several nights,
from one or several sites (registered as iod "tracklet-ranging").

1. The observations are split into tracklets (:func:`.tracklets.split_tracklets`: a gap of more
   than ``gap_hours``, a site change, or ``MAX_SPAN_HOURS``), and each tracklet is reduced to its
   attributable (line of sight and rate at its mean time).
2. A **seed** tracklet (the first with ``min_tracklet`` observations that lie on their curve; the
   next ones if that fails) spans its admissible region: a grid of ``n_range`` ranges, log-spaced
   over ``range_min_km``-``range_max_km`` (3,000 km to 3 million km by default: the bounds do not
   prune a cislunar object), times ``n_rate`` range rates within the energy bound ``max_c3``
   (:mod:`.ranging_search`).
3. Every grid state is propagated at once with the dynamics to the observations of the next
   ``score_tracklets`` tracklets and scored there; the least squares is started from the best few
   and the best converged fit is kept (outlier rejection on). A seed whose fit leaves residuals
   above :data:`.ranging_search.CLEAN_NOISE_SCALE` times the stated noise (a false minimum) gives
   way to the next seed; when no seed fits its observations, the fit nearest the noise is kept.
4. With ``arc = "all"`` (what ``cistrack fit`` asks for) the fit is extended over the whole arc,
   doubling its span each time; the cloud is then at the last observation and a filter after it
   has nothing left to do. With ``arc = "seed"`` (default, for ``cistrack run`` scenarios) the
   cloud is at the last observation of the seed and scoring tracklets and the filter goes on.

The cloud is ``n_particles`` draws from the fit's Gaussian at its epoch (seeded Generator). A file
of one tracklet leaves the range undetermined: the cloud is then the admissible region itself
(drawn from the grid) and ``meta["why"]`` says so. ``meta`` records the method, the tracklets
(their first times, sites, sizes, consistency), which were the seed and which scored it, the fits
tried and why the seed was chosen.

The IOD propagates with ``dynamics``: a registered dynamics name (built with the sensor's epoch
when the model takes one, e.g. ``ephemeris``) or, from Python, a Dynamics instance.
"""
from __future__ import annotations

import inspect

import numpy as np

from cistrack.errors import IODError
from cistrack import units
from cistrack.interfaces import Dynamics, IODMethod, Sensor
from cistrack.interfaces.component import check_choice, check_int, check_positive, check_range
from cistrack.interfaces.iod import check_iod_particles
from cistrack.least_squares import FitOptions, FitResult
from cistrack.least_squares.result import sigma_factor
from cistrack.least_squares.trajectory import arc_states_and_stms
from cistrack.model.belief import ParticleCloud
from cistrack.model.measurement import MeasurementSet
from cistrack.units import TU_S

from .ranging_search import (CLEAN_NOISE_SCALE, RangingProgress, ScoredGrid, admissible_extent, admissible_states, refine,
                             score_states)
from .ranging_arc import extend_arc, tracklet_record
from .tracklets import Attributable, attributable, split_tracklets

__all__ = ["TrackletRangingIOD", "ARCS"]

ARCS = ("seed", "all")
NEAR_DAYS = 6.0
"""A seed whose scoring tracklets all lie within this many days is tried before one whose do not."""
_SEED_OPTIONS = FitOptions(max_iterations=60, max_condition=1e30, max_weak_sigma_km=1e30, max_reject_fraction=0.1)
"""The seed's least squares: warnings off (a short arc is weakly determined by nature) and at most
10 % rejected: from a grid point the first pass can settle where whole tracklets disagree, and the
fit's default cap (half) let it reject them and keep a wrong orbit (9 of 22 clean observations
rejected, 55 km off, on one 9:2 NRHO set)."""
_PATIENT_OPTIONS = FitOptions(max_iterations=300, max_condition=1e30, max_weak_sigma_km=1e30, max_reject_fraction=0.1)
"""The seed's least squares again, with more iterations, when no seed converged within
:data:`_SEED_OPTIONS`' (only then: the fits that converge within them stay as they were). Two
tracklets of one site four days apart (2025-010D on 2025-12-21 and 25, 7 and 5 exposures) leave
the orbit weakly determined, and Levenberg-Marquardt needed 84 iterations from the best grid state."""


SEED_ROWS_PER_TRACKLET = 50
"""Observations of each tracklet the seed's scoring and least squares use, evenly spaced (all of a
shorter one): a survey's tracklets hold 3-5, and a file whose tracklets held 2,000 exposures each
spent over 15 minutes in the seed's fits, silent. The attributable and the final fit use them all."""


def _thinned(indices: np.ndarray, n: int = SEED_ROWS_PER_TRACKLET) -> np.ndarray:
    """``indices`` (sorted), or ``n`` of them evenly spaced, the first and last among them."""
    if indices.size <= n:
        return indices
    return indices[np.unique(np.round(np.linspace(0, indices.size - 1, n)).astype(int))]


EXTENSION_ROWS = 2000
"""The extension of the seed's fit over the arc (:func:`.ranging_arc.extend_arc`) uses every
observation of an arc of at most this many; of a longer one, every tracklet longer than
:data:`SEED_ROWS_PER_TRACKLET` gives that many, evenly spaced."""


def _extension_rows(n: int, atts: list[Attributable]) -> np.ndarray:
    """Rows (sorted) of the ``n`` observations the extension over the arc uses (:data:`EXTENSION_ROWS`)."""
    keep = np.ones(n, dtype=bool)
    if n <= EXTENSION_ROWS:
        return np.nonzero(keep)[0]
    for a in atts:
        if a.indices.size > SEED_ROWS_PER_TRACKLET:
            keep[a.indices] = False
            keep[_thinned(a.indices)] = True
    return np.nonzero(keep)[0]


def _extended(dyn, sensor, ms: MeasurementSet, atts: list[Attributable], fit: FitResult,
              rows: np.ndarray) -> tuple[FitResult, np.ndarray, list[str]]:
    """:func:`.ranging_arc.extend_arc` of the seed's ``fit`` (over ``rows`` of ``ms``) over the
    arc's observations, the long tracklets of a long arc thinned (:func:`_extension_rows`): the
    IOD's orbit is the least squares' start, which then takes every observation. A file whose 12 tracklets held
    2,000 exposures each had spent minutes here, silent, refitting all 24,000 at every step."""
    use = np.union1d(_extension_rows(len(ms), atts), rows)
    if use.size == len(ms):
        return extend_arc(dyn, sensor, ms, fit, rows)
    mask = np.zeros(len(ms), dtype=bool)
    mask[use] = True
    fit, sub_rows, steps = extend_arc(dyn, sensor, ms.subset(mask), fit, np.searchsorted(use, rows))
    return fit, use[sub_rows], [*steps, f"long tracklets thinned to {SEED_ROWS_PER_TRACKLET} observations each: "
                                f"{use.size} of {len(ms)} observations"]


def _tried_text(records: list[dict]) -> str:
    """The seeds tried, one short phrase each ('tracklet 1 scored on 2, 3: 8000 ranges, 3 fits'),
    at most four, then how many more."""
    parts = [f"tracklet {r['seed'] + 1} scored on {', '.join(str(j + 1) for j in r['scored_on']) or 'none'}: "
             f"{r['grid_states']} ranges, {r['fits_tried']} fits" for r in records[:4]]
    return "; ".join(parts) + (f"; and {len(records) - 4} more" if len(records) > 4 else "")


def _failure_advice(ms: MeasurementSet) -> str:
    """What to check when no seed gives an orbit: the stated angle uncertainties first when their
    median is below :data:`SMALLEST_PLAUSIBLE_ARCSEC` (weights that tight fit no orbit; they are
    most likely degrees written where arcseconds belong), else the observations and the range bounds."""
    median = float(np.median(ms.sigmas[:, :2])) / units.ARCSEC_RAD
    if median < SMALLEST_PLAUSIBLE_ARCSEC:
        return (f"the observations state angle uncertainties of {median:.3g} arcsec (median), below 1 "
                "milliarcsecond, finer than any astrometry: no orbit fits them to within such weights; check "
                "them (degrees written as arcseconds?), then the range bounds range_min_km/range_max_km")
    return "check the observations or widen range_min_km/range_max_km"


SMALLEST_PLAUSIBLE_ARCSEC = 0.001
"""Smallest plausible angle uncertainty, arcsec (1 milliarcsecond: no astrometry is finer); as
the observation readers warn of."""


class TrackletRangingIOD(IODMethod):
    """Systematic ranging over a tracklet's admissible region (see the module docstring).

    Parameters
    ----------
    n_particles : int
        Particles in the cloud.
    dynamics : str
        The registered model that propagates the grid and the fits, built with the sensor's epoch
        (a Dynamics instance is taken as it is, from Python).
    arc : str
        "seed": the cloud after the seed and scoring tracklets; "all": after the whole arc.
    gap_hours : float
        A gap longer than this (hours) starts a new tracklet.
    min_tracklet : int
        Observations a seed tracklet needs (at least 2).
    score_tracklets : int
        Tracklets after the seed whose observations score the grid.
    n_range : int
        Ranges of the grid (log-spaced between the range bounds).
    n_rate : int
        Range rates of the grid per range (inside the energy bound).
    range_min_km : float
        Smallest topocentric range of the grid, km.
    range_max_km : float
        Largest topocentric range of the grid, km.
    max_c3 : float
        Energy bound of the grid: geocentric C3 at most this, km^2/s^2 (0: bound to the Earth).
    tries : int
        Least-squares fits started per seed (the best grid states apart in range).
    seeds : int
        Seed tracklets tried before giving up.
    """

    def __init__(self, *, n_particles: int = 2000, dynamics: str = "cr3bp", arc: str = "seed",
                 gap_hours: float = 1.5, min_tracklet: int = 3, score_tracklets: int = 3,
                 n_range: int = 160, n_rate: int = 64, range_min_km: float = 3000.0,
                 range_max_km: float = 3.0e6, max_c3: float = 1.0, tries: int = 6, seeds: int = 4) -> None:
        self.n_particles = check_iod_particles(self, n_particles)
        if not isinstance(dynamics, (str, Dynamics)):
            self._fail("dynamics", dynamics, "must be a registered dynamics name or a Dynamics")
        if isinstance(dynamics, str):
            from cistrack.api import default_registry

            check_choice(self, "dynamics", dynamics, default_registry().names("dynamics"))
        self.dynamics = dynamics
        self.arc = check_choice(self, "arc", arc, ARCS)
        self.gap_hours = check_positive(self, "gap_hours", gap_hours)
        self.min_tracklet = check_int(self, "min_tracklet", min_tracklet, minimum=2)
        self.score_tracklets = check_int(self, "score_tracklets", score_tracklets, minimum=1)
        self.n_range = check_int(self, "n_range", n_range, minimum=10)
        self.n_rate = check_int(self, "n_rate", n_rate, minimum=4)
        self.range_min_km = check_positive(self, "range_min_km", range_min_km)
        self.range_max_km = check_positive(self, "range_max_km", range_max_km)
        if self.range_max_km <= self.range_min_km:
            self._fail("range_max_km", range_max_km, f"must exceed range_min_km ({range_min_km})")
        self.max_c3 = check_range(self, "max_c3", max_c3, -1.0e3, 1.0e3)
        self.tries = check_int(self, "tries", tries, minimum=1)
        self.seeds = check_int(self, "seeds", seeds, minimum=1)

    def _model(self, sensor: Sensor) -> Dynamics:
        """The dynamics: the instance given, or the registered model built with the sensor's epoch."""
        if isinstance(self.dynamics, Dynamics):
            return self.dynamics
        from cistrack.api import default_registry

        reg = default_registry()
        factory = reg.get("dynamics", self.dynamics).factory
        takes_epoch = isinstance(factory, type) and "epoch" in inspect.signature(factory).parameters
        epoch = _sensor_epoch(sensor)
        return reg.create("dynamics", self.dynamics, **({"epoch": epoch} if takes_epoch and epoch else {}))

    def _seed_rank(self, atts: list[Attributable], k: int) -> tuple[bool, bool, float]:
        """Sort key of tracklet ``k`` as a seed: consistent ones first, then those whose
        ``score_tracklets`` nearest tracklets lie within :data:`NEAR_DAYS` (a grid propagated
        further resolves the orbit too coarsely), then the earliest."""
        gaps = np.sort([abs(a.t - atts[k].t) for j, a in enumerate(atts) if j != k])
        far = gaps.size == 0 or gaps[min(self.score_tracklets, gaps.size) - 1] > NEAR_DAYS * 86400.0 / TU_S
        return (not atts[k].consistent, bool(far), float(atts[k].t))

    def _why_not_first(self, atts: list[Attributable], order: list[int], k: int, records: list[dict]) -> str:
        """Why the seed ``k`` is not the earliest tracklet that has enough observations ("" when it is);
        ``records``: the seeds tried (:meth:`_first_seed`)."""
        first = min(order)
        if k == first:
            return ""
        if not atts[first].consistent:
            return (f"; tracklet {first + 1} misses its own curve by {atts[first].misfit:.0f} sigma: it holds a "
                    "gross outlier")
        if order.index(first) < order.index(k):
            scales = [r["noise_scale"] for r in records if r["seed"] == first and "noise_scale" in r]
            if scales:
                return (f"; tracklet {first + 1}'s fit converged with residuals {min(scales):.3g} times the stated "
                        "noise: a false minimum")
            return f"; tracklet {first + 1} gave no fit"
        return f"; tracklet {first + 1} has no {self.score_tracklets} others within {NEAR_DAYS:g} days"

    def _grid(self, att: Attributable) -> tuple[np.ndarray, np.ndarray]:
        return admissible_states(att, n_range=self.n_range, n_rate=self.n_rate, range_min_km=self.range_min_km,
                                 range_max_km=self.range_max_km, max_c3=self.max_c3)

    def _scoring(self, atts: list[Attributable], k: int, near_only: bool = False) -> list[int]:
        """The tracklets that score the seed ``k``: the next :attr:`score_tracklets` (later ones
        first, nearest first); with ``near_only``, those of them within :data:`NEAR_DAYS`."""
        others = [j for j in range(len(atts)) if j != k]
        others.sort(key=lambda j: (atts[j].t < atts[k].t, abs(atts[j].t - atts[k].t)))
        score_with = others[:self.score_tracklets]
        if near_only:
            score_with = [j for j in score_with if abs(atts[j].t - atts[k].t) <= NEAR_DAYS * 86400.0 / TU_S]
        return score_with

    def _seed_fit(self, dyn: Dynamics, sensor: Sensor, ms: MeasurementSet, atts: list[Attributable],
                  k: int, options: FitOptions = _SEED_OPTIONS,
                  score_with: list[int] | None = None) -> tuple[FitResult | None, np.ndarray, dict]:
        """(fit, rows, record) of the ranging from tracklet ``k`` scored on ``score_with`` (None:
        the next tracklets, :meth:`_scoring`)."""
        score_with = self._scoring(atts, k) if score_with is None else score_with
        rows = np.sort(np.concatenate([_thinned(atts[j].indices) for j in [k, *score_with]]))
        states, rho = self._grid(atts[k])
        score = score_states(dyn, sensor, ms, np.setdiff1d(rows, _thinned(atts[k].indices)), states, atts[k].t)
        grid = ScoredGrid(states, rho, score, atts[k].t)
        fit, best, tried = refine(dyn, sensor, ms, rows, grid, tries=self.tries, options=options,
                                  progress=getattr(self, "_progress", None))
        rec = {"seed": k, "scored_on": score_with, "grid_states": int(len(states)), "fits_tried": tried,
               "start_range_km": float(rho[best]) if best >= 0 else None,
               "converged": bool(fit is not None and fit.converged)}
        return fit, rows, rec

    def estimate(self, measurements: MeasurementSet, sensor: Sensor, rng: np.random.Generator) -> ParticleCloud:
        """Particle cloud (n_particles, 6), synodic, at the last observation the fit used (see the
        module docstring); IODError when no tracklet has ``min_tracklet`` observations or no seed
        gives a fit."""
        ms = measurements
        who = f"iod '{type(self).registry_name or 'tracklet-ranging'}'"
        if not isinstance(ms, MeasurementSet):
            raise IODError(f"{who}: needs a MeasurementSet, got {type(ms).__name__}")
        n_times = len(np.unique(ms.times))
        if n_times < self.min_tracklet:
            raise IODError(f"{who}: needs observations at {self.min_tracklet} or more distinct times (one "
                           f"observation per time is used); these are at {n_times} time{'s' * (n_times != 1)}")
        sites = np.array([ms.site_at(i) for i in range(len(ms))])
        every = split_tracklets(ms.times, sites, self.gap_hours)
        atts = [attributable(ms, sensor, g) for g in every if g.size >= 2]
        order = [k for k in sorted(range(len(atts)), key=lambda k: self._seed_rank(atts, k))
                 if atts[k].indices.size >= self.min_tracklet]
        if not order:
            raise self._no_seed(who, [int(g.size) for g in every])
        if len(atts) == 1:
            return self._lone(atts[0], rng)
        return self._ranged(self._model(sensor), sensor, ms, atts, order, rng, who)

    def _no_seed(self, who: str, sizes: list[int]) -> IODError:
        """The error when no tracklet (of ``sizes`` observations each) has ``min_tracklet``: their
        sizes in words, and advice that can be followed (min_tracklet is lowered only above 2)."""
        counts = sorted(set(sizes), reverse=True)
        obs = [f"{n} observation{'s' * (n != 1)}" for n in counts]
        told = (f"{len(sizes)} tracklet{'s' * (len(sizes) != 1)}, " + ("each of " * (len(sizes) > 1)) + obs[0]
                if len(counts) == 1 else f"{len(sizes)} tracklets: "
                + ", ".join(f"{sizes.count(n)} of {o}" for n, o in zip(counts, obs)))
        head = (f"{who}: no tracklet has {self.min_tracklet} observations ({told}; a gap over "
                f"{self.gap_hours:g} h or a site change ends one)")
        if self.min_tracklet > 2:
            return IODError(f"{head}; lower min_tracklet or observe longer", settings=("min_tracklet",))
        return IODError(f"{head}; observe longer: a seed needs {self.min_tracklet} observations of one site within "
                        f"{self.gap_hours:g} h of each other")

    def _seed_trials(self, atts: list[Attributable], order: list[int]):
        """(options, seed, scoring tracklets, whether only the near ones) in the order :meth:`_first_seed` tries them: the first
        :attr:`seeds` seeds with :data:`_SEED_OPTIONS`, then with :data:`_PATIENT_OPTIONS`, then
        those whose scoring tracklets include one beyond :data:`NEAR_DAYS`, scored on the nearer
        ones alone (:data:`_PATIENT_OPTIONS`). A grid propagated over 11 days to a survey's fourth
        tracklet resolved no orbit (three tracklets of a halo orbit on three nights, one more 11.6
        days on: 8 seeds, 48 fits, none converged); the two nearer tracklets gave it, and the
        extension over the arc took the far one."""
        seeds = order[:self.seeds]
        scoring = {k: self._scoring(atts, k) for k in seeds}
        for options in (_SEED_OPTIONS, _PATIENT_OPTIONS):
            for k in seeds:
                yield options, k, scoring[k], False
        for k in seeds:
            near = self._scoring(atts, k, near_only=True)
            if near and near != scoring[k]:
                yield _PATIENT_OPTIONS, k, near, True

    def _first_seed(self, dyn, sensor, ms, atts, order) -> tuple[int, FitResult | None, np.ndarray, dict, list]:
        """(seed, fit, rows, its record, every record) of the first seed tracklet whose ranging gives a
        converged fit that fits its observations (noise scale below :data:`.ranging_search.CLEAN_NOISE_SCALE`),
        trying seeds, options and scoring tracklets in the order of :meth:`_seed_trials`; when none
        does, the converged fit with the smallest noise scale (fit None when none converged).
        A converged fit far above the noise is a false minimum: one seed tracklet's fit converged with
        residuals 57 times the noise, 139,000 km from the truth, where the next seed's fit lay 5 km off."""
        records: list[dict] = []
        fallback: tuple = (-1, None, np.zeros(0, dtype=int), {})
        self._progress = RangingProgress()
        trials = list(self._seed_trials(atts, order))
        for n, (options, k, score_with, near_only) in enumerate(trials, start=1):
            self._progress.seed(k, int(atts[k].indices.size), n, len(trials))
            fit, rows, rec = self._seed_fit(dyn, sensor, ms, atts, k, options, score_with)
            if options is _PATIENT_OPTIONS:
                rec["max_iterations"] = options.max_iterations
            if near_only:
                rec["near_only"] = True
            records.append(rec)
            if fit is None or not fit.converged:
                continue
            rec["noise_scale"] = float(fit.noise_scale)
            if fit.noise_scale < CLEAN_NOISE_SCALE:
                return k, fit, rows, rec, records
            if fallback[1] is None or fit.noise_scale < fallback[1].noise_scale:
                fallback = (k, fit, rows, rec)
        return (*fallback, records)

    def _ranged(self, dyn, sensor, ms, atts, order, rng, who) -> ParticleCloud:
        k, fit, rows, rec, records = self._first_seed(dyn, sensor, ms, atts, order)
        if fit is None:
            raise IODError(f"{who}: no seed tracklet gave an orbit that fits its neighbours ({len(records)} tried: "
                           f"{_tried_text(records)}); " + _failure_advice(ms), settings=("range_min_km", "range_max_km"))
        patient = (f"; its least squares needed more than {_SEED_OPTIONS.max_iterations} iterations (given "
                   f"{_PATIENT_OPTIONS.max_iterations})") if "max_iterations" in rec else ""
        if fit.noise_scale >= CLEAN_NOISE_SCALE:
            patient += (f"; no seed fitted its observations: this one's residuals are {fit.noise_scale:.3g} times "
                        "the stated noise, the smallest")
        if rec.get("near_only"):
            patient += (f"; only the tracklets within {NEAR_DAYS:g} days scored it: scored on farther ones too, "
                        "no seed gave an orbit that fits them")
        why = (f"ranging from tracklet {k + 1} of {len(atts)} ({atts[k].indices.size} observations"
               + self._why_not_first(atts, order, k, records) + "), scored on tracklets "
               + ", ".join(str(j + 1) for j in rec["scored_on"]) + patient)
        info = {"why": why, "tracklets": tracklet_record(atts), "seeds_tried": records,
                "seed_rows": [int(i) for i in rows], "extension": []}
        if self.arc == "all":
            fit, rows, info["extension"] = _extended(dyn, sensor, ms, atts, fit, rows)
        return self._cloud(dyn, fit, ms, rows, info, rng)

    def _cloud(self, dyn, fit: FitResult, ms, rows, info: dict, rng) -> ParticleCloud:
        """``n_particles`` draws from the fit's Gaussian at the last of ``rows``; ``info``: the
        meta the caller adds (why, tracklets, seeds tried, seed rows, extension steps)."""
        t_last = float(ms.times[rows].max())
        states, stms = arc_states_and_stms(dyn, fit.state, fit.epoch, np.array([t_last]))
        cov = stms[0] @ fit.covariance @ stms[0].T
        cov = 0.5 * (cov + cov.T) * sigma_factor(fit.noise_scale) ** 2
        draws = rng.multivariate_normal(states[0], cov, size=self.n_particles, method="eigh")
        meta = {"method": "tracklet-ranging", "arc": self.arc, **info, "rows_used": [int(i) for i in rows],
                "fit_rms": float(fit.rms), "noise_scale": float(fit.noise_scale), "n_rejected": int(fit.n_rejected),
                "best_state": [float(v) for v in states[0]], "best_covariance": cov.tolist()}
        return ParticleCloud(draws, t_last, meta=meta)

    def _lone(self, att: Attributable, rng: np.random.Generator) -> ParticleCloud:
        """One tracklet: the admissible region itself (range undetermined); ``meta["admissible_region"]``
        gives its extent (:func:`.ranging_search.admissible_extent`)."""
        states, rho = self._grid(att)
        if len(states) == 0:
            rate = float(np.linalg.norm(att.u_dot)) / units.ARCSEC_RAD * 60.0 / units.TU_S  # arcsec per minute
            raise IODError(
                f"iod '{type(self).registry_name or 'tracklet-ranging'}': the lone tracklet ({att.indices.size} "
                f"observations, moving {rate:,.4g}\"/min in the synodic frame) admits no orbit: at no range from "
                f"{self.range_min_km:,.0f} to {self.range_max_km:,.0f} km is this motion that of an orbit with "
                f"C3 <= {self.max_c3:g} km^2/s^2. A near-Earth object, or exposures with wrong times?")
        pick = rng.choice(len(states), size=self.n_particles, replace=len(states) < self.n_particles)
        region = admissible_extent(att, range_min_km=self.range_min_km, range_max_km=self.range_max_km,
                                   max_c3=self.max_c3)
        lo, hi = region.get("range_km", [rho.min(), rho.max()])
        why = (f"one tracklet only ({att.indices.size} observations): the range is not determined; the cloud "
               f"is the admissible region, ranges {lo:,.0f}-{hi:,.0f} km")
        meta = {"method": "tracklet-ranging", "why": why, "arc": "lone tracklet",
                "tracklets": tracklet_record([att]), "rows_used": [int(i) for i in att.indices],
                "seed_rows": [int(i) for i in att.indices], "admissible_region": region}
        return ParticleCloud(states[pick], float(att.t), meta=meta)


def _sensor_epoch(sensor: Sensor) -> str | None:
    """The epoch (UTC text) of the sensor or of the first member of a site network, or None."""
    for s in [sensor, *getattr(sensor, "members", {}).values()]:
        e = getattr(s, "epoch", None)
        if isinstance(e, str):
            return e
    return None
