"""The particle Gaussian mixture (PGM) filter (Raihan & Chakravorty 2018; paper section 3),
composed of swappable steps.

Particles are only propagated between measurements. At a measurement the particles are
clustered into components (weight N_i/N, sample mean and covariance; a ``clustering``
component), each component is conditioned on the measurement (a ``pgm-update`` component), the
component weights are multiplied by the components' measurement likelihoods (log domain), and the
N posterior particles are drawn (a ``pgm-draw`` component), each remembering its component.
Between measurements the belief is the propagated mixture: the particles grouped by the component
each was drawn from, without clustering or random draws. Two hooks change that course: at the
prediction that ends a pass the belief may be replaced by least-squares fits of the arc (a
``pgm-reanchor`` component), and in the first pass after a gap a measurement far sharper than the
cloud conditions every particle as its own kernel (:mod:`.kernel_update`, ``kernel_ess``). At a
measurement far sharper than the cloud the particles may be clustered into more components first
(:mod:`.measurement_sharpness`). The steps' interfaces: :mod:`cistrack.interfaces.pgm_steps`.
"""
from __future__ import annotations

import math
import sys

import numpy as np

from cistrack.errors import CistrackError, FilterError, exception_text
from cistrack.interrupts import plugin_fault
from cistrack.interfaces import Clusterer, Dynamics, Sensor
from cistrack.interfaces.component import (MemoryNeed, check_choice, check_int, check_nonnegative, check_positive,
                                           check_range, component_name, param_specs)
from cistrack.interfaces.filter import FilterBase
from cistrack.interfaces.clustering import checked_labels
from cistrack.interfaces.iod import MIN_IOD_PARTICLES
from cistrack.interfaces.pgm_steps import (ClusteredParticles, ComponentUpdate, KernelUpdate, ParticlePrediction,
                                           PosteriorDraw, Reanchor)
from cistrack.model.belief import Belief, GaussianMixture, ParticleCloud, read_only_view, regularize_covariance
from cistrack.model.measurement import Measurement

from ..ensemble_propagation import steps_by_group
from ..initial_cloud import check_cloud, initial_particles
from ..kalman_update import group_moments
from ..measured_components import MeasuredComponents, check_epoch
from ..posterior_linearization import MAX_UPDATE_ITERATIONS
from ..particle_declarations import ParticleFilterDeclarations
from ..random_streams import independent_stream
from ..resampling import normalize_log_weights
from .cluster_merge import merged_cluster_targets, used_ranks
from .clusterer_choice import resolve_clusterer, split_clusterer, within_asked
from .component_spread import shrink_components
from .component_update import COMPONENT_LIKELIHOODS
from .measurement_sharpness import likelihood_ess_fraction, measurement_quadratic
from .reacquisition_particles import draw_mixture, measurement_spread_sigma, particles_to_draw
from .step_choice import check_step, resolve_step
from .state_bounds import StateBounds, earth_position, sample_inside
from ..process_noise import check_velocity_noise

__all__ = ["PGMFilter", "resolve_clusterer"]


MAX_REACQUIRE_FACTOR = 100.0
"""The most particles, times ``n_particles``, the PGM draws while reacquiring (4 by default)."""


class PGMFilter(ParticleFilterDeclarations, FilterBase):
    """Particle Gaussian mixture filter: clustering + per-component Kalman update + resampling.

    Parameters
    ----------
    n_particles : int
        Particles N carried between measurements, at least 100.
    n_components : int or None
        Components M the clusterer is asked for; None lets the clusterer choose (e.g. "bic"). At
        most n_particles / min_cluster_size (33 for 10,000 particles by default).
    clusterer : Clusterer or str
        A clusterer instance or a registered clustering name. Default "kmeans" (the paper's);
        "gmm" (EM) suits the "ensemble" update better. Why: docs/pgm-parameters.md.
    min_cluster_size : int or None
        Clusters with fewer particles are merged into the nearest cluster. None = the larger of
        2 x dimension and 3% of ``n_particles`` (300 of 10,000): smaller clusters give
        overconfident components.
    velocity_noise_kms_per_sqrt_day : float
        Optional process noise: velocity random walk, km/s after one day (0 = off; handed to the
        prediction that takes it).
    min_range_km, max_range_km, max_speed_kms : float or None
        Optional cislunar pruning bounds (Earth distance, synodic speed); None = not applied.
    component_update : ComponentUpdate or str
        How each component is conditioned on a measurement (a pgm-update component or its name):
        "iterated" (posterior-linearised update of the component's Gaussian, re-linearised until
        its mean stops moving) or "ensemble" (the paper's Kalman update from the particles'
        sample cross-covariances).
    update_iterations : int
        Most posterior linearisations per component and measurement, 1 to 1000 (iterated update
        only; handed to the component_update that takes it).
    component_likelihood : str
        What reweights the components under the iterated update: "posterior" (the measurement
        likelihood with h linearised over the component's posterior) or "prior" (over its prior).
    split_components : int or None
        Components the clusterer is asked for at a sharp measurement (see ``split_ess``); None
        or 0 = off (default).
    split_ess : float
        A measurement is sharp when the effective sample size of the particles' likelihood
        weights is below this fraction of the particles (0.02: fewer than 200 of 10,000 lie
        within the noise of it).
    kept_spread : float
        Share lam^2 of the spread between the clustered components kept as spread of their means
        at an update; the rest is added to every component's covariance (moment-preserving).
        1 = the plain partition (the paper's); the default 0.7 is calibrated against the exact
        Kalman filter. Not applied while reacquiring (``shrink_spread_sigma``).
    reacquire_factor : float
        Particles resampled from a posterior, times ``n_particles``, while the prior's predicted
        measurements spread wider than ``reacquire_spread_sigma`` noise sigmas (a cloud
        reacquiring after a long gap); 1 = off; at most 100 (:data:`MAX_REACQUIRE_FACTOR`).
    reacquire_spread_sigma : float
        That spread threshold, in noise standard deviations.
    shrink_spread_sigma : float
        Components are shrunk (``kept_spread``) only while the prior's predicted measurements
        spread over at most this many noise standard deviations; above it the components are
        separate hypotheses of a cloud reacquiring after a gap, not cells of one cloud.
    reanchor : Reanchor or str
        A pgm-reanchor component or its name. "arcs" (default): at the end of every pass, batch
        least squares over the arc's measurements, started from the posterior particles that fit
        them best, replaces the belief when a fit is accepted (why: docs/pgm-parameters.md). "across-gaps": the fits also span gaps, and after a gap the
        belief is the fit's line of variations (Examples 2 and 3). "off": the PGM alone (the
        paper's).
    reanchor_gap_days : float
        A gap between updates at least this long ends an arc (and starts a pass after a gap, for
        kernel_ess).
    reanchor_pause_hours : float
        A pause between updates at least this long ends a pass (the attempt is made at the
        prediction that crosses it).
    reanchor_measurements : int
        Measurements an arc needs before an attempt.
    reanchor_starts : int
        Most fits started, from the best-fitting posterior particles.
    kernel_ess : float
        In the first pass after a gap of ``reanchor_gap_days`` or more, at a measurement whose
        likelihood weights' effective sample size is below this fraction of the particles, every
        particle is conditioned as its own Gaussian kernel (covariance: its cluster's, times
        Silverman's bandwidth) instead of the clusters' Gaussians (:mod:`.kernel_update`): after a
        gap of months the first measurements cut a slab a few km thick out of a filament millions
        of km long, where a cluster's Gaussian is far from the cloud's shape. 0 = off (default);
        1 = every update of that pass (Example 3).
    posterior_draw : PosteriorDraw or str
        Where the posterior particles come from (a pgm-draw component or its name). "transform"
        (default): each cluster's own particles, mapped affinely onto its component's posterior,
        so the cloud keeps its non-Gaussian shape; "gaussian" (the paper's): N draws from the
        posterior mixture. While reacquiring (more particles drawn) or with state bounds the
        draws are Gaussian either way.
    prediction : ParticlePrediction or str
        How the particles move between measurements (a pgm-prediction component or its name):
        "propagate" (default), the dynamics plus the velocity random walk above.
    kernel_update : KernelUpdate or str
        When every particle is conditioned as its own kernel (a pgm-kernel component or its
        name): "after-gap" (default; as kernel_ess says) or "off".

    How the defaults were chosen, with the seeds and figures: docs/pgm-parameters.md.
    """

    _min_cluster_fraction = 0.03  # default minimum cluster size, as a fraction of n_particles

    default_name = "pgm"
    stacked_updates = True  # reads measurements only through MeasuredComponents
    nested_params = {  # a scenario builds these components with the PGM's values of these parameters
        "clusterer": ("n_components",),
        "component_update": ("update_iterations", "component_likelihood"),
        "reanchor": ("reanchor_gap_days", "reanchor_pause_hours", "reanchor_measurements", "reanchor_starts"),
        "prediction": ("velocity_noise_kms_per_sqrt_day",),
        "kernel_update": ("kernel_ess", "reanchor_gap_days", "reanchor_pause_hours"),
    }
    _steps = (("prediction", "pgm-prediction"), ("component_update", "pgm-update"), ("posterior_draw", "pgm-draw"),
              ("kernel_update", "pgm-kernel"), ("reanchor", "pgm-reanchor"))  # step parameter, registry kind

    def __init__(self, n_particles: int = 10000, n_components: int | None = 6,
                 clusterer: Clusterer | str = "kmeans", min_cluster_size: int | None = None,
                 velocity_noise_kms_per_sqrt_day: float = 0.0, min_range_km: float | None = None,
                 max_range_km: float | None = None, max_speed_kms: float | None = None,
                 component_update: ComponentUpdate | str = "iterated", update_iterations: int = 10,
                 component_likelihood: str = "posterior", split_components: int | None = None,
                 split_ess: float = 0.02, kept_spread: float = 0.7, reacquire_factor: float = 4.0,
                 reacquire_spread_sigma: float = 1000.0, shrink_spread_sigma: float = 1000.0,
                 posterior_draw: PosteriorDraw | str = "transform", reanchor: Reanchor | str = "arcs",
                 reanchor_gap_days: float = 5.0, reanchor_pause_hours: float = 3.0, reanchor_measurements: int = 6,
                 reanchor_starts: int = 8, kernel_ess: float = 0.0, prediction: ParticlePrediction | str = "propagate",
                 kernel_update: KernelUpdate | str = "after-gap"):
        self.prediction = check_step(self, "prediction", prediction, ParticlePrediction, ("propagate",))
        self.kernel_update = check_step(self, "kernel_update", kernel_update, KernelUpdate, ("after-gap", "off"))
        self.kernel_ess = check_range(self, "kernel_ess", kernel_ess, 0.0, 1.0)
        self.reanchor = check_step(self, "reanchor", reanchor, Reanchor, ("off", "arcs", "across-gaps"))
        self.reanchor_gap_days = check_positive(self, "reanchor_gap_days", reanchor_gap_days)
        self.reanchor_pause_hours = check_positive(self, "reanchor_pause_hours", reanchor_pause_hours)
        self.reanchor_measurements = check_int(self, "reanchor_measurements", reanchor_measurements, minimum=1)
        self.reanchor_starts = check_int(self, "reanchor_starts", reanchor_starts, minimum=1)
        self.posterior_draw = check_step(self, "posterior_draw", posterior_draw, PosteriorDraw, ("gaussian", "transform"))
        self.kept_spread = check_range(self, "kept_spread", kept_spread, 0.0, 1.0)
        self.shrink_spread_sigma = check_positive(self, "shrink_spread_sigma", shrink_spread_sigma)
        self.split_components = None if not split_components else check_int(
            self, "split_components", split_components, minimum=1)
        self.split_ess = check_range(self, "split_ess", split_ess, 0.0, 1.0)
        self.reacquire_factor = check_range(self, "reacquire_factor", reacquire_factor, 0.0, MAX_REACQUIRE_FACTOR,
                                            lo_open=True)
        self.reacquire_spread_sigma = check_positive(self, "reacquire_spread_sigma", reacquire_spread_sigma)
        self.component_update = check_step(self, "component_update", component_update, ComponentUpdate,
                                           ("iterated", "ensemble"))
        self.update_iterations = check_int(self, "update_iterations", update_iterations, minimum=1,
                                           maximum=MAX_UPDATE_ITERATIONS)
        self.component_likelihood = check_choice(self, "component_likelihood", component_likelihood,
                                                 COMPONENT_LIKELIHOODS)
        self.n_particles = check_int(self, "n_particles", n_particles)
        if self.n_particles < MIN_IOD_PARTICLES:  # the same floor as the IOD's cloud, for the same reason
            self._fail("n_particles", n_particles, f"must be >= {MIN_IOD_PARTICLES}: the particles carry a mixture "
                                                   "over a 6-D state, whose covariances need at least 7 each to have "
                                                   "full rank; fewer end in a collapsed or lost belief")
        self.n_components = None if n_components is None else check_int(self, "n_components", n_components,
                                                                         minimum=1)
        if not isinstance(clusterer, (str, Clusterer)):
            self._fail("clusterer", clusterer, "must be a Clusterer instance or a registered clustering name")
        self.clusterer = clusterer
        if isinstance(clusterer, Clusterer):  # n_components set in two places is refused here, before any run
            resolve_clusterer(clusterer, self.n_components)
        self.min_cluster_size = None if min_cluster_size is None else check_int(
            self, "min_cluster_size", min_cluster_size, minimum=1)
        self._check_component_count()
        self.velocity_noise_kms_per_sqrt_day = check_velocity_noise(self, velocity_noise_kms_per_sqrt_day)
        self.min_range_km = None if min_range_km is None else check_nonnegative(self, "min_range_km", min_range_km)
        self.max_range_km = None if max_range_km is None else check_positive(self, "max_range_km", max_range_km)
        self.max_speed_kms = None if max_speed_kms is None else check_positive(self, "max_speed_kms", max_speed_kms)
        if self.min_range_km is not None and self.max_range_km is not None and self.min_range_km >= self.max_range_km:
            self._fail("max_range_km", max_range_km, f"must exceed min_range_km = {min_range_km}")
        self._x: np.ndarray | None = None
        self._clustered: ClusteredParticles | None = None  # an update's clustered prior, until its draw
        self._probe = object()  # referenced by this attribute alone: see _owns_particles
        self._h: np.ndarray | None = None  # each particle's next integration step (TU), carried

    # -- lifecycle --------------------------------------------------------------------------------
    def memory_need(self) -> MemoryNeed:
        """Its particles and the ``reacquire_factor`` x ``n_particles`` it draws while reacquiring
        (:data:`~cistrack.interfaces.component.BYTES_PER_PARTICLE` holds the default factor 4)."""
        return MemoryNeed.particles(int(math.ceil(self.n_particles * max(1.0, self.reacquire_factor / 4.0))))

    def initialize(self, cloud: ParticleCloud, dynamics: Dynamics, sensor: Sensor,
                   rng: np.random.Generator) -> None:
        """Start from ``cloud`` (N, 6) at ``cloud.epoch``; builds the clusterer and the steps."""
        who = self._who()
        check_cloud(cloud, who, dynamics, sensor, rng)
        self._build_steps(who)
        self._dyn, self._sensor, self._rng = dynamics, sensor, rng
        self._belief_rng = independent_stream(rng)
        self._bounds = StateBounds(self.min_range_km, self.max_range_km, self.max_speed_kms, earth_position(dynamics))
        self._t = float(cloud.epoch)
        x = initial_particles(cloud, self.n_particles, rng)
        self._lost_total = 0
        self._pruned_total = 0
        self._diag: dict[str, float] = {}
        self._x, self._h, _ = self._prune(x)
        self._invalidate()
        self._kernels = self._kernel_step.start()
        self._reanchor = self._reanchor_step.start()
        self._diag = {"n_particles": float(self._x.shape[0]), "particles_lost": 0.0,
                      "particles_lost_step": 0.0, "particles_pruned": float(self._pruned_total)}

    def _build_steps(self, who: str) -> None:
        """The clusterers and the steps (``_steps``) as components, each with the PGM's settings it
        takes (``nested_params``)."""
        self._clusterer = resolve_clusterer(self.clusterer, self.n_components)
        self._split_clusterer = split_clusterer(self.clusterer, self._clusterer, self.split_components)
        defaults = {k: spec.default for k, spec in param_specs(type(self)).items()}
        built = {param: resolve_step(kind, getattr(self, param),
                                     {k: getattr(self, k) for k in self.nested_params.get(param, ())}, who, defaults)
                 for param, kind in self._steps}
        self._predictor, self._update, self._draw = built["prediction"], built["component_update"], built["posterior_draw"]
        self._kernel_step, self._reanchor_step = built["kernel_update"], built["reanchor"]

    def _predict_to(self, t: float) -> None:
        """Re-anchor if a pass ends here, then propagate every particle to ``t`` (TU); particles that
        hit a body are removed and counted."""
        reanchored = self._reanchor is not None and self._reanchor.due(t) and self._try_reanchor()
        carried = _narrow(self._sample_labels)  # each particle's component, carried through the propagation
        self._invalidate()  # the last update's clustering (N,) need not be held while propagating
        own = {"overwrite": True} if getattr(self._predictor, "overwrites", False) and self._owns_particles() else {}
        x, alive, h = self._predictor.predict(self._dyn, self._x, self._t, t, self._rng, self._h, self._who(), **own)
        lost = int(np.count_nonzero(~alive))
        self._lost_total += lost
        self._t = t
        pruned_before = self._pruned_total
        if carried is not None and lost:
            carried = carried[alive]
        self._x, self._h, self._sample_labels = self._prune(x, h, carried)
        self._diag = {"n_particles": float(self._x.shape[0]), "particles_lost": float(self._lost_total),
                      "particles_lost_step": float(lost),
                      "particles_pruned": float(self._pruned_total - pruned_before)}
        if reanchored:
            self._diag["reanchored"] = 1.0

    def update(self, measurement: Measurement) -> None:
        """Cluster, update each component with the measurement, reweight, draw the posterior particles."""
        self._require_init()
        who = self._who()
        check_epoch(self._t, measurement, who)
        if self._reanchor is not None:
            self._reanchor.observe(measurement)
        self._sample_labels = self._mixture = None  # the carried components (N,): the update clusters afresh
        if self._split_clusterer is None:  # cluster before the residuals (N, m) exist, so that the
            self._ensure_clustered()       # clustering's work arrays never meet them
        meas = MeasuredComponents(self._sensor, measurement)
        dres = residuals_in_chunks(meas, self._x)
        if not np.all(np.isfinite(dres)):
            raise FilterError(f"filter '{who}': the sensor returned NaN predicted measurements")
        sharpness = _Sharpness(self._cluster_for(meas, dres), dres, meas.R)
        if self._kernels is not None and self._kernels.due(float(measurement.t), sharpness):
            self._kernel_update(meas, dres, sharpness.value, who)
            return
        # drawn particles start with their cluster's step: the clusters' steps now, so that the
        # carried steps (N,) are not held through the update
        step = steps_by_group(self._h, self._labels, self._prior.n_components)
        self._h = None
        ess = sharpness.value
        del sharpness
        post, w, self._clustered, spread, shrink, log_evidence = self._condition(meas, dres, who)
        del dres
        samples, slabels = self._draw_posterior(post, spread, who)
        self._h = None if step is None else step[slabels]
        self._x, self._sample_labels = samples, slabels
        self._mixture = post
        self._labels = None  # the next update clusters afresh
        self._diag.update({
            "n_components": float(post.n_components),
            "effective_components": float(1.0 / np.sum(w * w)),
            "log_likelihood": float(log_evidence),
            "max_component_weight": float(w.max()),
            "likelihood_ess_fraction": float(ess),
            "n_particles": float(samples.shape[0]),
            "prior_spread_sigma": spread,
            "components_shrunk": float(shrink),
        })

    def _cluster_for(self, meas: MeasuredComponents, dres: np.ndarray) -> float | None:
        """Cluster the prior particles for this measurement (into ``split_components`` when it is
        sharp); returns its sharpness (likelihood ESS fraction; None when not computed)."""
        sharpness = None
        if self._split_clusterer is not None:  # a measurement far sharper than the cloud: smaller clusters
            sharpness = likelihood_ess_fraction(measurement_quadratic(dres, meas.R))
            if sharpness < self.split_ess:
                self._labels = self._prior = None
                self._ensure_clustered(self._split_clusterer)
        self._ensure_clustered()
        return sharpness

    def _condition(self, meas: MeasuredComponents, dres: np.ndarray, who: str
                   ) -> tuple[GaussianMixture, np.ndarray, ClusteredParticles, float, bool, float]:
        """The posterior mixture after the component update and reweighting, its weights (M,) as
        computed; the clustered prior, the prior's measurement spread (noise sigmas), whether the
        components were shrunk, and the log evidence."""
        x, labels, m = self._x, self._labels, self._prior.n_components
        mom = group_moments(x, dres, labels, m)
        mom.pxx = regularize_covariance(mom.pxx, 1e-12)
        prior = ClusteredParticles(x, labels, mom.mean_x.copy(), mom.pxx.copy())
        spread = measurement_spread_sigma(dres, meas.R)
        shrink = (self.kept_spread < 1.0 and m > 1 and not self._update.uses_particles
                  and spread <= self.shrink_spread_sigma)  # not while reacquiring (component_spread.py)
        if shrink:
            mom.mean_x, mom.pxx = shrink_components(mom.counts, mom.mean_x, mom.pxx, self.kept_spread)
        means, covs, loglik = self._update.update(mom, meas.residuals_to_measurement, meas.R)
        logw, log_evidence = normalize_log_weights(np.log(mom.counts / mom.counts.sum()) + loglik, who)
        w = np.exp(logw)
        if not (np.all(np.isfinite(means)) and np.all(np.isfinite(covs))):
            raise FilterError(f"filter '{who}': the component update produced non-finite moments")
        return GaussianMixture(w, means, covs), w, prior, spread, shrink, log_evidence

    def _draw_posterior(self, post: GaussianMixture, spread: float, who: str) -> tuple[np.ndarray, np.ndarray]:
        """The posterior particles and their components: the draw step's from the clustered prior
        (``_clustered``, taken), except while reacquiring (more particles drawn) or with state
        bounds (Gaussian draws inside them)."""
        prior, self._clustered = self._clustered, None
        n_draw = particles_to_draw(spread, self.n_particles, self.reacquire_factor, self.reacquire_spread_sigma)
        if n_draw != self.n_particles or self._bounds.active:
            post.cholesky()  # a covariance that cannot be factorised fails here, with the prior still whole
            self._release_prior()
            del prior  # the prior particles are not needed for Gaussian draws: free them first
            return self._sample_posterior(post, n_draw)
        try:
            samples, slabels = self._draw.draw(prior, post, n_draw, self._rng)
        except np.linalg.LinAlgError as exc:
            raise FilterError(f"filter '{who}': a cluster's covariance could not be factorised "
                              f"for the posterior draw ({exc}); posterior_draw = 'gaussian' avoids it") from None
        if not np.all(np.isfinite(samples)):
            raise FilterError(f"filter '{who}': the posterior draw produced non-finite particles")
        return samples, slabels

    def _kernel_update(self, meas: MeasuredComponents, dres: np.ndarray, sharpness: float, who: str) -> None:
        """Every particle its own kernel (kernel_update.py): the clustered prior gives each cluster's
        covariance and size, ``dres`` (N, m) are the particles' residuals to the measurement."""
        prior = ClusteredParticles(self._x, self._labels, self._prior.means, self._prior.covariances)
        spread = measurement_spread_sigma(dres, meas.R)
        n_draw = particles_to_draw(spread, self.n_particles, self.reacquire_factor, self.reacquire_spread_sigma)
        samples, _, log_evidence = self._kernels.update(prior, meas.residuals_to_measurement, meas.R, n_draw,
                                                        self._rng, who)
        # the draws' parent clusters are no components of the posterior: the belief clusters them
        self._x, self._sample_labels, self._h = samples, None, None
        self._mixture = None
        self._labels = self._prior = None
        self._diag.update({"log_likelihood": log_evidence, "likelihood_ess_fraction": float(sharpness),
                           "n_particles": float(samples.shape[0]), "prior_spread_sigma": spread,
                           "kernel_update": 1.0})

    def _try_reanchor(self) -> bool:
        """Replace the particles by draws from the accepted least-squares solutions, if any."""
        mix = self._reanchor.attempt(self._x, self._t, self._dyn, self._sensor)
        if mix is None:
            return False
        x = self._reanchor.draw(self.n_particles, self._rng)
        if x is None:
            (self._x, self._sample_labels), self._h = self._sample_posterior(mix, self.n_particles), None
        else:
            self._x, self._h, self._sample_labels = self._prune(x)
        return True

    # -- belief -----------------------------------------------------------------------------------
    @property
    def belief(self) -> Belief:
        """Posterior mixture and resampled particles after an update; after a prediction the
        propagated mixture: each particle keeps the component it was drawn from, and each
        component is the mean and covariance of its particles now. Where the particles carry no
        components (the start, a kernel update, a re-anchoring to least-squares draws) they are
        clustered with a random stream of the belief's own. Reading the belief never draws from
        the update's random stream, so the estimates do not depend on how often it is read."""
        self._require_init()
        if self._mixture is None:
            labels = self._sample_labels
            if labels is None:
                labels = self._clustered_labels(self._clusterer, self._belief_rng)
            self._mixture, labels = self._group_mixture(labels)
            self._sample_labels = _narrow(labels)  # held beside the next update's own clustering
        return Belief(self._t, self._mixture, ParticleCloud(self._x, self._t, None, self._sample_labels))

    def _totals(self) -> dict[str, float]:
        out = {"particles_lost": float(self._lost_total)}
        if self._mixture is not None and "n_components" not in self._diag:
            out["n_components"] = float(self._mixture.n_components)
        return out

    # -- internals --------------------------------------------------------------------------------
    def _is_initialized(self) -> bool:
        return self._x is not None

    def _invalidate(self) -> None:
        self._labels = None
        self._mixture = None
        self._prior = None
        self._sample_labels = None

    def _ensure_clustered(self, clusterer: Clusterer | None = None) -> None:
        """Cluster the current particles into the prior mixture (once per prediction), with
        ``clusterer`` (default: the filter's)."""
        if self._labels is not None:
            return
        self._prior, self._labels = self._group_mixture(self._clustered_labels(clusterer or self._clusterer, self._rng))

    def _clustered_labels(self, clusterer: Clusterer, rng: np.random.Generator) -> np.ndarray:
        """The clusterer's labels (N,) of the current particles, drawing from ``rng``. The clusterer
        is handed a read-only view of the particles (no copy): one that writes into them is a
        FilterError naming it, where it would have moved the filter's particles."""
        who = f"filter '{self._who()}': clusterer '{component_name(clusterer)}'"
        try:
            labels = clusterer.cluster(read_only_view(self._x), rng)
        except CistrackError:
            raise
        except MemoryError as exc:  # still out of memory, with the clusterer named (probe I1)
            raise MemoryError(f"{who}: cluster() ran out of memory ({exception_text(exc)})") from exc
        except ValueError as exc:
            if "read-only" not in str(exc):
                raise FilterError(f"{who}: cluster() raised {exception_text(exc)}") from exc
            raise FilterError(f"{who}: cluster() tried to write into the particles it was given ({exc}); a "
                              "clusterer must not change its input (work on a copy)") from exc
        except BaseException as exc:  # the clusterer's own bug: named, not blamed on the filter
            if not plugin_fault(exc):
                raise
            raise FilterError(f"{who}: cluster() raised {exception_text(exc)}") from exc
        return within_asked(checked_labels(labels, self._x.shape[0], who), clusterer, who)

    def _group_mixture(self, labels: np.ndarray) -> tuple[GaussianMixture, np.ndarray]:
        """The mixture of the current particles grouped by ``labels`` (N,) (weight N_i/N, each group's
        mean and covariance), and the labels (N,) it was made from: numbered from 0 without gaps
        (groups emptied since the labels were given are dropped), groups too small for a
        covariance merged into their nearest."""
        labels = labels.astype(np.intp)  # its own copy, relabelled in place: one (N,) array at a time
        ranks = used_ranks(labels)
        if ranks[-1] + 1 < ranks.size:  # a group emptied: renumbered without gaps
            np.take(ranks, labels, out=labels, mode="clip")
        target, merged = merged_cluster_targets(self._x, labels, self._min_size())
        if target is not None:
            np.take(target, labels, out=labels, mode="clip")
        m = int(labels.max()) + 1
        mom = group_moments(self._x, None, labels, m)
        self._diag["clusters_merged"] = float(merged)
        self._diag["n_components"] = float(m)
        return GaussianMixture(mom.counts / mom.counts.sum(), mom.mean_x, regularize_covariance(mom.pxx, 1e-12)), labels

    def _check_component_count(self) -> None:
        """Refuse more components than ``n_particles`` holds clusters of the smallest size kept
        (``min_cluster_size``, else 3 % of the particles): the rest would be merged into their
        neighbours after a clustering into all of them (minutes for thousands)."""
        if self.n_components is None:
            return
        size = self.min_cluster_size or int(np.ceil(self._min_cluster_fraction * self.n_particles))
        most = max(1, self.n_particles // size)
        if self.n_components > most:
            which = "min_cluster_size" if self.min_cluster_size else "min_cluster_size's default, 3 % of n_particles"
            self._fail("n_components", self.n_components,
                       f"must be <= {most}: {self.n_particles} particles hold at most {most} clusters of {size} "
                       f"({which}); smaller ones are merged into their neighbours anyway")

    def _min_size(self) -> int:
        """Fewest particles a component may have: ``min_cluster_size``, else the larger of 2 x the
        dimension and ``_min_cluster_fraction`` of the particles (never more than there are)."""
        n, d = self._x.shape
        size = self.min_cluster_size if self.min_cluster_size is not None else max(
            2 * d, int(np.ceil(self._min_cluster_fraction * self.n_particles)))
        return min(size, n)

    def _prune(self, x: np.ndarray, h: np.ndarray | None = None, labels: np.ndarray | None = None
               ) -> tuple[np.ndarray, np.ndarray | None, np.ndarray | None]:
        """The particles (N, 6) inside the state bounds, with their carried step sizes (N,) and
        components (N,), each None when not carried."""
        if not self._bounds.active:
            return x, h, labels
        ok = self._bounds.admissible(x)
        n_bad = int(np.count_nonzero(~ok))
        if n_bad == x.shape[0]:
            raise FilterError(f"filter '{self._who()}': every particle lies outside the state bounds (min_range_km = "
                              f"{self.min_range_km}, max_range_km = {self.max_range_km}, max_speed_kms = "
                              f"{self.max_speed_kms}; range from the Earth's centre): widen them or leave them unset")
        self._pruned_total += n_bad
        return x[ok], (None if h is None else h[ok]), (None if labels is None else labels[ok])

    def _owns_particles(self) -> bool:
        """Whether nothing but this filter references its particles and steps (no belief, view or
        caller holds them), so that the prediction may overwrite them: each has as many references
        as ``_probe``, an object held by one attribute alone."""
        alone = sys.getrefcount(self._probe)
        return sys.getrefcount(self._x) <= alone and (self._h is None or sys.getrefcount(self._h) <= alone)

    def _release_prior(self) -> None:
        """Drop the filter's references to the prior particles (N, 6) and their labels, so that the
        posterior draws do not coexist with them; the update sets new ones."""
        self._x = self._labels = self._sample_labels = None

    def _sample_posterior(self, post: GaussianMixture, n: int) -> tuple[np.ndarray, np.ndarray]:
        """``n`` draws from ``post`` inside the state bounds, and their components; counts the pruned.
        Without bounds the draws are made in chunks (:func:`.reacquisition_particles.draw_mixture`)."""
        if not self._bounds.active:
            return draw_mixture(post, n, self._rng)
        x, lab, pruned = sample_inside(post, n, self._rng, self._bounds)
        self._pruned_total += pruned
        self._diag["particles_pruned"] = self._diag.get("particles_pruned", 0.0) + float(pruned)
        if x.shape[0] == 0:
            raise FilterError(f"filter '{self._who()}': the posterior lies entirely outside the state bounds")
        return x, lab


def _narrow(labels: np.ndarray | None) -> np.ndarray | None:
    """``labels`` (N,) as int8 when they fit (1 byte a particle instead of 8 while carried through a
    propagation), else as they are."""
    if labels is None or labels.dtype == np.int8 or labels.size == 0 or labels.max() > np.iinfo(np.int8).max:
        return labels
    return labels.astype(np.int8)


RESIDUAL_CHUNK = 65_536  # particles whose predicted measurements are computed at once


def residuals_in_chunks(meas: MeasuredComponents, x: np.ndarray, chunk: int = RESIDUAL_CHUNK) -> np.ndarray:
    """``meas.residuals_to_measurement(x)`` (N, m) for particles ``x`` (N, 6), ``chunk`` rows at a
    time: the sensor's work arrays are a chunk's, and each particle's residual is its own."""
    n = x.shape[0]
    if n <= chunk:
        return meas.residuals_to_measurement(x)
    first = meas.residuals_to_measurement(x[:chunk])
    out = np.empty((n,) + first.shape[1:], dtype=first.dtype)
    out[:chunk] = first
    del first
    for a in range(chunk, n, chunk):
        out[a:a + chunk] = meas.residuals_to_measurement(x[a:a + chunk])
    return out


class _Sharpness:
    """A measurement's likelihood ESS fraction (``measurement_sharpness.py``), computed once when
    first asked for; ``value`` is 1.0 while it has not been."""

    def __init__(self, known: float | None, residuals: np.ndarray, R: np.ndarray) -> None:
        self._known, self._residuals, self._R = known, residuals, R

    def __call__(self) -> float:
        if self._known is None:
            self._known = likelihood_ess_fraction(measurement_quadratic(self._residuals, self._R))
        return self._known

    @property
    def value(self) -> float:
        return 1.0 if self._known is None else self._known
