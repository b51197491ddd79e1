"""Reference orbits of the Earth–Moon CR3BP, registered under the kind "orbit".

Every periodic state below was produced by :func:`.corrector.correct_symmetric_orbit` (x0 held
fixed at the published value, rtol 1e-13, residual |vx|, |vz| < 1e-13 VU at the half-period
crossing) from approximate published initial conditions, for
mu = 1.2150582e-2; the literals are full precision so that they close after one period to
~1e-12 LU. Checked properties (tight-tolerance integration over one period):

=============  ========  ===========  ==================================================
name           period    period (d)   check
=============  ========  ===========  ==================================================
nrho-9-2       1.512146  6.566        perilune 3,260 km (REFERENCE: ~3,250 km)
nrho-3-1       2.267714  9.846        perilune 15,217 km
l2-lyapunov    3.404121  14.781       planar, Jacobi 3.157109
dro-2-1        3.399997  14.763       planar, retrograde about the Moon, 73,862 km min.
mirror-3-1     6.274634  27.244       planar, perigee 50,683 km (REFERENCE: ~50,700 km)
l2-transit     --        --           not periodic: closest to L2 ~1 km at 47.5 h, 41 m/s
=============  ========  ===========  ==================================================
"""
from __future__ import annotations

import numpy as np

from cistrack.api import hookimpl
from cistrack.interfaces.orbit import ReferenceOrbit

from cistrack.astro.primaries import MU_EARTH_MOON

__all__ = ["ORBITS", "GUESSES", "get_orbit"]

_MU = MU_EARTH_MOON


def _orbit(name: str, state: list[float], period: float | None, description: str) -> ReferenceOrbit:
    s = np.array(state, dtype=float)
    s.setflags(write=False)
    return ReferenceOrbit(name=name, state=s, period=period, mu=_MU, description=description)


ORBITS: dict[str, ReferenceOrbit] = {o.name: o for o in (
    _orbit("nrho-9-2",
           [1.0221, 0.0, -0.18215080321903362, 0.0, -0.103427251585984, 0.0],
           1.5121455320848902,
           "9:2 lunar-synodic-resonant L2 southern NRHO (Gateway), 6.57 d, perilune ~3,260 km"),
    _orbit("nrho-3-1",
           [1.0753, 0.0, -0.20215081148670752, 0.0, -0.19250344212142512, 0.0],
           2.2677138981408973,
           "3:1 L2 southern NRHO, 9.85 d (the paper's Example 3)"),
    _orbit("l2-lyapunov",
           [1.1257, 0.0, 0.0, 0.0, 0.150732399635109, 0.0],
           3.404121430795026,
           "planar Lyapunov orbit about Earth-Moon L2, 14.8 d"),
    _orbit("dro-2-1",
           [0.7957, 0.0, 0.0, 0.0, 0.5318195248528026, 0.0],
           3.399997183031531,
           "2:1 distant retrograde orbit about the Moon, 14.8 d"),
    _orbit("mirror-3-1",
           [-0.144, 0.0, 0.0, 0.0, -3.4620248592934244, 0.0],
           6.274634159209553,
           "3:1 resonant planar mirror orbit (IBEX-like), 27.2 d, perigee ~50,700 km"),
    _orbit("l2-transit",
           [1.16429257222878, -0.0144369085836121, 0.0, -0.0389308426824481, 0.0153488211249537, 0.0],
           None,
           "slow transit through the L2 region (the paper's Example 2), not periodic"),
)}
"""The catalog, by name."""

GUESSES: dict[str, tuple[list[float], float]] = {
    "nrho-9-2": ([1.0221, 0.0, -0.1821, 0.0, -0.1033, 0.0], 1.5111),
    "nrho-3-1": ([1.0753, 0.0, -0.2021, 0.0, -0.1925, 0.0], 2.267),
    "l2-lyapunov": ([1.1257, 0.0, 0.0, 0.0, 0.1508, 0.0], 3.404),
    "dro-2-1": ([0.7957, 0.0, 0.0, 0.0, 0.5319, 0.0], 3.401),
    "mirror-3-1": ([-0.1440, 0.0, 0.0, 0.0, -3.4613, 0.0], 6.275),
}
"""Published approximate initial states and periods the periodic entries were corrected from
(all corrected with ``fixed="x"``, ``period_guess`` = the period here)."""


def get_orbit(name: str) -> ReferenceOrbit:
    """The catalog orbit ``name``; unknown names list what exists."""
    try:
        return ORBITS[name]
    except KeyError:
        from cistrack.errors import UnknownComponentError
        raise UnknownComponentError(f"no reference orbit {name!r}; catalog: {', '.join(ORBITS)}") from None


@hookimpl
def cistrack_register(registry):
    for name, orbit in ORBITS.items():
        registry.add("orbit", name, orbit)
