"""Conformance checks for Dynamics plugins (states near the 9:2 NRHO, minutes to hours)."""
from __future__ import annotations

import numpy as np

from cistrack.errors import CistrackError
from cistrack.interfaces.dynamics import Dynamics, Propagation
from cistrack.units import hours_to_tu, km_to_lu, kms_to_vu
from cistrack.testing.check_support import (close, describe_exception, no_global_random_state, require, round_trip, unchanged)
from cistrack.testing.fixtures import nrho_states

__all__ = ["DYNAMICS_CHECKS"]

SHORT_TU = float(hours_to_tu(6.0))
"""Propagation span of the checks: 6 hours."""
VECTOR_RTOL = 1e-10
"""Agreement required between one call on N particles and N calls on one (relative). With
per-particle error control the two are the same computation; a stacked integrator whose error
norm mixes particles differs at the level of its tolerance."""
VECTOR_ATOL = 1e-12
CONSISTENT_RTOL = 1e-7
"""Agreement required between an intermediate output time and a direct propagation to it
(the step sequences differ, so this is at the level of the integration tolerance)."""
CONSISTENT_ATOL = 1e-9


def _propagate(dyn: Dynamics, x: np.ndarray, t0: float, times) -> Propagation:
    p = dyn.propagate(x, t0, times)
    require(isinstance(p, Propagation), f"propagate() returned {type(p).__name__}, not cistrack.interfaces.Propagation")
    states = np.asarray(p.states)
    if not (np.issubdtype(states.dtype, np.number) and np.all(np.isfinite(states))):
        bad = np.size(states) - int(np.count_nonzero(np.isfinite(states))) if np.issubdtype(states.dtype, np.number) else "some"
        require(False, f"propagate() returned NaN or infinite states ({bad} of {np.size(states)} values) for {len(x)} "
                       f"finite states on the 9:2 NRHO from t0 = {t0:g} TU; an impacting particle keeps its impact state")
    return p


def check_is_dynamics(dyn) -> None:
    require(isinstance(dyn, Dynamics), f"{type(dyn).__name__} does not derive from cistrack.interfaces.Dynamics")
    for b in dyn.bodies:
        require(np.shape(b.position) == (3,) and float(b.radius) > 0,
                f"body {b.name!r}: position must be (3,) LU and radius > 0 LU")
        require(float(b.radius) < 0.1, f"body {b.name!r} has radius {b.radius} LU (> 38,000 km): is it in km instead of LU?")


def check_derivatives_shape_and_units(dyn) -> None:
    """derivatives(t, (N,6)) -> (N,6) finite; d(position)/dt is the velocity; accelerations
    are nondimensional (order 1 near the Moon, not km/s²)."""
    x = nrho_states(5)
    d = np.asarray(dyn.derivatives(0.0, x))
    require(d.shape == x.shape, f"derivatives() returned shape {d.shape} for states {x.shape}")
    require(np.issubdtype(d.dtype, np.floating), f"derivatives() returned dtype {d.dtype}, expected float")
    require(np.all(np.isfinite(d)), "derivatives() returned NaN or infinity near the 9:2 NRHO")
    ok, diff = close(d[:, :3], x[:, 3:], 1e-12, 1e-14)
    require(ok, f"derivatives()[:, :3] must equal the velocities states[:, 3:] (differ by {diff:.3g})")
    acc = np.linalg.norm(d[:, 3:], axis=1)
    require(np.all((acc > 1e-4) & (acc < 1e2)),
            f"accelerations {acc} VU/TU near the NRHO are not of order 1: use nondimensional units (LU, VU, TU)")


def check_derivatives_vectorised_matches_loop(dyn) -> None:
    x = nrho_states(5)
    whole = np.asarray(dyn.derivatives(0.1, x))
    rows = np.concatenate([np.asarray(dyn.derivatives(0.1, x[i:i + 1])) for i in range(len(x))])
    ok, diff = close(whole, rows, 1e-12, 1e-14)
    require(ok, f"derivatives() on {len(x)} states differs from one state at a time by {diff:.3g}")


def check_propagate_shapes(dyn) -> None:
    """Propagation fields have the documented shapes and dtypes, for (K,) and scalar times."""
    x = nrho_states(4)
    times = np.array([0.3, 0.6, 1.0]) * SHORT_TU
    p = _propagate(dyn, x, 0.0, times)
    n = x.shape[0]
    require(np.shape(p.states) == (3, n, 6), f"states has shape {np.shape(p.states)}, expected (K, N, 6) = (3, {n}, 6)")
    require(np.shape(p.times) == (3,), f"times has shape {np.shape(p.times)}, expected (3,)")
    ok, _ = close(p.times, times, 0, 1e-14)
    require(ok, f"Propagation.times {p.times} differ from the requested {times}")
    require(np.all(np.isfinite(p.states)), "propagated states contain NaN or infinity")
    require(np.shape(p.alive) == (n,) and np.asarray(p.alive).dtype == bool, "alive must be a (N,) bool array")
    require(np.shape(p.impact_body) == (n,) and np.issubdtype(np.asarray(p.impact_body).dtype, np.integer),
            "impact_body must be a (N,) integer array")
    require(np.shape(p.impact_time) == (n,), "impact_time must be a (N,) float array")
    require(np.all(p.alive) and np.all(np.asarray(p.impact_body) == -1) and np.all(np.isinf(p.impact_time)),
            "particles on the NRHO were reported as impacting within 6 hours")
    p1 = _propagate(dyn, x, 0.0, SHORT_TU)
    require(np.shape(p1.states) == (1, n, 6), f"a scalar time gave states of shape {np.shape(p1.states)}, expected (1, N, 6)")


def check_propagate_vectorised_matches_loop(dyn) -> None:
    """Each particle's result does not depend on the others (per-particle error control)."""
    x = nrho_states(12)
    whole = _propagate(dyn, x, 0.0, SHORT_TU).final
    rows = np.concatenate([_propagate(dyn, x[i:i + 1], 0.0, SHORT_TU).final for i in range(len(x))])
    ok, diff = close(whole, rows, VECTOR_RTOL, VECTOR_ATOL)
    require(ok, f"propagating {len(x)} states together differs from one at a time by {diff:.3g} (LU/VU); "
                "control the error of each particle separately (a stacked solve_ivp loosens it)")


def check_output_times_consistent(dyn) -> None:
    """The state at an intermediate output time equals propagating to that time alone."""
    x = nrho_states(3)
    p = _propagate(dyn, x, 0.0, [0.5 * SHORT_TU, SHORT_TU])
    q = _propagate(dyn, x, 0.0, 0.5 * SHORT_TU)
    ok, diff = close(p.states[0], q.final, CONSISTENT_RTOL, CONSISTENT_ATOL)
    require(ok, f"state at an intermediate output time differs from a direct propagation by {diff:.3g}")


def check_propagates_backward(dyn) -> None:
    """Forward then backward propagation returns to the initial states; t0 need not be 0."""
    x = nrho_states(3)
    t0 = 0.25
    fwd = _propagate(dyn, x, t0, t0 + SHORT_TU).final
    back = _propagate(dyn, fwd, t0 + SHORT_TU, t0).final
    ok, diff = close(back, x, 1e-6, 1e-8)
    require(ok, f"propagating forward and back by 6 h misses the initial states by {diff:.3g} LU/VU")


def check_reports_impacts(dyn) -> None:
    """A particle falling onto a body is reported (alive False, body index, time) with a
    finite state, never NaN; a particle beside it is unaffected."""
    bodies = dyn.bodies
    if not bodies:
        return
    for i, b in enumerate(bodies):
        pos = np.asarray(b.position, dtype=float) + np.array([0.0, 0.0, b.radius + km_to_lu(300.0)])
        falling = np.concatenate([pos, [0.0, 0.0, -kms_to_vu(3.0)]])
        x = np.stack([falling, nrho_states(1)[0]])
        t_end = float(hours_to_tu(1.0))
        p = _propagate(dyn, x, 0.0, [0.5 * t_end, t_end])
        require(np.all(np.isfinite(p.states)), f"a particle hitting the {b.name} produced NaN or infinite states")
        require(not bool(p.alive[0]), f"a particle falling onto the {b.name} from 300 km at 3 km/s is still alive after 1 h")
        require(int(p.impact_body[0]) == i, f"impact on the {b.name} reported as body index {p.impact_body[0]}, expected {i}")
        require(0.0 < float(p.impact_time[0]) <= t_end, f"impact time {p.impact_time[0]} TU is outside (0, {t_end:.4g}]")
        require(bool(p.alive[1]) and int(p.impact_body[1]) == -1, "a particle on the NRHO was reported as impacting")


def check_inputs_not_mutated(dyn) -> None:
    x = nrho_states(3)
    times = np.array([0.5, 1.0]) * SHORT_TU
    with unchanged(states=x, times=times):
        dyn.derivatives(0.0, x)
        dyn.propagate(x, 0.0, times)


def check_deterministic(dyn) -> None:
    """Two propagations give the same answer, and no global random state is used."""
    x = nrho_states(3)
    with no_global_random_state("propagate()"):
        a = _propagate(dyn, x, 0.0, SHORT_TU).final
    b = _propagate(dyn, x, 0.0, SHORT_TU).final
    ok, diff = close(a, b, 1e-12, 0)
    require(ok, f"two identical propagations differ by {diff:.3g}")


def check_same_after_pickle(dyn) -> None:
    x = nrho_states(3)
    other = round_trip(dyn)
    a = _propagate(dyn, x, 0.0, SHORT_TU).final
    b = _propagate(other, x, 0.0, SHORT_TU).final
    ok, diff = close(a, b, 1e-12, 0)
    require(ok, f"the unpickled copy propagates differently (by {diff:.3g})")


def check_rejects_malformed_states(dyn) -> None:
    """States of the wrong shape or containing NaN raise a cistrack error, not a numpy one."""
    bad = {"shape (3, 5)": np.zeros((3, 5)), "a NaN": np.where(np.arange(6) == 2, np.nan, nrho_states(1)[0])[None]}
    for what, x in bad.items():
        try:
            dyn.propagate(x, 0.0, SHORT_TU)
        except CistrackError:
            continue
        except Exception as exc:
            require(False, f"propagate() with states of {what} raised {describe_exception(exc)}; raise a "
                           "cistrack.errors error (e.g. ParameterError) that says what is wrong")
        require(False, f"propagate() accepted states with {what}")


SENSITIVITY_TU = float(hours_to_tu(48.0))
"""Span of the sensitivity check: 2 days (a radiation pressure moves an orbit about 60 km per m^2/kg)."""
SENSITIVITY_RTOL = 1e-3
"""Agreement required between an integrated sensitivity and a central difference of the parameter
(relative to its largest component: the difference's own error, truncation and the integration's
tolerance over twice its step, is of order 1e-5 of it)."""


def check_transition_matrices_finite(dyn) -> None:
    """``propagate_with_stm(state (6,), t0, times (K,))`` (what ``cistrack fit`` calls) gives finite
    states (K, 6) and transition matrices (K, 6, 6)."""
    times = np.array([0.5, 1.0]) * SHORT_TU
    states, stms = dyn.propagate_with_stm(nrho_states(1)[0], 0.0, times)
    require(np.shape(states) == (2, 6) and np.shape(stms) == (2, 6, 6),
            f"propagate_with_stm returned states of shape {np.shape(states)} and matrices of shape {np.shape(stms)}, "
            "expected (K, 6) and (K, 6, 6) = (2, 6) and (2, 6, 6)")
    require(np.all(np.isfinite(states)) and np.all(np.isfinite(stms)),
            "propagate_with_stm returned NaN or infinite states or transition matrices on the 9:2 NRHO over 6 hours")


def check_sensitivities_match_differences(dyn) -> None:
    """Each of ``sensitivity_parameters``: ``propagate_with_sensitivity``'s d x / d p against a
    central difference of ``propagate`` with the parameter moved by ``with_parameters``."""
    x = nrho_states(1)[0]
    times = np.linspace(SENSITIVITY_TU / 4.0, SENSITIVITY_TU, 4)
    for name in tuple(getattr(dyn, "sensitivity_parameters", ())):
        p0 = float(dyn.parameter(name))
        h = 1e-4 * max(1.0, abs(p0))
        _, _, sens = dyn.propagate_with_sensitivity(x, 0.0, times, name)
        up, down = (_propagate(dyn.with_parameters(**{name: p0 + s * h}), x[None], 0.0, times).states[:, 0]
                    for s in (1.0, -1.0))
        want = (up - down) / (2.0 * h)
        scale = float(np.abs(want).max())
        ok, diff = close(np.asarray(sens, dtype=float), want, 0.0, SENSITIVITY_RTOL * scale)
        require(np.shape(sens) == (times.size, 6) and ok,
                f"propagate_with_sensitivity of {name!r} differs from a central difference of step {h:g} by "
                f"{diff:.3g} (largest component {scale:.3g})")


DYNAMICS_CHECKS = [
    ("is_dynamics", check_is_dynamics),
    ("derivatives_shape_and_units", check_derivatives_shape_and_units),
    ("derivatives_vectorised_matches_loop", check_derivatives_vectorised_matches_loop),
    ("propagate_shapes", check_propagate_shapes),
    ("propagate_vectorised_matches_loop", check_propagate_vectorised_matches_loop),
    ("output_times_consistent", check_output_times_consistent),
    ("propagates_backward", check_propagates_backward),
    ("reports_impacts", check_reports_impacts),
    ("inputs_not_mutated", check_inputs_not_mutated),
    ("deterministic", check_deterministic),
    ("same_after_pickle", check_same_after_pickle),
    ("rejects_malformed_states", check_rejects_malformed_states),
    ("transition_matrices_finite", check_transition_matrices_finite),
    ("sensitivities_match_differences", check_sensitivities_match_differences),
]
