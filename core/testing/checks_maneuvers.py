"""Conformance checks for burn plans (``maneuver-plan``) and maneuver responses (``maneuver-response``).

Both are checked on the reference CR3BP (:class:`cistrack.testing.reference_dynamics.ReferenceCR3BP`,
scipy's integrator) from the 9:2 NRHO's apolune. A plan must return well-formed impulses in the
span asked for, in time order, the same ones each time. A response is handed a detection whose
suspect interval is the last 0.2 TU (about 21 hours) and a Gaussian prior of 400 particles; it
must return None or a finite cloud of the prior's dimension at the detection's time, draw only from
the generator it is given (the same seed, the same cloud), leave the prior unchanged, and never
narrow the prior: a burn it allows for can only add spread. The checks call ``respond`` with the
four arguments, without a history; a response that asks for one (``needs_history = True``) must
take the keyword ``history`` and work without it (a response that refits the measurements of its
history may narrow the prior where they allow it, which these checks do not see).
"""
from __future__ import annotations

import inspect

import numpy as np

from cistrack.interfaces.maneuvers import Detection, Impulse, ManeuverPlan, ManeuverResponse
from cistrack.model.belief import Belief, GaussianMixture, ParticleCloud
from cistrack.testing.check_support import fresh, no_global_random_state, require, unchanged
from cistrack.testing.fixtures import NRHO_9_2_APOLUNE
from cistrack.testing.reference_dynamics import ReferenceCR3BP
from cistrack.units import days_to_tu, km_to_lu, kms_to_vu

__all__ = ["MANEUVER_PLAN_CHECKS", "MANEUVER_RESPONSE_CHECKS"]

_SPAN_DAYS = 14.0
_T_DETECT = 1.0
_SIGMAS = np.array([km_to_lu(10.0)] * 3 + [kms_to_vu(1e-4)] * 3)


def _impulses(c) -> list:
    t_end = float(days_to_tu(_SPAN_DAYS))
    with no_global_random_state("impulses"), unchanged(x0=NRHO_9_2_APOLUNE):
        out = c.impulses(ReferenceCR3BP(), NRHO_9_2_APOLUNE.copy(), 0.0, t_end)
    require(isinstance(out, list), f"impulses() must return a list of Impulse, got {type(out).__name__}")
    return out


def check_is_maneuver_plan(c) -> None:
    require(isinstance(c, ManeuverPlan), f"{type(c).__name__} does not derive from cistrack.interfaces.maneuvers.ManeuverPlan")


def check_impulses_are_well_formed_and_in_order(c) -> None:
    """Each an :class:`Impulse` with a finite (3,) dv, its time in (t0, t_end], sorted by time."""
    out = _impulses(c)
    t_end = float(days_to_tu(_SPAN_DAYS))
    for k, imp in enumerate(out):
        require(isinstance(imp, Impulse), f"impulse {k} is a {type(imp).__name__}, not cistrack.interfaces.maneuvers.Impulse")
        require(0.0 < imp.t <= t_end, f"impulse {k} at t = {imp.t} TU lies outside the span (0, {t_end:.4f}] asked for")
    times = [imp.t for imp in out]
    require(times == sorted(times), f"impulses must be in time order, got times {times}")


def check_plan_is_deterministic(c) -> None:
    """The same impulses from two fresh instances."""
    a, b = _impulses(c), _impulses(fresh(c))
    same = len(a) == len(b) and all(x.t == y.t and np.array_equal(x.dv, y.dv) for x, y in zip(a, b))
    require(same, "two instances with the same parameters planned different impulses")


def _prior(seed: int = 3) -> Belief:
    rng = np.random.default_rng(seed)
    t = float(_T_DETECT)
    x = NRHO_9_2_APOLUNE + _SIGMAS * rng.standard_normal((400, 6))
    cov = np.diag(_SIGMAS ** 2)
    return Belief(t, GaussianMixture(np.ones(1), NRHO_9_2_APOLUNE[None].copy(), cov[None]), ParticleCloud(x, t))


def _detection() -> Detection:
    return Detection(t=float(_T_DETECT), statistic=10.0, threshold=4.0, detector="check",
                     t_burn_bounds=(float(_T_DETECT) - 0.2, float(_T_DETECT)))


def _respond(c, seed: int):
    prior = _prior()
    with no_global_random_state("respond"), unchanged(states=prior.samples.states, means=prior.mixture.means):
        return c.respond(_detection(), prior, ReferenceCR3BP(), np.random.default_rng(seed)), prior


def check_is_maneuver_response(c) -> None:
    require(isinstance(c, ManeuverResponse),
            f"{type(c).__name__} does not derive from cistrack.interfaces.maneuvers.ManeuverResponse")


def check_response_is_a_cloud_at_the_detection(c) -> None:
    """None, or a ParticleCloud of finite (N >= 2, 6) states at the detection's time."""
    cloud, _ = _respond(c, 1)
    if cloud is None:
        return
    require(isinstance(cloud, ParticleCloud), f"respond() returned {type(cloud).__name__}; expected a ParticleCloud or None")
    s = np.asarray(cloud.states)
    require(s.ndim == 2 and s.shape[1] == 6 and s.shape[0] >= 2 and np.all(np.isfinite(s)),
            f"the response's cloud must hold finite (N >= 2, 6) states, got shape {s.shape}")
    require(cloud.epoch == _T_DETECT, f"the cloud's epoch {cloud.epoch} is not the detection's time {_T_DETECT}")


def check_response_draws_from_its_generator(c) -> None:
    """The same seed gives the same cloud."""
    a, _ = _respond(c, 7)
    b, _ = _respond(fresh(c), 7)
    if a is None or b is None:
        require(a is None and b is None, "one call returned a cloud and the other None for the same inputs")
        return
    require(np.array_equal(a.states, b.states), "the same inputs and seed gave different clouds: draw only from the rng given")


def check_response_never_narrows_the_prior(c) -> None:
    """The cloud's covariance minus the prior's has no negative eigenvalue beyond sampling noise."""
    cloud, prior = _respond(c, 5)
    if cloud is None:
        return
    scale = np.diag(1.0 / _SIGMAS)
    before = scale @ np.cov(prior.samples.states, rowvar=False) @ scale
    after = scale @ np.cov(np.asarray(cloud.states), rowvar=False) @ scale
    low = float(np.min(np.linalg.eigvalsh(after - before)))
    require(low > -0.5, f"the response narrows the prior (smallest eigenvalue of the change of the whitened covariance "
            f"{low:.3f}); a burn it allows for can only add spread")


def check_response_takes_the_history_it_asks_for(c) -> None:
    """``needs_history`` is a bool; when True, ``respond`` takes the keyword ``history``."""
    flag = getattr(c, "needs_history", False)
    require(isinstance(flag, bool), f"needs_history must be True or False, got {flag!r}")
    if not flag:
        return
    params = inspect.signature(c.respond).parameters.values()
    require(any(p.name == "history" or p.kind is inspect.Parameter.VAR_KEYWORD for p in params),
            "needs_history is True but respond() takes no keyword 'history': the run passes "
            "respond(detection, prior, dynamics, rng, history=ResponseHistory(...))")


MANEUVER_PLAN_CHECKS = [("is_maneuver_plan", check_is_maneuver_plan),
                        ("impulses_are_well_formed_and_in_order", check_impulses_are_well_formed_and_in_order),
                        ("plan_is_deterministic", check_plan_is_deterministic)]
MANEUVER_RESPONSE_CHECKS = [("is_maneuver_response", check_is_maneuver_response),
                            ("response_is_a_cloud_at_the_detection", check_response_is_a_cloud_at_the_detection),
                            ("response_draws_from_its_generator", check_response_draws_from_its_generator),
                            ("response_never_narrows_the_prior", check_response_never_narrows_the_prior),
                            ("response_takes_the_history_it_asks_for", check_response_takes_the_history_it_asks_for)]
