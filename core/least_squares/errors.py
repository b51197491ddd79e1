"""Errors and warnings of the orbit fit."""
from __future__ import annotations

from cistrack.errors import CistrackError

__all__ = ["FitError", "UnobservableWarning"]


class FitError(CistrackError, RuntimeError):
    """The least-squares fit cannot produce an orbit: too few measurement components for six
    unknowns, a normal matrix that is not positive definite, or a trajectory that cannot be
    propagated over the arc. The message says which."""


class UnobservableWarning(UserWarning):
    """The arc leaves a direction of the state nearly unobservable: the normal matrix's
    condition number, or the one-sigma size of its weakest direction, exceeds the fit's limit
    (the message and the result give that direction, km, km/s)."""
