"""Angle text <-> radians without losing a bit.

Readers turn a decimal angle (degrees, arcsec) into radians with 50-digit decimal arithmetic
and round once, so a reading is the correctly rounded radian value of the text. Writers print
the fewest fixed-point digits (at least 12 after the point) whose reading gives back the very
same double, so write -> read is exact. ``scale`` handles quantities such as ADES ``rmsRA``
(= sigma_RA x cos(dec)): the same double ``scale`` is applied in both directions.
"""
from __future__ import annotations

import decimal
from decimal import Decimal

from cistrack.errors import MeasurementError

__all__ = ["to_rad", "plain_float", "from_rad", "fixed", "decimal_in"]

_CTX = decimal.Context(prec=50)
_PI = Decimal("3.14159265358979323846264338327950288419716939937510")
_UNIT = {"rad": Decimal(1), "deg": _CTX.divide(_PI, Decimal(180)),
         "arcsec": _CTX.divide(_PI, Decimal(648000)), "hour": _CTX.divide(_PI, Decimal(12))}


def plain_float(text: str) -> float:
    """The number written in ``text`` (decimal or exponent notation, as ``float`` reads it);
    ValueError for anything else, including digits grouped with underscores (``1_08.5``) and
    digits of other scripts (a full-width ``８``), which Python's ``float`` and ``Decimal`` would read
    but no observation format allows."""
    if not isinstance(text, str) or "_" in text or not text.isascii():
        raise ValueError("not a number")
    return float(text)


def to_rad(text: str, unit: str, scale: float = 1.0) -> float:
    """Radians of the decimal ``text`` in ``unit`` ("deg", "arcsec", "hour", "rad"), divided
    by ``scale``; ValueError when the text is not a finite decimal number (underscores between
    digits and digits other than ASCII's are refused)."""
    try:
        if "_" in text or not text.isascii():
            raise decimal.InvalidOperation
        d = Decimal(text.strip())
    except (decimal.InvalidOperation, AttributeError, TypeError):
        raise ValueError("not a number") from None
    if not d.is_finite():
        raise ValueError("not a finite number")
    v = _CTX.multiply(d, _UNIT[unit])
    if scale != 1.0:
        v = _CTX.divide(v, Decimal(scale))
    return float(v)


def from_rad(value: float, unit: str, scale: float = 1.0, min_digits: int = 12) -> str:
    """Fixed-point text of ``value`` rad x ``scale`` in ``unit`` that :func:`to_rad` reads back
    to exactly ``value``."""
    x = _CTX.divide(_CTX.multiply(Decimal(float(value)), Decimal(float(scale))), _UNIT[unit])
    for digits in range(min_digits, 40):
        t = format(x, f".{digits}f")
        if to_rad(t, unit, scale) == value:
            return t
    raise MeasurementError(f"cannot write {value!r} rad exactly in {unit}")  # pragma: no cover


def fixed(x: float, digits: int) -> str:
    """``x`` with ``digits`` digits after the point (no exponent)."""
    return format(Decimal(float(x)), f".{digits}f")


def decimal_in(value: float, unit: str) -> Decimal:
    """The exact double ``value`` (rad) expressed in ``unit`` to 50 digits."""
    return _CTX.divide(Decimal(float(value)), _UNIT[unit])
