"""CR3BP dynamics written against 0.1's paths: CompiledDynamics from cistrack.plugins.dynamics.compiled."""
import numpy as np
from numba import njit

from cistrack.component import check_range
from cistrack.hookspecs import hookimpl
from cistrack.plugins.dynamics.compiled import CompiledDynamics
from cistrack.primaries import MU_EARTH_MOON, earth_moon_primaries


@njit(cache=True)
def legacy_rhs(t, y, p, out):
    mu = p[0]
    xe, xm = y[0] + mu, y[0] - 1.0 + mu
    yz2 = y[1] * y[1] + y[2] * y[2]
    r1s, r2s = xe * xe + yz2, xm * xm + yz2
    c1 = (1.0 - mu) / (r1s * np.sqrt(r1s))
    c2 = mu / (r2s * np.sqrt(r2s))
    out[0], out[1], out[2] = y[3], y[4], y[5]
    out[3] = y[0] + 2.0 * y[4] - c1 * xe - c2 * xm
    out[4] = y[1] - 2.0 * y[3] - (c1 + c2) * y[1]
    out[5] = -(c1 + c2) * y[2]


class LegacyCR3BP(CompiledDynamics):
    """Earth-Moon CR3BP.

    Parameters
    ----------
    rtol, atol : float
        Integration tolerances.
    """

    rhs = legacy_rhs

    def __init__(self, rtol: float = 1e-11, atol: float = 1e-12):
        self.rtol = check_range(self, "rtol", rtol, 1e-15, 1e-2)
        self.atol = check_range(self, "atol", atol, 1e-18, 1e-2)

    def params_vector(self):
        return np.array([MU_EARTH_MOON])

    @property
    def primaries(self):
        return earth_moon_primaries()


@hookimpl
def cistrack_register(registry):
    registry.add("dynamics", "legacy-cr3bp", LegacyCR3BP)
