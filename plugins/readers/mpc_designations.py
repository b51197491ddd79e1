"""The MPC's packed designations, as MPC 80-column lines carry them, and their unpacked form, as
ADES files carry them.

An object observed in both formats must be one object: "K26F01A" in columns 6-12 is ADES provID
"2026 FA1", "00433" in columns 1-5 is permID "433", "A0433" is "100433". Packing follows the MPC's
documented scheme:

- permanent numbers (5 characters): 5 digits; a letter (A-Z 10-35, a-z 36-61) and 4 digits for
  100,000-619,999; "~" and 4 base-62 digits for 620,000 and above;
- provisional designations (7 characters): the century (I 18, J 19, K 20, L 21), two digits of
  the year, the half-month letter, the cycle count in two characters (00-99, or a letter for the
  hundreds as above and a digit), the second letter: "K26F01A" = "2026 FA1", "J98SA8Q" = "1998 SQ108";
- the Palomar-Leiden and Trojan surveys: "PLS2040" = "2040 P-L", "T1S3138" = "3138 T-1".

Anything else (a temporary designation such as "C1AMXV2", a comet's or satellite's packed form) is
left as written.
"""
from __future__ import annotations

import re

__all__ = ["unpack_number", "unpack_provisional", "pack_provisional"]

_BASE62 = "0123456789ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz"
_CENTURIES = {"I": 18, "J": 19, "K": 20, "L": 21}
_NUMBER = re.compile(r"^(?:\d{5}|[A-Za-z]\d{4}|~[0-9A-Za-z]{4})$")
_PROVISIONAL = re.compile(r"^([IJKL])(\d\d)([A-HJ-Y])([0-9A-Za-z])(\d)([A-HJ-Z])$")
_SURVEY = re.compile(r"^(PL|T1|T2|T3)S(\d{4})$")
_UNPACKED = re.compile(r"^(1[89]|2[01])(\d\d) ([A-HJ-Y])([A-HJ-Z])(\d*)$")


def _value(c: str) -> int:
    return _BASE62.index(c)


def _number(text: str) -> str:
    """A packed permanent number (5 characters) as its decimal digits."""
    if text[0] == "~":
        n = 0
        for c in text[1:]:
            n = 62 * n + _value(c)
        return str(620000 + n)
    return str(_value(text[0]) * 10000 + int(text[1:]))


def unpack_number(text: str) -> str:
    """``text`` (columns 1-5 of an MPC 80-column line, stripped) as the permanent number ADES
    files give ("00433" -> "433", "A0433" -> "100433"); ``text`` itself when it is not a packed number."""
    return _number(text) if _NUMBER.match(text) else text


def unpack_provisional(text: str) -> str:
    """``text`` (columns 6-12 of an MPC 80-column line, stripped) as the provisional designation
    ADES files give ("K26F01A" -> "2026 FA1", "PLS2040" -> "2040 P-L"); ``text`` itself when it is
    not a packed provisional or survey designation (a temporary designation)."""
    m = _PROVISIONAL.match(text)
    if m:
        century, year, half, hundreds, units, second = m.groups()
        cycle = _value(hundreds) * 10 + int(units)
        return f"{_CENTURIES[century]}{year} {half}{second}{cycle if cycle else ''}"
    m = _SURVEY.match(text)
    if m:
        survey, number = m.groups()
        return f"{number} {'P-L' if survey == 'PL' else survey[0] + '-' + survey[1]}"
    return text


def pack_provisional(text: str) -> str | None:
    """The 7-character packed form of the unpacked provisional designation ``text`` ("2026 FA1"
    -> "K26F01A"), or None when ``text`` is not one (or its cycle count exceeds 619)."""
    m = _UNPACKED.match(text)
    if not m:
        return None
    century, year, half, second, cycle_text = m.groups()
    cycle = int(cycle_text) if cycle_text else 0
    if cycle > 619:
        return None
    letter = {v: k for k, v in _CENTURIES.items()}[int(century)]
    return f"{letter}{year}{half}{_BASE62[cycle // 10]}{cycle % 10}{second}"
