"""The scenario's ``[custody]`` table: every threshold of :class:`~cistrack.evaluation.custody.CustodyRule`,
validated like every other field (a wrong key or value names the file, the table, the key and
what is allowed)::

    [custody]
    loglik_threshold = -100.0      # truth log-likelihood below this: lost
    hdr_threshold = 0.997          # truth outside this highest-density region ...
    hdr_consecutive = 2            # ... on this many consecutive updates: lost
    precision_km = 100.0           # largest final position sigma of a "tracking" run (km)
    collapse_sigma_km = 1e-3       # a smaller final position sigma is a collapsed belief (km; 0: off)
    diverged_error_km = 50.0       # a final error above this (km) ...
    diverged_nees = 1e4            # ... with a NEES above this: diverged (inf: off)
    degenerate_ess = 7.0           # effective sample size or distinct particles below this: diverged (0: off)
    max_earth_distance_km = 2e6    # a final mean farther from Earth (km), the truth not: diverged (inf: off)
    blowup_nis = 1e6               # an NIS above this ...
    blowup_nis_updates = 3         # ... on this many consecutive updates: diverged there (inf: off)
    diverged_nis = 1e3             # without a truth: a median NIS above this ...
    diverged_nis_updates = 3       # ... over the last this many updates: diverged (inf: off)
    regain_updates = 0             # after a loss, this many consecutive updates with the truth inside
                                   # regain custody (0: a loss is final)

The rules that need no truth (degenerate weights, collapse, leaving cislunar space, the NIS
blow-up, and the NIS rule that only runs without a truth use) judge runs on measurement files too
(:mod:`cistrack.evaluation.verdicts`).
"""
from __future__ import annotations

import math
from typing import Any

from cistrack.plugin.component_tables import check_keys, typed
from cistrack.evaluation.custody import CustodyRule
from cistrack.errors import ConfigError

__all__ = ["custody_rule", "CUSTODY_KEYS"]

_WHERE = "[custody]"

# key -> (allowed range as words, check of the float value)
_CHECKS: dict[str, tuple[str, Any]] = {
    "loglik_threshold": ("a finite number", math.isfinite),
    "hdr_threshold": ("a number in (0, 1)", lambda v: 0 < v < 1),
    "precision_km": ("a finite number > 0 (km)", lambda v: math.isfinite(v) and v > 0),
    "collapse_sigma_km": ("a finite number >= 0 (km; 0 turns the rule off)", lambda v: math.isfinite(v) and v >= 0),
    "diverged_error_km": ("a number >= 0 (km; inf turns the rule off)", lambda v: v >= 0),
    "diverged_nees": ("a number >= 0 (inf turns the rule off)", lambda v: v >= 0),
    "degenerate_ess": ("a finite number >= 0 (particles; 0 turns the rule off)", lambda v: math.isfinite(v) and v >= 0),
    "max_earth_distance_km": ("a number > 0 (km; inf turns the rule off)", lambda v: v > 0),
    "diverged_nis": ("a number > 0 (inf turns the rule off)", lambda v: v > 0),
    "blowup_nis": ("a number > 0 (inf turns the rule off)", lambda v: v > 0),
}
_COUNTS = ("hdr_consecutive", "diverged_nis_updates", "blowup_nis_updates")
CUSTODY_KEYS: frozenset[str] = frozenset({*_CHECKS, *_COUNTS, "regain_updates"})
"""Keys allowed in a scenario's ``[custody]`` table (the fields of CustodyRule)."""


def custody_rule(table: Any, source: str) -> CustodyRule:
    """The :class:`CustodyRule` of a scenario's ``[custody]`` table (a dict; missing keys keep the
    rule's defaults). Raises ConfigError naming ``source``, the table and the key."""
    if not isinstance(table, dict):
        raise ConfigError(f"{source}: 'custody' must be a table")
    check_keys(table, set(CUSTODY_KEYS), source, _WHERE)
    values: dict[str, Any] = {}
    for key, (allowed, ok) in _CHECKS.items():
        if key not in table:
            continue
        v = float(typed(table[key], (int, float), source, _WHERE, key))
        if math.isnan(v) or not ok(v):
            raise ConfigError(f"{source}: {_WHERE}: key {key!r} = {table[key]!r} must be {allowed}")
        values[key] = v
    for key in _COUNTS:
        if key in table:
            n = typed(table[key], int, source, _WHERE, key)
            if n < 1:
                raise ConfigError(f"{source}: {_WHERE}: key {key!r} = {n} must be an integer >= 1")
            values[key] = n
    if "regain_updates" in table:
        n = typed(table["regain_updates"], int, source, _WHERE, "regain_updates")
        if n < 0:
            raise ConfigError(f"{source}: {_WHERE}: key 'regain_updates' = {n} must be an integer >= 0 "
                              "(0: a loss is final)")
        values["regain_updates"] = n
    return CustodyRule(**values)
