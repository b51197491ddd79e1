"""The paper's three kinematic-fit IOD variants as presets of :class:`.kinematic.KinematicFitIOD`
(registered as iod "noisy-range", "uniform-range" and "uniform-range-velocity-bound"): each fixes
the range prior (and the speed bound) and keeps the other parameters, so a preset gives the same
cloud as the composed component with the same seed.
"""
from __future__ import annotations

from cistrack.interfaces.component import check_positive
from cistrack import hookimpl
from cistrack.errors import ParameterError

from .kinematic import KinematicFitIOD
from .range_priors import NoisyRange, UniformRange

__all__ = ["NoisyRangeIOD", "UniformRangeIOD", "UniformRangeVelocityBoundIOD"]


class NoisyRangeIOD(KinematicFitIOD):
    """Preset "noisy-range": kinematic-fit with ``range_prior = noisy(alpha)``, no speed bound.

    Parameters
    ----------
    alpha : float
        Relative 1-sigma of the measured range (handed to the noisy range prior).
    n_particles, oversampling, max_oversampling, order, pass_gap_hours, fit_fraction, min_fit, max_fit, range_min_km, range_max_km, range_sampling : as for kinematic-fit
        See :class:`KinematicFitIOD`.
    """

    def __init__(self, *, n_particles: int = 2000, oversampling: float = 5.0,
                 max_oversampling: float = 50.0, order: int = 4, pass_gap_hours: float = 3.0,
                 fit_fraction: float = 0.5, min_fit: int = 8, max_fit: int = 12,
                 alpha: float = 0.05, range_min_km: float = 84_328.0,
                 range_max_km: float = 550_000.0, range_sampling: str = "per-measurement") -> None:
        super().__init__(range_prior=NoisyRange(alpha=alpha), n_particles=n_particles,
                         oversampling=oversampling, max_oversampling=max_oversampling, order=order,
                         pass_gap_hours=pass_gap_hours, fit_fraction=fit_fraction, min_fit=min_fit,
                         max_fit=max_fit, range_min_km=range_min_km, range_max_km=range_max_km,
                         range_sampling=range_sampling)
        self.alpha = self.range_prior.alpha


class UniformRangeIOD(KinematicFitIOD):
    """Preset "uniform-range": kinematic-fit with ``range_prior = uniform`` between the range
    bounds, no speed bound.

    Parameters
    ----------
    n_particles, oversampling, max_oversampling, order, pass_gap_hours, fit_fraction, min_fit, max_fit, range_min_km, range_max_km, range_sampling : as for kinematic-fit
        See :class:`KinematicFitIOD` (the range bounds are also the uniform prior's).
    """

    def __init__(self, *, n_particles: int = 2000, oversampling: float = 5.0,
                 max_oversampling: float = 50.0, order: int = 4, pass_gap_hours: float = 3.0,
                 fit_fraction: float = 0.5, min_fit: int = 8, max_fit: int = 12,
                 range_min_km: float = 84_328.0, range_max_km: float = 550_000.0,
                 range_sampling: str = "per-measurement") -> None:
        super().__init__(range_prior=_uniform(self, range_min_km, range_max_km), n_particles=n_particles,
                         oversampling=oversampling, max_oversampling=max_oversampling, order=order,
                         pass_gap_hours=pass_gap_hours, fit_fraction=fit_fraction, min_fit=min_fit,
                         max_fit=max_fit, range_min_km=range_min_km, range_max_km=range_max_km,
                         range_sampling=range_sampling)


class UniformRangeVelocityBoundIOD(KinematicFitIOD):
    """Preset "uniform-range-velocity-bound": uniform-range plus the speed bound
    ``max_speed_kms`` (42 km/s in the topocentric frame, the paper's).

    Parameters
    ----------
    n_particles, oversampling, max_oversampling, order, pass_gap_hours, fit_fraction, min_fit, max_fit, range_min_km, range_max_km, max_speed_kms, speed_frame, range_sampling : as for kinematic-fit
        See :class:`KinematicFitIOD`; here ``max_speed_kms`` is a number (default 42 km/s).
    """

    def __init__(self, *, n_particles: int = 2000, oversampling: float = 10.0,
                 max_oversampling: float = 100.0, order: int = 4, pass_gap_hours: float = 3.0,
                 fit_fraction: float = 0.5, min_fit: int = 8, max_fit: int = 12,
                 range_min_km: float = 84_328.0, range_max_km: float = 550_000.0,
                 max_speed_kms: float = 42.0, speed_frame: str = "topocentric",
                 range_sampling: str = "per-measurement") -> None:
        super().__init__(range_prior=_uniform(self, range_min_km, range_max_km), n_particles=n_particles,
                         oversampling=oversampling, max_oversampling=max_oversampling, order=order,
                         pass_gap_hours=pass_gap_hours, fit_fraction=fit_fraction, min_fit=min_fit,
                         max_fit=max_fit, range_min_km=range_min_km, range_max_km=range_max_km,
                         max_speed_kms=check_positive(self, "max_speed_kms", max_speed_kms),
                         speed_frame=speed_frame, range_sampling=range_sampling)


def _uniform(owner: KinematicFitIOD, range_min_km: float, range_max_km: float) -> UniformRange:
    """The uniform prior of a preset; its parameter errors name the preset."""
    try:
        return UniformRange(range_min_km=range_min_km, range_max_km=range_max_km)
    except ParameterError as exc:
        raise ParameterError(str(exc).replace("range-prior 'uniform'", owner._label())) from None


@hookimpl
def cistrack_register(registry) -> None:
    """The composed component and its three presets, in this order (this module is the entry point
    ``kinematic-fit``: registering here keeps kinematic.py free of an import of its presets)."""
    registry.add("iod", "kinematic-fit", KinematicFitIOD)
    registry.add("iod", "noisy-range", NoisyRangeIOD)
    registry.add("iod", "uniform-range", UniformRangeIOD)
    registry.add("iod", "uniform-range-velocity-bound", UniformRangeVelocityBoundIOD)
