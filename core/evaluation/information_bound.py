"""The posterior Cramér-Rao bound along a run's truth: the best covariance the data allow.

For a run with a truth, the Bayesian information recursion is evaluated along the true trajectory
(in covariance form, so a vague prior causes no trouble):

    prior        P_0 = the IOD cloud's sample covariance (the information the IOD gives)
    prediction   P^- = F P F^T + Q        F: state transition matrix of the filters' dynamics model
                                          from the previous step to this one, along the truth, by
                                          central differences of its ``propagate`` (the run's own
                                          compiled kernel: nothing more to compile; ~1e-7 relative),
                                          Q: the process noise the filter declares
                                          (``Filter.process_noise``, none by default)
    update       P   = (P^-^-1 + sum_i H_i^T R_i^-1 H_i)^-1   for every measurement of the step,
                                          H_i: the Jacobian of the measured components at the
                                          truth (central differences), R_i: their noise covariance

With linear dynamics and measurements and a Gaussian prior this is exactly the Kalman filter's
covariance; otherwise it bounds the mean-square error of any estimator that uses the same data
and prior (a Gaussian prior of the IOD cloud's covariance stands for the IOD's information). The
model is the one the filters use (the scenario's ``[dynamics]``), so the bound is that of any
estimator built on it; the truth model (``[truth] dynamics``) only supplies the trajectory, and is
still propagated once per run.

:class:`InformationBoundMetric` (the metric stage ``information_bound``) adds to every step's
metrics (so to ``steps.parquet``):
``bound_sigma_{x,y,z}_km`` and ``bound_sigma_{vx,vy,vz}_cms``, the bound's per-axis sigma, and
``bound_pos_km`` = sqrt(trace of its position block), the bound on the RMS position error. A
filter's error (``pos_err_km``) and sigma sit beside them: ``pos_err_km / bound_pos_km`` over
seeds is the efficiency a study reports.
"""
from __future__ import annotations

from typing import Any

import numpy as np

from cistrack.evaluation.metric_stage import StepMetric
from cistrack.interfaces.transition_matrix import stm_by_central_differences
from cistrack.model.belief import sample_covariance
from cistrack.units import LU_KM, VU_KMS
from cistrack._moved import renamed_names

__all__ = ["JACOBIAN_STEPS", "measurement_jacobian", "bound_predict", "bound_update", "bound_metrics",
           "BOUND_KEYS", "InformationBoundMetric"]

JACOBIAN_STEPS = np.array([1e-6, 1e-6, 1e-6, 1e-7, 1e-7, 1e-7])
"""Central-difference steps of the measurement Jacobian: position LU (384 m), velocity VU (0.1 mm/s)."""

BOUND_KEYS = ("bound_sigma_x_km", "bound_sigma_y_km", "bound_sigma_z_km",
              "bound_sigma_vx_cms", "bound_sigma_vy_cms", "bound_sigma_vz_cms", "bound_pos_km")
"""The metrics the stage writes."""

_CMS = VU_KMS * 1e5  # VU in cm/s


def measurement_jacobian(sensor: Any, state: np.ndarray, t: float, names: tuple[str, ...],
                         steps: np.ndarray | None = None) -> np.ndarray:
    """d h / d x (m, 6) of the components ``names`` of ``sensor.measure`` at ``state`` (6,), time
    ``t`` (TU), by central differences (angle differences wrapped with ``sensor.residual``)."""
    h = JACOBIAN_STEPS if steps is None else np.asarray(steps, dtype=float)
    x = np.asarray(state, dtype=float).reshape(6)
    all_names = tuple(sensor.names)
    cols = np.array([all_names.index(n) for n in names], dtype=np.intp)
    batch = np.repeat(x[None], 12, axis=0)
    for j in range(6):
        batch[2 * j, j] += h[j]
        batch[2 * j + 1, j] -= h[j]
    z = np.asarray(sensor.measure(batch, t), dtype=float)
    diff = np.asarray(sensor.residual(z[0::2], z[1::2]), dtype=float)  # (6, m_all): plus - minus, wrapped
    return (diff[:, cols] / (2.0 * h[:, None])).T


def bound_predict(p: np.ndarray, f: np.ndarray, q: np.ndarray | None = None) -> np.ndarray:
    """P^- = F P F^T (+ Q), symmetrised; all (6, 6)."""
    out = f @ p @ f.T
    if q is not None:
        out = out + q
    return 0.5 * (out + out.T)


def bound_update(p: np.ndarray, h: np.ndarray, r: np.ndarray) -> np.ndarray:
    """The covariance after one measurement with Jacobian ``h`` (m, 6) and noise ``r`` (m, m):
    (P^-1 + H^T R^-1 H)^-1, computed as P - P H^T (H P H^T + R)^-1 H P (no inverse of a vague P)."""
    s = h @ p @ h.T + r
    k = np.linalg.solve(s, h @ p).T  # P H^T S^-1, (6, m)
    out = p - k @ h @ p
    return 0.5 * (out + out.T)


def bound_metrics(p: np.ndarray) -> dict[str, float]:
    """The :data:`BOUND_KEYS` of a covariance (6, 6) in LU, VU."""
    d = np.sqrt(np.maximum(np.diag(p), 0.0))
    pos = d[:3] * LU_KM
    vel = d[3:] * _CMS
    return {"bound_sigma_x_km": float(pos[0]), "bound_sigma_y_km": float(pos[1]), "bound_sigma_z_km": float(pos[2]),
            "bound_sigma_vx_cms": float(vel[0]), "bound_sigma_vy_cms": float(vel[1]),
            "bound_sigma_vz_cms": float(vel[2]), "bound_pos_km": float(np.sqrt(np.sum(pos ** 2)))}


class InformationBoundMetric(StepMetric):
    """Metric stage ``information_bound``: the bound (:data:`BOUND_KEYS`) of every step of a run
    with a truth, priors of updates included (the bound is predicted there). A step where the
    bound cannot be evaluated (the truth hits a body, a singular innovation) leaves it out from
    there on, and the reason is kept in :attr:`stopped`."""

    name = "information_bound"

    def __init__(self) -> None:
        self._p: np.ndarray | None = None
        self._t = 0.0
        self._x: np.ndarray | None = None
        self._dynamics: Any = None
        self._filter: Any = None
        self.stopped = ""

    def start(self, run) -> None:
        if run.truth is None:
            return
        self._dynamics = run.dynamics  # the filters' model, along the true trajectory
        self._filter = run.filter
        cloud = run.iod_cloud
        self._p = sample_covariance(np.asarray(cloud.states, dtype=float), getattr(cloud, "weights", None))
        self._t = float(cloud.epoch)
        self._x = None

    def _advance(self, step) -> None:
        """The bound predicted from its last time to ``step.t`` along the truth."""
        assert self._p is not None
        x = np.asarray(step.truth, dtype=float)
        t = float(step.t)
        if t == self._t:
            self._x = x
            return
        start = self._x if self._x is not None else None
        if start is None:  # the first step after the IOD epoch: the truth at the IOD epoch
            start = x
            _, stm = stm_by_central_differences(self._dynamics, x, t, [self._t])
            f = np.linalg.inv(stm[-1])  # from the IOD epoch to t
        else:
            _, stm = stm_by_central_differences(self._dynamics, start, self._t, [t])
            f = stm[-1]
        q = None
        declare = getattr(self._filter, "process_noise", None)
        if callable(declare):
            q = declare(self._t, t)
        self._p = bound_predict(self._p, f, q)
        self._t, self._x = t, x

    def _update(self, run, step) -> None:
        """The bound after every measurement of update ``step`` (at the truth)."""
        assert self._p is not None and self._x is not None
        for m in (step.group or (step.measurement,)):
            own = run.sensor.for_measurement(m) if hasattr(run.sensor, "for_measurement") else run.sensor
            h = measurement_jacobian(own, self._x, float(m.t), tuple(m.names))
            self._p = bound_update(self._p, h, np.asarray(m.covariance, dtype=float))

    def compute(self, run, step, event: str) -> dict[str, float]:
        if self._p is None or step.truth is None or self.stopped:
            return {}
        try:
            self._advance(step)
            if event == "updated":
                self._update(run, step)
        except Exception as exc:  # singular, non-finite, or the truth model refused (an impact): no bound from here on
            self.stopped = f"step {step.index}: {type(exc).__name__}: {exc}"
            self._p = None
            return {}
        return bound_metrics(self._p) if np.all(np.isfinite(self._p)) else {}


__getattr__ = renamed_names(__name__, {"InformationBoundObserver": ("InformationBoundMetric", InformationBoundMetric)})  # the old name, for one release
