"""Conformance checks for IOD plugins (a simulated first pass of the 9:2 NRHO)."""
from __future__ import annotations

import numpy as np

from cistrack.model.belief import ParticleCloud
from cistrack.errors import IODError
from cistrack.interfaces.iod import IODMethod
from cistrack.units import km_to_lu
from cistrack.testing.check_support import (close, describe_exception, no_global_random_state, require, round_trip, unchanged)
from cistrack.testing.fixtures import first_pass, nrho_truth

__all__ = ["IOD_CHECKS"]

RANGE_MIN_LU = float(km_to_lu(84_328.0))
RANGE_MAX_LU = float(km_to_lu(550_000.0))


def _estimate(iod, seed=0, n_times=16):
    ms, sensor = first_pass(n_times)
    cloud = iod.estimate(ms, sensor, np.random.default_rng(seed))
    require(isinstance(cloud, ParticleCloud), f"estimate() returned {type(cloud).__name__}, not ParticleCloud")
    return cloud, ms, sensor


def check_is_iod(iod) -> None:
    require(isinstance(iod, IODMethod), f"{type(iod).__name__} does not derive from cistrack.interfaces.IODMethod")


def check_cloud_shape_epoch_and_units(iod) -> None:
    """The cloud is (N, 6) finite at the epoch of one of the measurements, in LU and VU
    (median range from the observer inside the cislunar bounds, 84,328-550,000 km)."""
    cloud, ms, sensor = _estimate(iod)
    x = cloud.states
    require(x.ndim == 2 and x.shape[1] == 6 and x.shape[0] >= 2, f"cloud states have shape {x.shape}, expected (N>=2, 6)")
    require(np.all(np.isfinite(x)), "cloud states contain NaN or infinity")
    require(np.any(np.isclose(ms.times, cloud.epoch, rtol=0, atol=1e-9)),
            f"cloud epoch {cloud.epoch} TU is not the time of any measurement used ({ms.times[0]:.4g}..{ms.times[-1]:.4g})")
    rho = np.linalg.norm(x[:, :3] - np.asarray(sensor.observer_position(cloud.epoch)), axis=1)
    med = float(np.median(rho))
    require(RANGE_MIN_LU <= med <= RANGE_MAX_LU,
            f"median range of the cloud is {med:.4g} LU, outside cislunar space: are positions in LU?")


def check_cloud_near_truth(iod) -> None:
    """The cloud's mean position is within half the target's range of the truth at the
    cloud's epoch (catches a wrong frame, unit or epoch; not a test of accuracy)."""
    cloud, ms, sensor = _estimate(iod)
    times, states = nrho_truth(16)
    k = int(np.argmin(np.abs(times - cloud.epoch)))
    rho = float(np.linalg.norm(states[k, :3] - np.asarray(sensor.observer_position(times[k]))))
    miss = float(np.linalg.norm(cloud.mean[:3] - states[k, :3]))
    require(miss < 0.5 * rho, f"the cloud's mean position is {miss:.3g} LU from the truth at its epoch (the target "
                              f"is {rho:.3g} LU away): check the frame (synodic), units (LU) and epoch")


def check_reproducible(iod) -> None:
    with no_global_random_state("estimate()"):
        a, _, _ = _estimate(iod, seed=5)
    b, _, _ = _estimate(iod, seed=5)
    ok, diff = close(a.states, b.states, 0, 0)
    require(ok and a.epoch == b.epoch, "estimate() with generators of the same seed gave different clouds")


def check_inputs_not_mutated(iod) -> None:
    ms, sensor = first_pass(16)
    with unchanged(measurements=ms):
        iod.estimate(ms, sensor, np.random.default_rng(0))


def check_too_few_measurements_raise_ioderror(iod) -> None:
    """A single measurement cannot determine an orbit: IODError with a message."""
    ms, sensor = first_pass(16)
    one = ms.subset(np.array([0]))
    try:
        iod.estimate(one, sensor, np.random.default_rng(0))
    except IODError as exc:
        require(str(exc).strip(), "IODError without a message")
        return
    except Exception as exc:
        require(False, f"estimate() from one measurement raised {describe_exception(exc)}, not cistrack.errors.IODError")
    require(False, "estimate() returned a cloud from a single measurement; raise IODError")


def check_same_after_pickle(iod) -> None:
    other = round_trip(iod)
    a, _, _ = _estimate(iod, seed=9)
    b, _, _ = _estimate(other, seed=9)
    ok, _ = close(a.states, b.states, 0, 0)
    require(ok, "the unpickled copy estimates a different cloud")


IOD_CHECKS = [
    ("is_iod", check_is_iod),
    ("cloud_shape_epoch_and_units", check_cloud_shape_epoch_and_units),
    ("cloud_near_truth", check_cloud_near_truth),
    ("reproducible", check_reproducible),
    ("inputs_not_mutated", check_inputs_not_mutated),
    ("too_few_measurements_raise_ioderror", check_too_few_measurements_raise_ioderror),
    ("same_after_pickle", check_same_after_pickle),
]
