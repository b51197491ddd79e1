"""Batch least-squares differential correction of an orbit over an arc of measurements.

Unknown: the state x (6,) at the epoch t0 (synodic LU, VU). With r_i = O - C the residual of
observation i (angles wrapped), W = diag(1/sigma^2) and H_i = (d h / d x)(x(t_i)) Phi(t_i, t0) the
measurement Jacobian chained with the state transition matrix, each iteration solves the damped
normal equations

    (N + lambda diag N) dx = g,   N = sum_i H_i^T W H_i + P0^-1,   g = sum_i H_i^T W r_i + P0^-1 (x0 - x)

(Levenberg-Marquardt; lambda -> 0 is Gauss-Newton; P0, x0 an optional prior) and accepts the step
when the cost sum_i r_i^T W r_i + (x - x0)^T P0^-1 (x - x0) decreases. Convergence: the
Gauss-Newton step is below ``step_tolerance`` sigma, or an accepted step changes the weighted RMS
by less than ``rms_tolerance``. Outliers are rejected and readmitted between passes
(:mod:`cistrack.least_squares.outliers`). The covariance is N^-1 at the estimate.

Residuals are computed from the dynamics' ``propagate`` (the same propagation that simulates
measurements), Jacobians from its ``propagate_with_stm``; an approximate STM only slows the
convergence, the fixed point is the least-squares solution of the model ``propagate`` defines.
"""
from __future__ import annotations

import math
import warnings
from dataclasses import dataclass
from typing import Any, NamedTuple

import numpy as np

from cistrack.astro.kept_by_time import kept_or_evaluated
from cistrack.errors import MeasurementError, PropagationError, StateError
from cistrack.least_squares.errors import FitError, UnobservableWarning
from cistrack.least_squares.measurement_model import MeasurementModel
from cistrack.least_squares.observability import condition_text, observability
from cistrack.least_squares.options import FitOptions
from cistrack.least_squares.outliers import update_rejections
from cistrack.least_squares.progress import tell
from cistrack.least_squares.residual_table import residual_table
from cistrack.least_squares.result import FitResult, noise_scale_text
from cistrack.least_squares.impulse_partials import delta_v_state_partials, impulse_columns
from cistrack.least_squares.solve_for_parameters import SolveFor, solve_for as _solve_for
from cistrack.least_squares.options import AREA_TO_MASS
from cistrack.least_squares.trajectory import arc_states, arc_states_and_stms, arc_states_stms_and_sensitivity
from cistrack.interfaces.dynamics import Dynamics
from cistrack.interfaces.sensor import Sensor
from cistrack.model.measurement import MeasurementSet

__all__ = ["fit_orbit", "whitened_jacobian"]


def _check_state(state: Any, name: str) -> np.ndarray:
    try:
        x = np.asarray(state, dtype=float).reshape(-1)
    except (TypeError, ValueError) as exc:
        raise StateError(f"fit: {name} must be 6 numbers (LU, VU): {exc}") from None
    if x.shape != (6,):
        raise StateError(f"fit: {name} must have shape (6,) (synodic LU, VU), got {np.shape(state)}")
    if not np.all(np.isfinite(x)):
        raise StateError(f"fit: {name} contains NaN or infinity: {x}")
    return x


def _check_prior(prior: Any) -> tuple[np.ndarray, np.ndarray] | None:
    if prior is None:
        return None
    try:
        mean, cov = prior
    except (TypeError, ValueError):
        raise StateError("fit: prior must be a pair (mean (6,), covariance (6, 6)) in LU, VU") from None
    mean = _check_state(mean, "the prior mean")
    cov = np.asarray(cov, dtype=float)
    if cov.shape != (6, 6) or not np.all(np.isfinite(cov)):
        raise StateError(f"fit: the prior covariance must be a finite (6, 6) matrix, got shape {cov.shape}")
    if not np.allclose(cov, cov.T, rtol=1e-10, atol=0.0):
        raise StateError("fit: the prior covariance is not symmetric")
    try:
        np.linalg.cholesky(cov)
    except np.linalg.LinAlgError:
        raise StateError("fit: the prior covariance is not positive definite") from None
    return mean, np.linalg.inv(cov)


_KEPT_POINTS = 4
"""Points whose residuals and Jacobian a fit keeps (:meth:`_Problem._kept_or_computed`)."""


class _Problem:
    """Residuals, cost and normal equations of one fit. The unknowns x are the state (6,) and,
    with ``solve_for``, its parameters after it (6 + P,)."""

    def __init__(self, dynamics: Dynamics, model: MeasurementModel, t0: float,
                 prior: tuple[np.ndarray, np.ndarray] | None, solve_for: SolveFor | None = None) -> None:
        self.dynamics, self.model, self.t0, self.prior = dynamics, model, t0, prior
        self.solve_for = solve_for
        self.n = 6 + (0 if solve_for is None else solve_for.size)
        self._kept: dict[str, dict[bytes, tuple[np.ndarray, ...]]] = {"evaluate": {}, "jacobian": {}}

    def _kept_or_computed(self, what: str, x: np.ndarray, compute) -> tuple[np.ndarray, ...]:
        """``compute()`` at the unknowns ``x``, kept for the next request at the same ``x`` (bit for
        bit: the passes, their starts and the estimate ask again where an earlier step ended; the
        propagation and the sensor give the same numbers again). ``compute`` returns new arrays; the
        caller gets copies of the kept ones. At most 4 points each."""
        hit = kept_or_evaluated(self._kept[what], np.asarray(x, dtype=float).tobytes(), _KEPT_POINTS, compute)
        return tuple(a.copy() for a in hit)

    def _dynamics(self, x: np.ndarray) -> Dynamics:
        return self.dynamics if self.solve_for is None else self.solve_for.dynamics(x[6:])

    def evaluate(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(weighted residuals (K, m), states (K, 6)) at the unknowns x."""
        def compute() -> tuple[np.ndarray, np.ndarray]:
            states = arc_states(self._dynamics(x), x[:6], self.t0, self.model.times)
            return self.model.residuals(states) / self.model.sigmas, states

        w, states = self._kept_or_computed("evaluate", x, compute)
        return w, states

    def cost(self, w: np.ndarray, x: np.ndarray, used: np.ndarray) -> float:
        c = float(np.sum(w[used] ** 2))
        if self.prior is not None:
            e = x[:6] - self.prior[0]
            c += float(e @ self.prior[1] @ e)
        return c

    def jacobian(self, x: np.ndarray) -> np.ndarray:
        """Weighted d r / d x (K, m, 6 + P): H(x(t_i)) Phi(t_i, t0) / sigma, then the parameters'
        central differences (:mod:`cistrack.least_squares.solve_for_parameters`) / sigma."""
        return self._kept_or_computed("jacobian", x, lambda: (self._jacobian(x),))[0]

    def _jacobian(self, x: np.ndarray) -> np.ndarray:
        """The state's columns from the transition matrices; a burn's delta-v from them too
        (:mod:`cistrack.least_squares.impulse_partials`, the burn times among the outputs); a
        parameter whose sensitivity the model integrates with them (its ``sensitivity_parameters``:
        the ephemeris model's radiation pressure) from that; every other parameter by central
        differences."""
        dyn, k = self._dynamics(x), self.model.times.size
        burns = {} if self.solve_for is None else impulse_columns(dyn, self.solve_for.names)
        burn_t = np.array(sorted({tb for tb, _ in burns.values()}))
        rest = [] if self.solve_for is None else [j for j in range(self.solve_for.size) if j not in burns]
        known = set(getattr(dyn, "sensitivity_parameters", ()))
        integrated = next((j for j in rest if self.solve_for.names[j] in known), None)
        times = np.concatenate([self.model.times, burn_t])
        if integrated is None:
            states, stms = arc_states_and_stms(dyn, x[:6], self.t0, times)
        else:
            states, stms, sens = arc_states_stms_and_sensitivity(dyn, x[:6], self.t0, times,
                                                                 self.solve_for.names[integrated])
        h = self.model.jacobian(states[:k])
        a = np.einsum("kmj,kjl->kml", h, stms[:k]) / self.model.sigmas[:, :, None]
        if self.solve_for is None:
            return a
        dp = np.empty(a.shape[:2] + (self.solve_for.size,))
        rest = [j for j in rest if j != integrated]
        if rest:
            def predicted(dyn: Dynamics) -> np.ndarray:  # minus the residuals: wrapped like them
                return -self.model.residuals(arc_states(dyn, x[:6], self.t0, self.model.times))

            dp[:, :, rest] = self.solve_for.partials(predicted, x[6:], only=rest)
        if integrated is not None:
            dp[:, :, integrated] = np.einsum("kmj,kj->km", h, sens[:k])
        if burns:
            dx = delta_v_state_partials(self.model.times, self.t0, stms[:k], dict(zip(burn_t.tolist(), stms[k:])), burns)
            dp[:, :, list(burns)] = np.einsum("kmj,kjp->kmp", h, dx)
        return np.concatenate([a, dp / self.model.sigmas[:, :, None]], axis=2)

    def normal(self, a: np.ndarray, w: np.ndarray, x: np.ndarray, used: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Normal matrix (6 + P, 6 + P) and right-hand side (6 + P,) over the used rows."""
        au = a[used].reshape(-1, self.n)
        n = au.T @ au
        g = au.T @ w[used].reshape(-1)
        if self.prior is not None and self.n == 6:
            n = n + self.prior[1]
            g = g + self.prior[1] @ (self.prior[0] - x)
        elif self.prior is not None:  # the prior bounds the state only
            n[:6, :6] += self.prior[1]
            g[:6] += self.prior[1] @ (self.prior[0] - x[:6])
        return 0.5 * (n + n.T), g


def whitened_jacobian(dynamics: Dynamics, model: MeasurementModel, state: np.ndarray, t0: float,
                      names: tuple[str, ...] = (), values: Any = ()) -> np.ndarray:
    """The fit's own Jacobian (K, m, 6 + P) at the ``state`` (6,) at ``t0`` (TU) with the solve-for
    parameters ``names`` at ``values`` (P,): d h / d (state, parameters) over the rows of ``model``,
    each divided by its sigma (a burn's delta-v columns from the transition matrices, like the
    fit's)."""
    x = np.concatenate([np.asarray(state, dtype=float), np.asarray(values, dtype=float).reshape(-1)])
    return _Problem(dynamics, model, t0, None, _solve_for(dynamics, names)).jacobian(x)


def _diagonal_scale(n: np.ndarray) -> np.ndarray:
    """sqrt(diag N), with 1 where a coordinate has no information (diagonal <= 0)."""
    diag = np.diag(n)
    return np.where(diag > 0, np.sqrt(np.abs(diag)), 1.0)


def _solve(n: np.ndarray, g: np.ndarray, lam: float) -> np.ndarray:
    """(N + lam diag N)^-1 g, in unit-diagonal scaling; raises LinAlgError when singular."""
    d = _diagonal_scale(n)
    ns = n / np.outer(d, d) + lam * np.eye(n.shape[0])
    return np.linalg.solve(ns, g / d) / d


def _step_size(n: np.ndarray, dx: np.ndarray) -> float:
    return float(np.sqrt(max(dx @ n @ dx, 0.0)))


def _stalled(say: list[str], gn_size: float, opts: FitOptions) -> bool:
    """Whether a pass whose damped steps no longer lower the cost has converged (its Gauss-Newton
    step, in sigmas, under ``opts.stall_step``: the cost's numerical floor); says so in ``say``."""
    ok = gn_size < opts.stall_step
    say.append(f"the cost stopped decreasing with a Gauss-Newton step of {gn_size:.3g} sigma"
               + (" (numerical floor: converged)" if ok else " (not converged)"))
    return ok


def _one_pass(prob: _Problem, x: np.ndarray, used: np.ndarray, opts: FitOptions,
              say: list[str]) -> tuple[np.ndarray, int, bool]:
    """Levenberg-Marquardt with a fixed set of used rows: (state, iterations, converged)."""
    w, _ = prob.evaluate(x)
    cost = prob.cost(w, x, used)
    a = prob.jacobian(x)
    lam = opts.damping
    its = 0
    small_change = False  # the last accepted step changed the weighted RMS by < rms_tolerance
    while its < opts.max_iterations:
        n, g = prob.normal(a, w, x, used)
        try:
            gn = _solve(n, g, 0.0)
            gn_size = _step_size(n, gn)
        except np.linalg.LinAlgError:
            gn, gn_size = None, np.inf
        if gn is not None and (gn_size < opts.step_tolerance or small_change):
            its += 1
            try:  # the last Gauss-Newton step: take it when it does not raise the cost
                w_new, _ = prob.evaluate(x + gn)
                if prob.cost(w_new, x + gn, used) <= cost:
                    x = x + gn
            except (PropagationError, MeasurementError):
                pass
            return x, its, True
        accepted = False
        while not accepted:
            try:
                dx = _solve(n, g, lam)
            except np.linalg.LinAlgError:
                dx = None
            its += 1
            new_cost = np.inf
            if dx is not None and np.all(np.isfinite(dx)):
                try:
                    w_new, _ = prob.evaluate(x + dx)
                    new_cost = prob.cost(w_new, x + dx, used)
                except (PropagationError, MeasurementError):
                    new_cost = np.inf
            if new_cost < cost:
                accepted = True
                rel = (cost - new_cost) / max(cost, 1e-300)
                x, w, cost = x + dx, w_new, new_cost
                tell(len(prob.model.times), f"    least squares iteration {its}: chi-square {cost:.6g} over "
                                            f"{int(np.sum(used))} observations")
                lam_was = lam
                lam = max(lam / opts.damping_factor, 1e-12)
                small_change = lam_was <= opts.damping and 0.5 * rel < opts.rms_tolerance
                a = prob.jacobian(x)
            elif gn_size < opts.stall_step:  # at the numerical floor: more damping only shortens the step
                return x, its, _stalled(say, gn_size, opts)
            else:
                lam *= opts.damping_factor
                if lam > opts.max_damping:
                    return x, its, _stalled(say, gn_size, opts)
                if its >= opts.max_iterations:
                    break
    say.append(f"no convergence within {opts.max_iterations} iterations")
    return x, its, False


@dataclass
class _Passes:
    """Where the fit-then-reject passes ended: the state (6,) LU, VU, the rejected rows (K,) bool,
    the last chi-square threshold, the iterations of all passes and whether they converged."""

    x: np.ndarray
    rejected: np.ndarray
    threshold: float = float("inf")
    iterations: int = 0
    converged: bool = False


def _checked_inputs(state: Any, t0: Any, prior: Any, options: Any
                    ) -> tuple[FitOptions, np.ndarray, float, tuple[np.ndarray, np.ndarray] | None]:
    """(options, state (6,), epoch TU, (prior mean (6,), inverse prior covariance (6, 6)) or None),
    checked in that order; raises StateError."""
    opts = FitOptions() if options is None else options
    if not isinstance(opts, FitOptions):
        raise StateError(f"fit: options must be a FitOptions, got {type(opts).__name__}")
    x = _check_state(state, "the initial state")
    try:
        t0 = float(t0)
    except (TypeError, ValueError):
        raise StateError(f"fit: the epoch t0 must be a number (TU), got {t0!r}") from None
    if not np.isfinite(t0):
        raise StateError(f"fit: the epoch t0 must be finite, got {t0}")
    return opts, x, t0, _check_prior(prior)


def _problem(dynamics: Dynamics, model: MeasurementModel, x: np.ndarray, t0: float,
             prior: tuple[np.ndarray, np.ndarray] | None, params: SolveFor | None = None) -> _Problem:
    """The fit's problem, once there are enough numbers for the unknowns and the initial unknowns
    ``x`` (6 + P,) propagate over the arc; raises FitError."""
    k, m = len(model.times), model.m
    unknowns = 6 + (0 if params is None else params.size)
    if prior is None and k * m < unknowns:
        raise FitError(f"fit: {k} observation(s) of {m} component(s) give {k * m} numbers for {unknowns} "
                       "unknowns; add observations or a prior")
    prob = _Problem(dynamics, model, t0, prior, params)
    try:
        prob.evaluate(x)
    except PropagationError as exc:
        raise FitError(f"fit: the initial state cannot be propagated over the arc: {exc}") from exc
    return prob


def _say_pass(say: list[str], n_pass: int, new: np.ndarray, rejected: np.ndarray, threshold: float) -> None:
    back = int(np.sum(rejected & ~new))
    say.append(f"pass {n_pass}: {int(np.sum(new & ~rejected))} observation(s) rejected"
               + (f", {back} readmitted" if back else "") + f" (chi-square threshold {threshold:.4g})")


def _pass_start(prob: _Problem, initial: np.ndarray, last: np.ndarray, used: np.ndarray) -> np.ndarray:
    """Where a pass starts: the last pass's estimate, or the fit's initial unknowns when they fit the
    pass's observations better (a lower cost over its used rows). A start that is already the orbit
    of the clean observations (the ranging IOD's, fitted with its outliers rejected) is pulled along
    the arc's weakest direction by the outliers the first pass still holds; on an ill-conditioned
    arc (condition number 2.6e11: survey set halo seed 23) Levenberg-Marquardt then needs ~300
    iterations of a curved valley to crawl back once they are rejected, from the start none."""
    if last is initial or np.array_equal(last, initial):
        return last
    try:
        w0, _ = prob.evaluate(initial)
        w1, _ = prob.evaluate(last)
    except (PropagationError, MeasurementError):
        return last
    return initial if prob.cost(w0, initial, used) < prob.cost(w1, last, used) else last


def _fit_passes(prob: _Problem, x: np.ndarray, opts: FitOptions, say: list[str],
                first_out: np.ndarray | None = None) -> _Passes:
    """Fit, reject outliers, refit, until the rejected set settles (at most ``opts.max_passes``);
    the first pass without the ``first_out`` rows (K,) when given and outliers are rejected."""
    k, m = len(prob.model.times), prob.model.m
    seen: list[np.ndarray] = []
    min_rows = 0 if prob.prior is not None else int(np.ceil(prob.n / m))
    start = first_out if first_out is not None and opts.reject_outliers else np.zeros(k, dtype=bool)
    p = _Passes(x, start.copy() if k - int(start.sum()) >= min_rows else np.zeros(k, dtype=bool))
    for _ in range(opts.max_passes):
        p.x = _pass_start(prob, x, p.x, ~p.rejected)
        p.x, its, p.converged = _one_pass(prob, p.x, ~p.rejected, opts, say)
        p.iterations += its
        if not opts.reject_outliers:
            break
        w, _ = prob.evaluate(p.x)
        new, p.threshold = update_rejections(np.sum(w ** 2, axis=1), m, p.rejected, opts.reject_sigma,
                                             opts.robust_threshold, opts.max_reject_fraction)
        if k - int(new.sum()) < min_rows:
            say.append("rejection would leave fewer components than unknowns: the rejected set is kept")
            break
        if np.array_equal(new, p.rejected):
            break
        _say_pass(say, len(seen) + 1, new, p.rejected, p.threshold)
        tell(k, f"    least squares: {say[-1]}; fitting again")
        first = next((i for i, s in enumerate(seen) if np.array_equal(new, s)), None)
        if first is not None:
            _settle_cycle(prob, p, seen[first:] + [p.rejected, new], opts, say)
            break
        seen.append(p.rejected.copy())
        p.rejected = new
    else:
        p.converged = False
        say.append(f"the rejected set did not settle within {opts.max_passes} passes")
    return p


def _settle_cycle(prob: _Problem, p: _Passes, cycle: list[np.ndarray], opts: FitOptions, say: list[str]) -> None:
    """The rejected sets of ``cycle`` repeat: observations at the threshold, rejected in one pass
    (their chi-square just above it) and readmitted in the next (just below it, the fit without
    them). They are kept rejected (the union of the sets, a lower bar for readmission than for
    rejection) and the fit made once more; it converges as that pass does. Survey set nrho seed 208
    had been reported as not converged, RMS 1.06, for one such observation."""
    union = np.logical_or.reduce(cycle)
    moved = int(np.sum(union & ~np.logical_and.reduce(cycle)))
    say.append(f"the rejected set cycles between passes: {moved} observation(s) at the threshold, rejected in "
               "one pass and readmitted in the next, are kept rejected")
    p.rejected = union
    p.x, its, p.converged = _one_pass(prob, p.x, ~p.rejected, opts, say)
    p.iterations += its


def _at_estimate(prob: _Problem, x: np.ndarray, used: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(weighted residuals (K, m), states (K, 6), normal matrix (6, 6)) at the estimate ``x``."""
    try:
        w, states = prob.evaluate(x)
        a = prob.jacobian(x)
    except PropagationError as exc:
        raise FitError(f"fit: the estimate cannot be propagated over the arc: {exc}") from exc
    n, _ = prob.normal(a, w, x, used)
    return w, states, n


def _covariance(n: np.ndarray, obs: Any) -> np.ndarray:
    """N^-1 (6, 6), LU and VU, inverted in unit-diagonal scaling; raises FitError when N is not
    positive definite or the inverse is not finite."""
    try:
        d = _diagonal_scale(n)
        cov = np.linalg.inv(np.linalg.cholesky(n / np.outer(d, d)))
        cov = (cov.T @ cov) / np.outer(d, d)
    except (np.linalg.LinAlgError, FloatingPointError):
        raise FitError(f"fit: the normal matrix is not positive definite ({condition_text(obs.condition)}); the arc does not determine the direction "
                       f"{np.array2string(obs.weakest_direction_km, precision=4)} (km, km/s): "
                       "add observations over a longer arc or a prior") from None
    cov = 0.5 * (cov + cov.T)
    if not np.all(np.isfinite(cov)):
        raise FitError("fit: the covariance is not finite")
    return cov


def _unobservable_text(obs: Any, opts: FitOptions) -> str | None:
    """Why the arc leaves a direction nearly unobservable, or None when it does not."""
    weak_km = float(np.linalg.norm(obs.weakest_direction_km[:3]))
    sized = np.isfinite(obs.condition)   # a singular matrix's direction has no one-sigma size
    ill_conditioned = obs.condition > opts.max_condition and not (sized and weak_km <= opts.min_weak_sigma_km)
    if not (ill_conditioned or weak_km > opts.max_weak_sigma_km):
        return None
    return (f"the arc leaves a direction nearly unobservable: {condition_text(obs.condition)} "
            f"(limit {opts.max_condition:.3g}), one sigma along the weakest direction "
            f"{np.array2string(obs.weakest_direction_km, precision=4)} (km, km/s), {weak_km:.4g} km in "
            f"position (limit {opts.max_weak_sigma_km:.4g} km); observe over a longer arc or add a prior")


def _table(model: MeasurementModel, measurements: MeasurementSet, states: np.ndarray, rejected: np.ndarray):
    """The post-fit residual table of every observation (rad, range LU), rejected ones marked."""
    k = len(measurements)
    return residual_table(model.times, np.array([measurements.site_at(i) for i in range(k)]),
                          np.array([measurements.kind_at(i) for i in range(k)]), model.names,
                          model.values, model.residuals(states), model.sigmas, rejected)


def _goodness(w: np.ndarray, used: np.ndarray, say: list[str], unknowns: int = 6) -> tuple[float, float, float]:
    """(chi-square, weighted RMS, noise scale) of the used rows of the weighted residuals ``w``
    (K, m): the RMS over the used components, the noise scale sqrt(chi2 / (components - unknowns))."""
    n_comp = int(used.sum()) * w.shape[1]
    chi2 = float(np.sum(w[used] ** 2))
    rms = float(np.sqrt(chi2 / n_comp)) if n_comp else float("inf")
    if n_comp > unknowns:
        return chi2, rms, float(np.sqrt(chi2 / (n_comp - unknowns)))
    say.append("no redundancy (as many components as unknowns): noise scale undefined")
    return chi2, rms, float("nan")


def _verdict(p: _Passes, rms: float, noise_scale: float, opts: FitOptions, say: list[str],
             row_chi2: np.ndarray | None = None) -> bool:
    """Whether the fit converged to an orbit that fits (weighted RMS at most ``opts.max_rms``);
    adds the closing messages and puts the summary first. ``row_chi2`` (K,): each observation's
    chi-square at the estimate, to say when the rejection cap kept some above the threshold."""
    converged = p.converged
    if converged and rms > opts.max_rms:
        converged = False
        say.append(f"the orbit does not fit the observations: weighted RMS {rms:.4g} > {opts.max_rms:g} "
                   "(a wrong local minimum from a poor start, or a wrong model or sensor); start closer "
                   "to the truth or check the data")
    if int(p.rejected.sum()):
        at_cap = int(p.rejected.sum()) >= math.floor(opts.max_reject_fraction * len(p.rejected))
        kept = int(np.sum(row_chi2[~p.rejected] > p.threshold)) if at_cap and row_chi2 is not None else 0
        capped = (f"; {kept} more exceed it but are kept: at most {opts.max_reject_fraction:g} of the observations "
                  "are rejected (fit.max_reject_fraction)") if kept else ""
        say.append(f"{int(p.rejected.sum())} of {len(p.rejected)} observations rejected "
                   f"(chi-square > {p.threshold:.4g}{_threshold_origin(opts)}{capped})")
    say.insert(0, ("converged" if converged else "NOT converged") + f" after {p.iterations} iterations; "
               f"weighted RMS {rms:.4g}, noise scale {noise_scale_text(noise_scale)}")
    return converged


LOW_REJECT_SIGMA = 2.0
"""A ``reject_sigma`` below this is said to reject observations that are noise (a share of
2 (1 - Phi(s)) of them exceeds its threshold: 32 % at 1 sigma, 76 % at 0.3)."""


def _threshold_origin(opts: FitOptions) -> str:
    """Words naming ``fit.reject_sigma`` when it is not the default ("" when it is), with the share
    of observations that are pure noise its threshold rejects when it is below
    :data:`LOW_REJECT_SIGMA`."""
    default = FitOptions.reject_sigma
    s = float(opts.reject_sigma)
    if s == default:
        return ""
    words = f", set by fit.reject_sigma = {s:g} (default {default:g})"
    if s < LOW_REJECT_SIGMA:
        noise = 1.0 - math.erf(s / math.sqrt(2.0))
        words += f": {100.0 * noise:.0f} % of observations whose residuals are noise exceed it"
    return words


def _state_information(n: np.ndarray) -> np.ndarray:
    """The state's information (6, 6) with the parameters marginalised: the Schur complement
    N_xx - N_xp N_pp^-1 N_px of the normal matrix (6 + P, 6 + P) (N itself when P = 0)."""
    if n.shape[0] == 6:
        return n
    try:
        s = n[:6, :6] - n[:6, 6:] @ np.linalg.solve(n[6:, 6:], n[6:, :6])
    except np.linalg.LinAlgError:
        s = n[:6, :6]
    return 0.5 * (s + s.T)


def fit_orbit(dynamics: Dynamics, sensor: Sensor, measurements: MeasurementSet, state: Any, t0: float, *,
              prior: tuple[Any, Any] | None = None, options: FitOptions | None = None,
              solve_for: Any = None, rejected: Any = None) -> FitResult:
    """Least-squares orbit from ``measurements``, starting at ``state`` (6,) at epoch ``t0``.

    Parameters
    ----------
    dynamics : Dynamics
        Propagates the orbit (its ``propagate_with_stm`` gives the transition matrices).
    sensor : Sensor
        The sensor (or site network) that took the measurements; predicts them.
    measurements : MeasurementSet
        Times TU since the scenario epoch, values rad (range LU), one-sigma noise per component.
    state : (6,) float
        Initial estimate at ``t0``: synodic LU, VU.
    t0 : float
        Epoch of the estimated state, TU (anywhere in or outside the arc).
    prior : (mean (6,), covariance (6, 6)), optional
        Gaussian prior on the state at ``t0`` (LU, VU), added to the normal equations.
    options : FitOptions, optional
        ``options.area_to_mass`` "solve" estimates the radiation pressure's C_R A/m (m^2/kg) too,
        "auto" where the arc supports it (:mod:`cistrack.least_squares.area_to_mass`).
    solve_for : str or tuple of str, optional
        Names of dynamics parameters estimated with the state, started at the dynamics' own
        values (:mod:`cistrack.least_squares.solve_for_parameters`); adds to ``area_to_mass``.
    rejected : (K,) bool, optional
        Observations left out of the first pass (the outliers of an earlier fit of these
        measurements); the passes after it readmit those that fit. Default: none.

    Returns
    -------
    FitResult. Raises :class:`cistrack.least_squares.FitError` when there are fewer measurement components
    than unknowns (without a prior), when the normal matrix at the estimate is not positive
    definite, or when the orbit cannot be propagated over the arc; :class:`cistrack.errors.StateError`
    and :class:`cistrack.errors.MeasurementError` for malformed input. Warns
    :class:`cistrack.least_squares.UnobservableWarning` when the condition number exceeds
    ``options.max_condition`` (while the weakest direction's one sigma exceeds
    ``options.min_weak_sigma_km``) or that sigma exceeds ``options.max_weak_sigma_km``.
    """
    opts, x, t0, pri = _checked_inputs(state, t0, prior, options)
    first_out = _first_rejected(rejected, len(measurements.times))
    names = () if solve_for is None else ((solve_for,) if isinstance(solve_for, str) else tuple(solve_for))
    if opts.area_to_mass == "auto":
        from cistrack.least_squares.area_to_mass import fit_area_to_mass_auto

        def fit(start: np.ndarray, options: FitOptions) -> FitResult:
            return fit_orbit(dynamics, sensor, measurements, start, t0, prior=prior, options=options,
                             solve_for=names or None, rejected=first_out)

        return fit_area_to_mass_auto(fit, dynamics, measurements, x, options=opts)
    if opts.area_to_mass == "solve":
        from cistrack.least_squares.area_to_mass import forced_decision

        names = names if AREA_TO_MASS in names else names + (AREA_TO_MASS,)
        return forced_decision(_fit(dynamics, sensor, measurements, _Start(x, t0, first_out), pri, opts,
                                    _solve_for(dynamics, names)))
    return _fit(dynamics, sensor, measurements, _Start(x, t0, first_out), pri, opts, _solve_for(dynamics, names))


def _first_rejected(rejected: Any, k: int) -> np.ndarray | None:
    """``fit_orbit``'s ``rejected`` as (K,) bool (None: none), or a FitError naming what it got."""
    if rejected is None:
        return None
    out = np.asarray(rejected)
    if out.shape != (k,) or out.dtype != bool:
        raise FitError(f"fit_orbit: rejected must be a ({k},) bool array, one flag per measurement; got "
                       f"shape {out.shape}, dtype {out.dtype}")
    return out.copy()


class _Start(NamedTuple):
    """Where a fit starts: the state (6,) LU, VU at the epoch ``t0`` TU, and the rows (K,) bool its
    first pass leaves out (None: none)."""

    x: np.ndarray
    t0: float
    first_out: np.ndarray | None


def _fit(dynamics: Dynamics, sensor: Sensor, measurements: MeasurementSet, start: _Start,
         pri: tuple[np.ndarray, np.ndarray] | None, opts: FitOptions, params: SolveFor | None) -> FitResult:
    """:func:`fit_orbit` on checked inputs: the unknowns are the state ``start.x`` (6,) and ``params``."""
    x, t0, first_out = start
    model = MeasurementModel(sensor, measurements, use_range=opts.use_range, steps=opts.sensor_steps)
    if params is not None:
        x = np.concatenate([x, params.initial()])
    prob = _problem(dynamics, model, x, t0, pri, params)
    say: list[str] = []
    p = _fit_passes(prob, x, opts, say, first_out)
    used = ~p.rejected
    w, states, n = _at_estimate(prob, p.x, used)
    obs = observability(_state_information(n))
    cov = _covariance(n, obs)
    unobservable = _unobservable_text(obs, opts)
    if unobservable is not None:
        say.append(unobservable)
        warnings.warn(f"fit: {unobservable}", UnobservableWarning, stacklevel=3)
    table = _table(model, measurements, states, p.rejected)
    chi2, rms, noise_scale = _goodness(w, used, say, prob.n)
    converged = _verdict(p, rms, noise_scale, opts, say, np.sum(w ** 2, axis=1))
    extra = {} if params is None else {"parameter_names": params.names, "parameters": p.x[6:].copy(),
                                        "full_covariance": cov}
    return FitResult(state=p.x[:6], covariance=cov[:6, :6], epoch=t0, residuals=table, rms=rms, chi2=chi2,
                     n_used=int(used.sum()), n_rejected=int(p.rejected.sum()), iterations=p.iterations,
                     converged=bool(converged), condition_number=obs.condition,
                     weakest_direction_km=obs.weakest_direction_km, noise_scale=noise_scale,
                     rejection_threshold=p.threshold, unobservable=unobservable is not None, messages=tuple(say),
                     **extra)
