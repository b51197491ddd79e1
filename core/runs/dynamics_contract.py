"""What a run holds a third party's dynamics to at every ``propagate`` call, as the conformance
suite does (:mod:`cistrack.testing.checks_dynamics`): a Propagation whose times are the ones asked
for, whose states are finite (K, N, 6) and whose ``alive``, ``impact_body`` and ``impact_time`` are
(N,) each. A model that raises, calls ``sys.exit`` or returns anything else is a
:class:`~cistrack.errors.PluginError` naming it (kind, name, distribution): the run ends "failed",
not blamed on the filter, a metric stage or the orbit ("every particle hit a body").

Built-in models and :class:`~cistrack.propagation.compiled.CompiledDynamics` (whose Propagation
cistrack's own integrator builds) are left as they are: same objects, same speed."""
from __future__ import annotations

import functools
from typing import Any

import numpy as np

from cistrack.errors import CistrackError, PluginError, exception_text
from cistrack.interrupts import plugin_fault
from cistrack.interfaces.component import component_name
from cistrack.interfaces.dynamics import Propagation, check_output_times
from cistrack.plugin.registry import BUILTIN_DISTRIBUTION, Registry

__all__ = ["checked_dynamics", "propagation_fault"]


def checked_dynamics(dynamics: Any, registry: Registry) -> Any:
    """``dynamics`` with its ``propagate`` checked at every call (module docstring) when it is a
    third party's model (not built in, not a CompiledDynamics); the same object either way."""
    from cistrack.propagation.compiled import CompiledDynamics

    name = component_name(dynamics)
    entry = _entry(registry, name)
    if entry is None or entry.distribution == BUILTIN_DISTRIBUTION or isinstance(dynamics, CompiledDynamics):
        return dynamics
    if getattr(dynamics.propagate, "_cistrack_checked", False):
        return dynamics
    try:
        dynamics.propagate = _checking(dynamics.propagate, registry.describe("dynamics", name))
    except AttributeError:  # a class with __slots__: used unchecked, as before
        pass
    return dynamics


def _entry(registry: Registry, name: str) -> Any:
    try:
        return registry.get("dynamics", name)
    except CistrackError:
        return None


def _checking(propagate: Any, who: str) -> Any:
    """``propagate`` raising a PluginError naming ``who`` when it raises or returns what
    :func:`propagation_fault` refuses."""
    @functools.wraps(propagate)
    def checked(states, t0, times, *args, **kwargs):
        try:
            out = propagate(states, t0, times, *args, **kwargs)
        except (CistrackError, MemoryError):
            raise
        except BaseException as exc:  # the plugin's own bug: named, never the filter's
            if not plugin_fault(exc):
                raise
            raise PluginError(f"{who}: propagate() raised {exception_text(exc)}") from exc
        fault = propagation_fault(out, np.shape(states), t0, times)
        if fault:
            raise PluginError(f"{who}: propagate() returned {fault}")
        return out

    checked._cistrack_checked = True  # type: ignore[attr-defined]
    return checked


def propagation_fault(p: Any, shape: tuple, t0: Any, times: Any) -> str:
    """What is wrong with ``p``, a propagation of states of ``shape`` (N, 6) from ``t0`` to
    ``times`` (TU), in words ("" when nothing)."""
    if not isinstance(p, Propagation):
        return f"{type(p).__name__}, not a cistrack Propagation"
    _, want = check_output_times("propagate", t0, times)
    n = shape[0] if len(shape) == 2 else 1
    got = np.asarray(p.times, dtype=float).reshape(-1)
    if got.shape != want.shape or not np.allclose(got, want, rtol=1e-12, atol=1e-12):
        return f"times {_short(got)}, not the requested {_short(want)} (TU)"
    states = np.asarray(p.states)
    if states.shape != (want.size, n, 6):
        return f"states of shape {states.shape}, expected {(want.size, n, 6)} (times, particles, 6)"
    for name in ("alive", "impact_body", "impact_time"):
        if np.shape(getattr(p, name)) != (n,):
            return f"{name} of shape {np.shape(getattr(p, name))}, expected {(n,)}"
    bad = int(np.count_nonzero(~np.all(np.isfinite(states), axis=(0, 2))))
    if bad:
        return f"NaN or infinite states for {bad} of {n} particles (a particle that hits a body keeps its impact state)"
    return ""


def _short(t: np.ndarray) -> str:
    """Times as a short list: all of up to 4, else the first two and the last."""
    shown = [f"{v:.6g}" for v in t] if t.size <= 4 else [f"{t[0]:.6g}", f"{t[1]:.6g}", "...", f"{t[-1]:.6g}"]
    return "[" + ", ".join(shown) + "]"
