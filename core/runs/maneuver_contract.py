"""What a run holds its maneuver detector and response to at every call, as the conformance suite
does (docs/plugins.md, "Maneuver detectors"; :mod:`cistrack.testing.checks_maneuver_detectors`):
a detector that raises or answers what ``observe`` does not promise, and a response whose cloud
the filter cannot start from at the detection, end the run "failed" with a
:class:`~cistrack.errors.PluginError` naming the plugin (kind, name, distribution), the step and
what was wrong, never a NaN in the results or a failure blamed on the filter."""
from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np

from cistrack import units
from cistrack.errors import CistrackError, PluginError, exception_text
from cistrack.interfaces.maneuvers import Detection
from cistrack.interrupts import plugin_fault
from cistrack.model.belief import ParticleCloud

__all__ = ["plugin_call", "checked_observation", "checked_response_cloud"]


def _days(t: float) -> str:
    return f"{float(units.tu_to_days(t)):.3f} d"


def plugin_call(who: str, where: str, call: Callable[..., Any], *args: Any, **kwargs: Any) -> Any:
    """``call(*args, **kwargs)``; the plugin's own exception (``sys.exit``, GeneratorExit and a
    KeyboardInterrupt that no signal raised included) becomes a PluginError
    ``"{who}: {method}() raised {Type}: {message} {where}"``, ``where`` saying when (the step).
    cistrack's errors, numerical failures (LinAlgError, FloatingPointError) and interrupts from
    signals pass as they are; a MemoryError stays one, naming the plugin (probe I1)."""
    try:
        return call(*args, **kwargs)
    except (CistrackError, np.linalg.LinAlgError, FloatingPointError):
        raise
    except MemoryError as exc:
        raise MemoryError(f"{who}: {call.__name__}() ran out of memory {where} ({exception_text(exc)})") from exc
    except BaseException as exc:
        if not plugin_fault(exc):
            raise
        raise PluginError(f"{who}: {call.__name__}() raised {exception_text(exc)} {where}") from exc


def _is_number(x: Any) -> bool:
    return isinstance(x, (int, float, np.integer, np.floating)) and not isinstance(x, (bool, np.bool_))


def checked_observation(out: Any, t: float, t_first: float, who: str, where: str) -> tuple[float, Detection | None]:
    """``out``, what the detector ``who`` returned from ``observe`` at the update at ``t`` (TU),
    as (statistic float, Detection or None), unless it is not a pair of a finite number and None
    or a well-formed Detection (:func:`_detection_fault`, ``t_first``: the run's first update, TU):
    PluginError naming ``who``, ``where`` (the step) and what was wrong."""
    if not (isinstance(out, tuple) and len(out) == 2):
        shown = f"a tuple of {len(out)}" if isinstance(out, tuple) else type(out).__name__
        raise PluginError(f"{who}: observe() {where} returned {shown}, not (statistic, Detection or None)")
    stat, det = out
    if not (_is_number(stat) and math.isfinite(float(stat))):
        what = "NaN or infinite" if _is_number(stat) else f"a {type(stat).__name__}"
        raise PluginError(f"{who}: observe() {where} returned the statistic {stat!r}: {what}, not a finite number "
                          "(a statistic is due at every update, also when nothing is detected)")
    if det is not None:
        fault = _detection_fault(det, float(t), t_first)
        if fault:
            raise PluginError(f"{who}: observe() {where} returned a Detection whose {fault}")
    return float(stat), det


def _detection_fault(det: Any, t: float, t_first: float) -> str:
    """What is wrong with the detection ``det`` at the update at ``t`` ("" when nothing): not a
    Detection, its ``t`` not the update's, its statistic or threshold not finite, its
    ``t_burn_bounds`` not finite within [``t_first``, ``t``], its ``delta_v`` not 3 finite numbers."""
    if not isinstance(det, Detection):
        return f"type is {type(det).__name__} (expected a cistrack.interfaces.maneuvers.Detection or None)"
    if not (_is_number(det.t) and abs(float(det.t) - t) <= 1e-9 * max(1.0, abs(t))):
        shown = _days(det.t) if _is_number(det.t) else repr(det.t)
        return f"t = {shown} is not the update's time {_days(t)}"
    if not all(_is_number(v) and math.isfinite(float(v)) for v in (det.statistic, det.threshold)):
        return f"statistic {det.statistic!r} or threshold {det.threshold!r} is not a finite number"
    bounds = tuple(det.t_burn_bounds) if isinstance(det.t_burn_bounds, (tuple, list)) else ()
    if not (len(bounds) == 2 and all(_is_number(v) and math.isfinite(float(v)) for v in bounds)
            and t_first - 1e-9 <= float(bounds[0]) <= float(bounds[1]) <= t + 1e-9 * max(1.0, abs(t))):
        shown = ", ".join(_days(v) if _is_number(v) else repr(v) for v in bounds) or repr(det.t_burn_bounds)
        return (f"t_burn_bounds ({shown}) are not finite times within [an earlier update's time, the detection's] = "
                f"[{_days(t_first)}, {_days(t)}]")
    if det.delta_v is not None and not (np.shape(det.delta_v) == (3,) and np.all(np.isfinite(det.delta_v))):
        return f"delta_v {np.asarray(det.delta_v).tolist()} is not None or 3 finite numbers (synodic VU)"
    return ""


def checked_response_cloud(cloud: Any, detection: Detection, who: str) -> ParticleCloud | None:
    """``cloud``, what the response ``who`` returned for ``detection``: None, or a ParticleCloud of
    finite (N >= 1, 6) states at ``detection.t`` (to 1e-9 TU relative); PluginError naming ``who``
    and what was wrong otherwise (the filter would be blamed for starting from it)."""
    if cloud is None:
        return None
    t = float(detection.t)
    if not isinstance(cloud, ParticleCloud):
        raise PluginError(f"{who}: respond() returned {type(cloud).__name__} for the detection at {_days(t)}, not a "
                          "ParticleCloud or None")
    states = np.asarray(cloud.states)
    if states.ndim != 2 or states.shape[1] != 6 or states.shape[0] == 0:
        raise PluginError(f"{who}: respond() returned a cloud with states of shape {states.shape} for the detection "
                          f"at {_days(t)}; expected (N, 6)")
    bad = int(np.count_nonzero(~np.all(np.isfinite(states), axis=1)))
    if bad:
        raise PluginError(f"{who}: respond() returned a cloud whose states are not all finite ({bad} of "
                          f"{len(states)} hold NaN or inf) for the detection at {_days(t)}")
    if not abs(float(cloud.epoch) - t) <= 1e-9 * max(1.0, abs(t)):
        raise PluginError(f"{who}: respond() returned a cloud at t = {_days(cloud.epoch)}, not at the detection's "
                          f"{_days(t)}")
    return cloud
