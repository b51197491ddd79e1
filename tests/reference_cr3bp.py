"""An independent, plain-scipy CR3BP right-hand side for tests that need a truth trajectory
without going through cistrack's own (numba) dynamics plugin."""
from __future__ import annotations

import numpy as np

MU = 1.2150582e-2


def cr3bp_rhs(_t, s):
    """CR3BP equations of motion (REFERENCE.md) for one state (6,)."""
    x, y, z, vx, vy, vz = s
    r1 = np.sqrt((x + MU) ** 2 + y * y + z * z) ** 3
    r2 = np.sqrt((x - 1 + MU) ** 2 + y * y + z * z) ** 3
    return [vx, vy, vz,
            x + 2 * vy - (1 - MU) * (x + MU) / r1 - MU * (x - 1 + MU) / r2,
            y - 2 * vx - (1 - MU) * y / r1 - MU * y / r2,
            -(1 - MU) * z / r1 - MU * z / r2]
