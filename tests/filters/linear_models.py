"""Linear test models implementing the Dynamics and Sensor interfaces, with closed forms.

LinearDynamics: force-free motion x' = v, v' = 0 (exact propagation x + v dt), optionally with
a spherical "body" that stops particles. LinearSensor: z = H x with constant noise. BearingSensor:
an azimuth (wraps at 2pi) and a linear component, for angle-wrap tests.
"""
from __future__ import annotations

import numpy as np

from cistrack.model.belief import ParticleCloud
from cistrack.interfaces import Body, Dynamics, Propagation, Sensor
from cistrack.model.measurement import MeasurementSet


def transition(dt: float) -> np.ndarray:
    """State transition matrix (6, 6) of x' = v, v' = 0 over dt."""
    f = np.eye(6)
    f[:3, 3:] = dt * np.eye(3)
    return f


def kalman_step(m: np.ndarray, P: np.ndarray, dt: float, H: np.ndarray, R: np.ndarray,
                z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The textbook Kalman filter's prediction over dt (free motion) and update with z = H x + v."""
    F = transition(dt)
    m, P = F @ m, F @ P @ F.T
    K = P @ H.T @ np.linalg.inv(H @ P @ H.T + R)
    return m + K @ (z - H @ m), (np.eye(6) - K @ H) @ P


class LinearDynamics(Dynamics):
    """Free motion; a particle is stopped when its position enters the ball ``body_radius``
    around ``body_center`` at the final time (enough for the tests that use it)."""

    def __init__(self, body_radius: float = 0.0, body_x: float = 0.0):
        self.body_radius = body_radius
        self.body_x = body_x

    @property
    def bodies(self):
        if self.body_radius > 0:
            return (Body("Rock", np.array([self.body_x, 0.0, 0.0]), self.body_radius),)
        return ()

    def derivatives(self, t, states):
        s = np.asarray(states, dtype=float)
        return np.hstack([s[:, 3:], np.zeros_like(s[:, 3:])])

    def propagate(self, states, t0, times):
        s = np.atleast_2d(np.asarray(states, dtype=float))
        times = np.atleast_1d(np.asarray(times, dtype=float))
        out = np.stack([s @ transition(t - t0).T for t in times])
        alive = np.ones(s.shape[0], dtype=bool)
        body = np.full(s.shape[0], -1)
        t_imp = np.full(s.shape[0], np.inf)
        if self.body_radius > 0:
            hit = np.linalg.norm(out[-1, :, :3] - np.array([self.body_x, 0, 0]), axis=1) < self.body_radius
            alive &= ~hit
            body[hit] = 0
            t_imp[hit] = times[-1]
        return Propagation(times, out, alive, body, t_imp)


class LinearSensor(Sensor):
    """z = H x, H picking the given state coordinates; noise sigma on every component."""

    names = ("p0", "p1")
    angular = (False, False)

    def __init__(self, sigma: float = 0.1, coords: tuple = (0, 1)):
        self.sigma = sigma
        self.coords = tuple(coords)
        self.names = tuple(f"p{c}" for c in self.coords)
        self.angular = tuple(False for _ in self.coords)

    @property
    def H(self) -> np.ndarray:
        h = np.zeros((len(self.coords), 6))
        h[np.arange(len(self.coords)), list(self.coords)] = 1.0
        return h

    def measure(self, states, t):
        return np.atleast_2d(states) @ self.H.T

    def sigmas(self, states, t):
        return np.full((np.atleast_2d(states).shape[0], len(self.coords)), self.sigma)

    def visible(self, states, t):
        return np.ones(np.atleast_2d(states).shape[0], dtype=bool)

    def observer_position(self, t):
        t = np.asarray(t, dtype=float)
        return np.zeros(3) if t.ndim == 0 else np.zeros((t.size, 3))

    def line_of_sight(self, angles, t):
        raise NotImplementedError("linear sensor has no line of sight")

    def simulate(self, states, times, rng):
        z = self.measure(states, times)
        return MeasurementSet(times, z + self.sigma * rng.standard_normal(z.shape),
                              np.full(z.shape, self.sigma), self.names)


class BearingSensor(Sensor):
    """Azimuth atan2(y, x) in [0, 2pi) (wraps) and the z coordinate, both with noise ``sigma``."""

    names = ("azimuth", "height")
    angular = (True, False)

    def __init__(self, sigma: float = 1e-3):
        self.sigma = sigma

    def measure(self, states, t):
        s = np.atleast_2d(states)
        return np.column_stack([np.arctan2(s[:, 1], s[:, 0]) % (2 * np.pi), s[:, 2]])

    def sigmas(self, states, t):
        return np.full((np.atleast_2d(states).shape[0], 2), self.sigma)

    def visible(self, states, t):
        return np.ones(np.atleast_2d(states).shape[0], dtype=bool)

    def observer_position(self, t):
        return np.zeros(3)

    def line_of_sight(self, angles, t):
        raise NotImplementedError

    def simulate(self, states, times, rng):
        z = self.measure(states, times)
        return MeasurementSet(times, z + self.sigma * rng.standard_normal(z.shape),
                              np.full(z.shape, self.sigma), self.names)


def filter_beside_kalman(filt, m0: np.ndarray, p0: np.ndarray, times: np.ndarray,
                         sensor: LinearSensor, rng: np.random.Generator,
                         filter_rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """Run ``filt`` on free motion from a cloud of ``filt.n_particles`` draws of N(m0, p0), on
    measurements of a truth drawn from the same prior, at ``times`` (days); beside it the textbook
    Kalman filter from the cloud's own moments. Returns the Kalman filter's final (m (6,), P (6, 6)).
    Draws in order: truth, measurement noise, cloud (all from ``rng``)."""
    truth0 = rng.multivariate_normal(m0, p0)
    ms = sensor.simulate(np.stack([transition(t) @ truth0 for t in times]), times, rng)
    cloud = ParticleCloud(rng.multivariate_normal(m0, p0, filt.n_particles), 0.0)
    filt.initialize(cloud, LinearDynamics(), sensor, filter_rng)
    m, P, tp = cloud.mean, cloud.covariance, 0.0
    R = sensor.sigma ** 2 * np.eye(len(sensor.coords))
    for t, meas in zip(times, ms):
        m, P = kalman_step(m, P, t - tp, sensor.H, R, meas.z)
        tp = t
        filt.predict(meas.t)
        filt.update(meas)
    return m, P
