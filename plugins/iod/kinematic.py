"""Kinematic-fitting IOD (the paper's Algorithm 1), vectorised over the Monte Carlo samples.

For each sample: perturb every fitted azimuth/elevation with its noise, draw a range for each
measurement from the range model, place the target at

    r_syn(t_k) = sensor.observer_position(t_k) + rho_k * sensor.line_of_sight((az_k, el_k), t_k),

fit a polynomial of order p in time to each synodic coordinate and take value and derivative at
the last fitted time t_f. Because the positions are synodic, the derivative *is* the synodic
velocity: no transport-theorem terms are needed.

All samples share the fit times, so the fit is a fixed linear map of the data
(:mod:`cistrack.plugins.iod.polyfit`): one matrix product for all samples and coordinates.

Range models
------------
The range model is a component parameter, ``range_prior`` (kind "range-prior",
:mod:`.range_priors`): ``noisy`` (Gaussian around the measured range, ``alpha``) or ``uniform``
(between two bounds); the speed bound is a separate parameter, ``max_speed_kms`` (None: no
bound). The paper's three variants are registered presets with their own names::

    [iod]                                     # the same as name = "noisy-range", alpha = 0.05
    name = "kinematic-fit"
    range_prior = { name = "noisy", alpha = 0.05 }

``noisy-range``
    range_prior = noisy(alpha): rho ~ N(rho_meas, (alpha rho_meas)^2) around the *measured*
    range of the measurement set's 'range' component (OD later ignores that component).
``uniform-range``
    range_prior = uniform: rho ~ U[range_min_km, range_max_km] (default 84,328-550,000 km).
``uniform-range-velocity-bound``
    uniform-range plus ``max_speed_kms`` = 42 km/s: samples faster than that are pruned.

``range_sampling`` chooses whether each measurement gets its own range draw ("per-measurement",
Algorithm 1 of the paper, default) or one draw is shared by all the measurements of a sample
("per-sample", a target at constant range).

Pruning and the frame of the speed bound
----------------------------------------
A sample survives when its fitted range from the observer at t_f lies in
[range_min_km, range_max_km] and, for the velocity-bounded model, its speed is at most
``max_speed_kms``. The paper fitted in the Earth-fixed (rotating) topocentric NEU frame, where a
target at lunar distance has an apparent speed of ~29 km/s from the Earth's rotation alone; the
42 km/s bound only makes sense in that frame. ``speed_frame="topocentric"`` (default) therefore
bounds the speed of a second, equally cheap fit of the topocentric positions
rho [cos el cos az, cos el sin az, sin el] (NEU); ``speed_frame="synodic"`` bounds the synodic
speed instead. The synodic frame turns at only 1 rad/TU (~1 km/s of apparent motion at lunar
distance instead of ~29 km/s), so the same 42 km/s is a *looser* bound there and prunes fewer
samples; lower ``max_speed_kms`` if you bound synodic speed (the NRHO moves at < 2 km/s).

The fit works with any sensor whose two angles (a, b) give the unit vector
(cos b cos a, cos b sin a, sin b) in an observer frame that ``line_of_sight`` maps to synodic:
az/el (NEU) or RA/Dec (ICRF axes, e.g. sensor ``real-telescope`` with ``measurement = "radec"``).
With RA/Dec the "topocentric" speed is that of the fitted ICRF-axes topocentric positions, an
inertial frame without the ~29 km/s of Earth rotation: as for ``speed_frame="synodic"``, the
42 km/s bound is looser there.

Gross outliers in the first pass
--------------------------------
An observation hundreds of sigma off the pass's other ones (a wrong object, a mistyped time)
would bend every sample's polynomials. Before sampling, the pass is screened
(:mod:`.pass_screen`): one or two such measurements are left out, the fit window is chosen again
from the rest by the same rule, and the cloud's ``meta["screened_out"]`` (and the run's manifest)
names them. Clean passes lose nothing, so runs without such an outlier give the numbers they gave
before.

When too few samples survive, more are drawn in batches of ``oversampling * n_particles`` until
``n_particles`` survive or ``max_oversampling * n_particles`` samples have been drawn; then an
:class:`~cistrack.errors.IODError` says how many survived and what pruned the rest. The cloud's
``meta`` records draws, survivors and pruning counts. Each batch is drawn and fitted in chunks
of at most ``CHUNK_SAMPLES`` samples (:mod:`.chunked_draws`) with the numbers of one whole draw,
so memory does not grow with the oversampling factor.
"""
from __future__ import annotations

import math
from typing import Iterator

import numpy as np

from cistrack.model.belief import ParticleCloud
from cistrack.interfaces.component import check_choice, check_int, check_positive, check_range, MemoryNeed, IOD_CHUNK_BYTES
from cistrack.errors import IODError, PluginError
from cistrack.interfaces import IODMethod, RangePrior, Sensor
from cistrack.interfaces.iod import check_iod_particles
from cistrack.model.measurement import MeasurementSet
from cistrack.units import LU_KM, VU_KMS

from .chunked_draws import CHUNK_SAMPLES, draw_in_chunks
from .kinematic_fit import FitInputs, kinematic_states, prepare_fit

__all__ = ["KinematicFitIOD", "RANGE_MODELS", "FitInputs", "kinematic_states", "prepare_fit"]

RANGE_MODELS = ("noisy-range", "uniform-range", "uniform-range-velocity-bound")
SPEED_FRAMES = ("topocentric", "synodic")
RANGE_SAMPLING = ("per-measurement", "per-sample")


class KinematicFitIOD(IODMethod):
    """Kinematic-fitting IOD with a selectable range model (see the module docstring).

    Defaults are the paper's.

    Parameters
    ----------
    range_prior : RangePrior or str
        How ranges are drawn: a range-prior component, e.g. "uniform" (between two bounds) or
        "noisy" (Gaussian around the measured range).
    n_particles : int
        Particles wanted in the cloud.
    oversampling : float
        Samples drawn per batch, as a multiple of ``n_particles`` (paper: 5-10).
    max_oversampling : float
        Give up after drawing this multiple of ``n_particles`` in total.
    order : int
        Order of the polynomial fitted to each angle over time (paper: 4).
    pass_gap_hours : float
        A gap between measurements longer than this ends the first pass, hours.
    fit_fraction : float
        Fraction of the first pass's measurements that are fitted (the earliest ones).
    min_fit, max_fit : int
        Bounds on the number of measurements fitted.
    range_min_km, range_max_km : float
        Cislunar range bounds: samples whose fitted range falls outside are pruned, km.
    max_speed_kms : float or None
        Samples faster than this are pruned, km/s (None: no speed bound).
    speed_frame : str
        Frame of the speed bound: "topocentric" (paper) or "synodic".
    range_sampling : str
        "per-measurement" (one range per fitted measurement, the paper's Algorithm 1) or
        "per-sample" (one range per sample).
    """

    _chunk = CHUNK_SAMPLES  # samples fitted at once (bounds memory; the numbers do not depend on it)

    def __init__(self, *, range_prior: RangePrior | str = "uniform", n_particles: int = 2000,
                 oversampling: float = 5.0, max_oversampling: float = 50.0, order: int = 4,
                 pass_gap_hours: float = 3.0, fit_fraction: float = 0.5, min_fit: int = 8,
                 max_fit: int = 12, range_min_km: float = 84_328.0,
                 range_max_km: float = 550_000.0, max_speed_kms: float | None = None,
                 speed_frame: str = "topocentric", range_sampling: str = "per-measurement") -> None:
        if not isinstance(range_prior, (str, RangePrior)):
            self._fail("range_prior", range_prior, "must be a range-prior component or its registered name")
        self.range_prior = range_prior
        self.n_particles = check_iod_particles(self, n_particles)
        self.oversampling = check_range(self, "oversampling", oversampling, 1.0, 1e4)
        self.max_oversampling = check_range(self, "max_oversampling", max_oversampling, 1.0, 1e6)
        if self.max_oversampling < self.oversampling:
            self._fail("max_oversampling", max_oversampling, f"must be >= oversampling ({oversampling})")
        self.order = check_int(self, "order", order, minimum=1, maximum=10)
        self.pass_gap_hours = check_positive(self, "pass_gap_hours", pass_gap_hours)
        self.fit_fraction = check_range(self, "fit_fraction", fit_fraction, 0.0, 1.0, lo_open=True)
        self.min_fit = check_int(self, "min_fit", min_fit, minimum=self.order + 1)
        self.max_fit = check_int(self, "max_fit", max_fit, minimum=self.min_fit)
        self.range_min_km = check_positive(self, "range_min_km", range_min_km)
        self.range_max_km = check_positive(self, "range_max_km", range_max_km)
        if self.range_max_km <= self.range_min_km:
            self._fail("range_max_km", range_max_km, f"must exceed range_min_km ({range_min_km})")
        self.max_speed_kms = None if max_speed_kms is None else check_positive(self, "max_speed_kms", max_speed_kms)
        self.speed_frame = check_choice(self, "speed_frame", speed_frame, SPEED_FRAMES)
        self.range_sampling = check_choice(self, "range_sampling", range_sampling, RANGE_SAMPLING)

    # -- sampling -------------------------------------------------------------------------------
    def memory_need(self) -> MemoryNeed:
        """The particles it returns plus one chunk of oversampled fits (``n_particles``)."""
        return MemoryNeed.particles(self.n_particles, IOD_CHUNK_BYTES)

    def _label_name(self) -> str:
        return type(self).registry_name or self.range_model

    @property
    def range_model(self) -> str:
        """The paper's name of this range model: "noisy-range", "uniform-range" or
        "uniform-range-velocity-bound" (a prior of another kind: its registered name)."""
        prior = self._prior()
        base = {"noisy": "noisy-range", "uniform": "uniform-range"}.get(
            type(prior).registry_name, type(prior).registry_name or type(prior).__name__)
        return base + ("-velocity-bound" if self.max_speed_kms is not None else "")

    def _prior(self) -> RangePrior:
        """The range prior (a name given in Python is created from the installed plugins; in a
        scenario the prior arrives built through the run's registry)."""
        if isinstance(self.range_prior, str):
            from cistrack.api import default_registry
            return default_registry().create("range-prior", self.range_prior)
        return self.range_prior

    def _draw(self, fit: FitInputs, n: int, rng: np.random.Generator,
              prior: RangePrior) -> Iterator[tuple[np.ndarray, np.ndarray]]:
        """Sampled angles (c, K, 2) and ranges (c, K) LU, chunk by chunk (:mod:`.chunked_draws`):
        together the n samples of one whole draw of the angles followed by the ranges."""
        k = fit.times.shape[0]

        def angles(c: int, g: np.random.Generator) -> np.ndarray:
            return fit.angles[None] + fit.angle_sigmas[None] * g.standard_normal((c, k, 2))

        def ranges(c: int, g: np.random.Generator) -> np.ndarray:
            shape = (c, k) if self.range_sampling == "per-measurement" else (c, 1)
            return _checked_ranges(prior, prior.draw(fit.ranges, shape, g), shape, (c, k))

        return draw_in_chunks(n, rng, angles, ranges, self._chunk)

    def _prune(self, fit: FitInputs, states: np.ndarray, topo_vel: np.ndarray,
               rho: np.ndarray) -> tuple[np.ndarray, dict[str, int]]:
        """Boolean keep mask (n,) and the number of samples each reason removed (first reason
        that applies, in the order listed)."""
        rng_km = np.linalg.norm(states[:, :3] - fit.observer[-1], axis=1) * LU_KM
        finite = np.all(np.isfinite(states), axis=1) & np.all(np.isfinite(topo_vel), axis=1)
        reasons = {
            "non_finite": ~finite,
            "nonpositive_range_draw": np.any(rho <= 0.0, axis=1),
            "range_below_min": rng_km < self.range_min_km,
            "range_above_max": rng_km > self.range_max_km,
        }
        if self.max_speed_kms is not None:
            v = topo_vel if self.speed_frame == "topocentric" else states[:, 3:]
            reasons["speed_above_max"] = np.linalg.norm(v, axis=1) * VU_KMS > self.max_speed_kms
        keep = np.ones(states.shape[0], dtype=bool)
        counts: dict[str, int] = {}
        for name, bad in reasons.items():
            hit = bad & keep
            counts[name] = int(hit.sum())
            keep &= ~bad
        return keep, counts

    def estimate(self, measurements: MeasurementSet, sensor: Sensor,
                 rng: np.random.Generator) -> ParticleCloud:
        """Particle cloud (n_particles, 6), synodic, at the last fitted measurement time.

        Raises IODError (before sampling) when the first pass cannot be fitted, and after
        sampling when fewer than n_particles samples survive ``max_oversampling`` draws.
        """
        who = f"iod '{self._label_name()}'"
        prior = self._prior()
        fit = prepare_fit(measurements, sensor, order=self.order, pass_gap_hours=self.pass_gap_hours,
                          fit_fraction=self.fit_fraction, min_fit=self.min_fit, max_fit=self.max_fit,
                          need_range=prior.needs_measured_range, who=who)
        batch = int(math.ceil(self.oversampling * self.n_particles))
        limit = int(math.ceil(self.max_oversampling * self.n_particles))
        out = np.empty((self.n_particles, 6))  # survivors are written here as they come (no second copy)
        n_kept = drawn = batches = 0
        pruned: dict[str, int] = {}
        while n_kept < self.n_particles and drawn < limit:
            n = min(batch, limit - drawn)
            for angles, rho in self._draw(fit, n, rng, prior):  # memory bounded by the chunk size
                states, topo_vel = kinematic_states(fit, sensor, angles, rho)
                keep, counts = self._prune(fit, states, topo_vel, rho)
                for key, c in counts.items():
                    pruned[key] = pruned.get(key, 0) + c
                if n_kept < self.n_particles:  # later survivors are counted, not kept
                    new = states[keep][: self.n_particles - n_kept]
                    out[n_kept:n_kept + new.shape[0]] = new
                n_kept += int(keep.sum())
            drawn += n
            batches += 1
        if n_kept < self.n_particles:
            why = ", ".join(f"{c} by {k.replace('_', ' ')}" for k, c in pruned.items() if c) or "none"
            raise IODError(
                f"{who}: only {n_kept} of {drawn} drawn samples survived pruning, fewer than the "
                f"{self.n_particles} particles wanted (pruned: {why}; bounds: range "
                f"{self.range_min_km:g}-{self.range_max_km:g} km"
                + (f", {self.speed_frame} speed <= {self.max_speed_kms:g} km/s"
                   if self.max_speed_kms is not None else "")
                + "). Raise max_oversampling, relax the bounds, or check the measurements.",
                settings=("max_oversampling", "range_min_km", "range_max_km", "max_speed_kms"))
        states = out
        meta = {
            "method": self._label_name(),
            "range_model": self.range_model,
            "range_sampling": self.range_sampling,
            "speed_frame": self.speed_frame if self.max_speed_kms is not None else None,
            "order": self.order,
            "fit_indices": fit.indices.tolist(),
            "fit_times": fit.times.tolist(),
            "screened_out": fit.screened_record(measurements),
            "draws": drawn,
            "batches": batches,
            "survivors": n_kept,
            "survival_fraction": n_kept / drawn,
            "pruned": pruned,
        }
        return ParticleCloud(states, fit.epoch, meta=meta)


def _checked_ranges(prior: RangePrior, drawn: object, shape: tuple[int, int], full: tuple[int, int]) -> np.ndarray:
    """The range prior's draw for ``shape`` as (n, K) LU (``full``), unless it is not numbers that
    broadcast there or holds NaN or inf: a PluginError naming the prior (NaN had been dropped as
    pruned without a word, and a wrong shape blamed on the IOD)."""
    who = f"range-prior '{getattr(prior, 'registry_name', '') or type(prior).__name__}'"
    try:
        ranges = np.asarray(drawn, dtype=float)
        out = np.broadcast_to(ranges, full)
    except (TypeError, ValueError):
        raise PluginError(f"{who}: draw() for shape {shape} returned {type(drawn).__name__} of shape {np.shape(drawn)}, "
                       f"not ranges (LU) that broadcast to {full}") from None
    bad = int(np.count_nonzero(~np.isfinite(ranges)))
    if bad:
        raise PluginError(f"{who}: draw() returned {bad} NaN or infinite ranges of {ranges.size}; ranges must be "
                       "finite numbers (LU)")
    return out

