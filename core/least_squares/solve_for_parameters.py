"""Dynamics parameters estimated with the state (solve-for parameters) and their partials.

A dynamics model that offers solve-for parameters has

- ``solve_for_parameters``: a tuple of names it accepts,
- ``parameter(name) -> float``: the value it integrates with,
- ``with_parameters(**values) -> Dynamics``: a copy with those values (the original unchanged).

The ephemeris model (``dynamics = "ephemeris"``) offers ``area_to_mass_m2_kg``: C_R A/m of the
cannonball radiation pressure, m^2/kg.

The partial of the measurements with respect to a parameter p is a central difference of the
propagated measurements, (h(x(t; p + dp)) - h(x(t; p - dp))) / (2 dp) with the epoch state held
fixed: two more propagations of one orbit per Jacobian. The step :data:`STEPS` (1e-3 m^2/kg for
the area-to-mass ratio) moves a cislunar orbit by tens of km over a month, far above the
integration's noise (tolerance 1e-12), and the trajectory is nearly linear in p (the acceleration
is exactly linear in it), so the difference's truncation error is negligible; the test compares
it with a step ten times smaller.
"""
from __future__ import annotations

import re
from collections.abc import Sequence
from typing import Any

import numpy as np

from cistrack.errors import ParameterError, StateError
from cistrack.interfaces.dynamics import Dynamics
from cistrack.least_squares.errors import FitError

__all__ = ["SolveFor", "STEPS", "solve_for", "fitted_dynamics"]

STEPS: dict[str, float] = {"area_to_mass_m2_kg": 1e-3}
"""Central-difference step of each known parameter, in its own unit."""
DEFAULT_STEP = 1e-3
WORDS: dict[str, tuple[str, str]] = {"area_to_mass_m2_kg": ("area-to-mass ratio (C_R A/m)", "m^2/kg")}
"""How messages to a user name each known parameter, and its unit."""


def _left_range(names: tuple[str, ...], values: np.ndarray, exc: ParameterError) -> FitError:
    """The fit's failure when its iterate ``values`` (P,) of the parameters ``names`` left the
    range the dynamics allow (``exc``: the dynamics' refusal), worded for a user: the parameter
    by name and unit, its value and what the model allows; not the dynamics' internal words (probe
    M12: "dynamics 'ephemeris': parameter 'area_to_mass_m2_kg' = 1251.458... is invalid")."""
    found = re.search(r"parameter '([^']+)' = .* is invalid: (?:must be )?(.*)$", str(exc), re.S)
    name = found[1] if found and found[1] in names else names[0]
    allowed = found[2] if found else str(exc)
    what, unit = WORDS.get(name, (f"parameter {name}", ""))
    value = f"{float(values[names.index(name)]):.4g}" + (f" {unit}" if unit else "")
    return FitError(f"the fitted {what} ran to {value}, outside what the model allows ({allowed}): these "
                    "observations do not determine it")


def _check_dynamics(dynamics: Dynamics, names: tuple[str, ...]) -> None:
    offered = tuple(getattr(dynamics, "solve_for_parameters", ()))
    label = getattr(dynamics, "_label", lambda: type(dynamics).__name__)()
    for name in names:
        if name not in offered:
            raise StateError(f"fit: solve-for parameter {name!r}: the dynamics {label} does not offer it "
                             f"(it offers: {', '.join(offered) or 'none'}); "
                             + ("use dynamics 'ephemeris'" if name == "area_to_mass_m2_kg" else ""))


class SolveFor:
    """The solve-for parameters of one fit.

    Parameters
    ----------
    dynamics : Dynamics   the model; offers the parameters (module docstring)
    names : tuple of str  the parameters estimated, in the order of the unknowns 7, 8, ...
    """

    def __init__(self, dynamics: Dynamics, names: tuple[str, ...]) -> None:
        _check_dynamics(dynamics, names)
        self.base = dynamics
        self.names = tuple(names)
        self.steps = np.array([STEPS.get(n, DEFAULT_STEP) for n in self.names])
        self._cache: tuple[bytes, Dynamics] | None = None

    @property
    def size(self) -> int:
        """Number of parameters."""
        return len(self.names)

    def initial(self) -> np.ndarray:
        """The values (P,) the dynamics integrates with now: where the fit starts."""
        return np.array([float(self.base.parameter(n)) for n in self.names])

    def dynamics(self, values: np.ndarray) -> Dynamics:
        """The model with the parameters at ``values`` (P,) (the last one built is reused)."""
        key = np.asarray(values, dtype=float).tobytes()
        if self._cache is None or self._cache[0] != key:
            try:
                dyn = self.base.with_parameters(**{n: float(v) for n, v in zip(self.names, values)})
            except ParameterError as exc:  # an iterate outside the model's range: the fit's failure, not the user's
                raise _left_range(self.names, values, exc) from None
            self._cache = (key, dyn)
        return self._cache[1]

    def partials(self, predict: Any, values: np.ndarray, only: Sequence[int] | None = None) -> np.ndarray:
        """Central differences d z / d p (K, m, P) of ``predict(dynamics) -> (K, m)`` (the
        measurements predicted with a model; angle differences wrapped by the caller's function)
        at ``values`` (P,); with ``only``, of those parameters' indices alone (K, m, len(only))."""
        cols = []
        for j in range(self.size) if only is None else only:
            h = self.steps[j]
            e = np.zeros(self.size)
            e[j] = h
            up = predict(self.dynamics(values + e))
            down = predict(self.dynamics(values - e))
            cols.append((up - down) / (2.0 * h))
        return np.stack(cols, axis=-1)


def solve_for(dynamics: Dynamics, names: Any) -> SolveFor | None:
    """A :class:`SolveFor` for ``names`` (a name or names; empty: None)."""
    if names is None:
        return None
    names = (names,) if isinstance(names, str) else tuple(names)
    return SolveFor(dynamics, names) if names else None


def fitted_dynamics(dynamics: Dynamics, result: Any) -> Dynamics:
    """``dynamics`` with the parameters a fit estimated (``result.parameter_names`` and
    ``result.parameters``), or ``dynamics`` itself when it estimated none: the model to predict
    the fitted orbit with."""
    names = tuple(getattr(result, "parameter_names", ()))
    if not names:
        return dynamics
    return dynamics.with_parameters(**{n: float(v) for n, v in zip(names, result.parameters)})
