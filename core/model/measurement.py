"""Measurements: one observation and an ordered set of them.

A measurement set may carry, per measurement, the observing site (a key into the set's
``site_table`` of :class:`cistrack.astro.sites.Site`) and the measurement type (``"azel"``: azimuth
and elevation; ``"radec"``: topocentric right ascension and declination). Sets built without
them (simulated by one sensor) mean "the sensor's own site" and take the type from ``names``.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from cistrack import units
from cistrack.errors import MeasurementError

__all__ = ["Measurement", "MeasurementSet", "StackedMeasurement", "KIND_NAMES", "kind_of_names", "names_of_kind"]

KIND_NAMES: dict[str, tuple[str, str]] = {
    "azel": ("azimuth", "elevation"),
    "radec": ("right_ascension", "declination"),
}
"""Measurement type -> names of its two angle components (rad). A 'range' (LU) may follow."""


def kind_of_names(names: tuple[str, ...]) -> str:
    """The measurement type whose angle names start ``names`` ("" when none does)."""
    for kind, pair in KIND_NAMES.items():
        if tuple(names[:2]) == pair:
            return kind
    return ""


def names_of_kind(kind: str, with_range: bool = False) -> tuple[str, ...]:
    """Component names of a measurement type, e.g. ("right_ascension", "declination")."""
    if kind not in KIND_NAMES:
        raise MeasurementError(f"unknown measurement type {kind!r}; known: {', '.join(KIND_NAMES)}")
    return KIND_NAMES[kind] + (("range",) if with_range else ())


@dataclass(frozen=True)
class Measurement:
    """One observation.

    Attributes
    ----------
    t : float
        TU since the scenario epoch.
    z : (m,) float
        Measured values in the sensor's units (angles in rad, range in LU).
    covariance : (m, m) float
        Noise covariance of ``z``.
    names : tuple of str
        Name of each component of ``z`` (e.g. ("azimuth", "elevation")).
    index : int
        Position in its measurement set.
    site : str
        Key of the observing site in the set's ``site_table`` ("" = the sensor's own site).
    kind : str
        Measurement type, "azel" or "radec" ("" when the names are neither).
    """

    t: float
    z: np.ndarray
    covariance: np.ndarray
    names: tuple[str, ...]
    index: int = 0
    site: str = ""
    kind: str = ""

    def angles_only(self) -> "Measurement":
        """This measurement without a 'range' component (IOD-only range is dropped for OD)."""
        keep = [i for i, n in enumerate(self.names) if n != "range"]
        return Measurement(self.t, self.z[keep], self.covariance[np.ix_(keep, keep)],
                           tuple(self.names[i] for i in keep), self.index, self.site, self.kind)


@dataclass(frozen=True)
class StackedMeasurement:
    """Several measurements taken at one time (by several sites), conditioned on as one: a
    filter whose class sets ``stacked_updates`` receives it in one ``update`` (its
    ``MeasuredComponents`` predicts each part from its own site and stacks them); other filters
    get the parts one after the other.

    Attributes
    ----------
    parts : tuple of Measurement, all at the same ``t``, in file order
    t : float             TU since the scenario epoch
    z : (sum m,) float    the parts' values, stacked
    covariance : (sum m, sum m) float   block-diagonal (the parts' noises are independent)
    names : tuple of str  the parts' names, concatenated (they repeat)
    index : int           the first part's index in its set
    """

    parts: tuple[Measurement, ...]

    def __post_init__(self) -> None:
        if len(self.parts) < 1 or any(abs(p.t - self.parts[0].t) > 0 for p in self.parts):
            raise MeasurementError("a stacked measurement needs one or more measurements taken at one time")

    @property
    def t(self) -> float:
        return float(self.parts[0].t)

    @property
    def z(self) -> np.ndarray:
        return np.concatenate([np.asarray(p.z, dtype=float).reshape(-1) for p in self.parts])

    @property
    def covariance(self) -> np.ndarray:
        n = sum(len(p.z) for p in self.parts)
        out = np.zeros((n, n))
        i = 0
        for p in self.parts:
            m = len(p.z)
            out[i:i + m, i:i + m] = p.covariance
            i += m
        return out

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(n for p in self.parts for n in p.names)

    @property
    def index(self) -> int:
        return int(self.parts[0].index)


def _check_same_time_rows(times: np.ndarray, sites: np.ndarray | None) -> None:
    """Rows may share a time tag only when they come from different sites."""
    same = np.nonzero(np.diff(times) == 0)[0]
    if same.size == 0:
        return
    if sites is None:
        i = int(same[0])
        raise MeasurementError(f"measurement times must increase strictly without sites; row {i + 1} is "
                               f"at the same time as row {i}")
    for k in same:  # rows k and k + 1 share a time: every row of that time needs its own site
        i = int(k)
        j = i
        while j > 0 and times[j - 1] == times[i]:
            j -= 1
        if sites[i + 1] in sites[j:i + 1]:
            raise MeasurementError(f"rows {j}..{i + 1} share one time and row {i + 1} repeats site "
                                   f"{str(sites[i + 1])!r}; one site measures once per time")


@dataclass
class MeasurementSet:
    """Time-ordered measurements, of one sensor or of several sites.

    Attributes
    ----------
    times : (K,) float
        TU since the scenario epoch, increasing; rows may share a time only when they name
        different sites (several sites measuring at once).
    values : (K, m) float
        Measured values (rad, LU).
    sigmas : (K, m) float
        One-sigma noise of each value (rad, LU); noise is independent per component.
    names : tuple of str
        Component names, length m. In a set mixing types the angle columns are named
        ("angle_1", "angle_2") and each measurement's own names follow its ``kinds`` entry.
    meta : dict
        Free-form provenance (source file, epoch, ...).
    sites : (K,) str or None
        Site key of each measurement (into ``site_table``); None: every measurement comes from
        the observing sensor's own site.
    kinds : (K,) str or None
        Measurement type of each row ("azel" / "radec"); None: the type given by ``names``.
    site_table : dict str -> cistrack.astro.sites.Site
        The sites named in ``sites``.
    """

    times: np.ndarray
    values: np.ndarray
    sigmas: np.ndarray
    names: tuple[str, ...]
    meta: dict = field(default_factory=dict)
    sites: np.ndarray | None = None
    kinds: np.ndarray | None = None
    site_table: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        self.names = tuple(self.names)
        self.times = np.asarray(self.times, dtype=float).reshape(-1)
        k = self.times.shape[0]
        m = len(self.names)
        self.values = np.asarray(self.values, dtype=float).reshape(k, m)
        self.sigmas = np.asarray(self.sigmas, dtype=float).reshape(k, m)
        if k and not np.all(np.isfinite(self.times)):
            raise MeasurementError("measurement times contain NaN or infinity")
        if k > 1 and np.any(np.diff(self.times) < 0):
            i = int(np.argmax(np.diff(self.times) < 0))
            raise MeasurementError(f"measurement times must not decrease; row {i + 1} is before row {i}")
        if not (np.all(np.isfinite(self.values)) and np.all(np.isfinite(self.sigmas))):
            raise MeasurementError("measurement values or sigmas contain NaN or infinity: "
                                   + self._first_where(lambda v, s: ~(np.isfinite(v) & np.isfinite(s))))
        if np.any(self.sigmas <= 0):
            raise MeasurementError("measurement sigmas must be > 0: " + self._first_where(lambda v, s: s <= 0))
        if self.sites is not None:
            self.sites = np.asarray(self.sites, dtype=str).reshape(-1)
            if self.sites.shape[0] != k:
                raise MeasurementError(f"{self.sites.shape[0]} site keys for {k} measurements")
            unknown = sorted(set(self.sites.tolist()) - set(self.site_table))
            if unknown:
                raise MeasurementError(f"site keys {unknown} are not in the set's site table "
                                       f"(known: {sorted(self.site_table)})")
        _check_same_time_rows(self.times, self.sites)
        if self.kinds is not None:
            self.kinds = np.asarray(self.kinds, dtype=str).reshape(-1)
            if self.kinds.shape[0] != k:
                raise MeasurementError(f"{self.kinds.shape[0]} measurement types for {k} measurements")
            bad = sorted(set(self.kinds.tolist()) - set(KIND_NAMES))
            if bad:
                raise MeasurementError(f"unknown measurement types {bad}; known: {', '.join(KIND_NAMES)}")
            own = kind_of_names(self.names)
            if own and k and np.any(self.kinds != own):
                raise MeasurementError(f"components named {self.names} but measurement types "
                                       f"{sorted(set(self.kinds.tolist()))}; a mixed set names its "
                                       f"angle columns ('angle_1', 'angle_2')")

    def _first_where(self, bad) -> str:
        """The first measurement and component where ``bad(values, sigmas)`` (K, m) holds, with its
        time: "measurement 0 (t = 0.2581 TU = 1.121 d), azimuth: value nan, sigma 7.27e-06"."""
        k, c = np.argwhere(bad(self.values, self.sigmas))[0]
        t = float(self.times[k])
        return (f"measurement {k} (t = {t:.6g} TU = {float(units.tu_to_days(t)):.4g} d), {self.names[c]}: "
                f"value {self.values[k, c]:.6g}, sigma {self.sigmas[k, c]:.3g}")

    def __len__(self) -> int:
        return self.times.shape[0]

    def time_groups(self) -> list[np.ndarray]:
        """Row indices grouped by time tag, in time order: one (n,) int array per distinct time
        (several rows share a time when several sites measured at once)."""
        if len(self) == 0:
            return []
        cuts = np.nonzero(np.diff(self.times) > 0)[0] + 1
        return np.split(np.arange(len(self)), cuts)

    def kind_at(self, i: int) -> str:
        """Measurement type of row ``i`` ("azel", "radec" or "" when not an angle pair)."""
        return str(self.kinds[i]) if self.kinds is not None else kind_of_names(self.names)

    def site_at(self, i: int) -> str:
        """Site key of row ``i`` ("" = the sensor's own site)."""
        return str(self.sites[i]) if self.sites is not None else ""

    def names_at(self, i: int) -> tuple[str, ...]:
        """Component names of row ``i`` (its type's angle names in a mixed set)."""
        if self.kinds is None or kind_of_names(self.names):
            return self.names
        return KIND_NAMES[str(self.kinds[i])] + tuple(self.names[2:])

    def __getitem__(self, i: int) -> Measurement:
        return Measurement(float(self.times[i]), self.values[i].copy(), np.diag(self.sigmas[i] ** 2),
                           self.names_at(i), int(i), self.site_at(i), self.kind_at(i))

    def __iter__(self):
        for i in range(len(self)):
            yield self[i]

    def _with(self, idx, cols=None, names=None) -> "MeasurementSet":
        cols = slice(None) if cols is None else cols
        sites = None if self.sites is None else self.sites[idx]
        kinds = None if self.kinds is None else self.kinds[idx]
        table = dict(self.site_table)
        return MeasurementSet(self.times[idx], self.values[idx][:, cols], self.sigmas[idx][:, cols],
                              self.names if names is None else names, dict(self.meta), sites, kinds, table)

    def subset(self, mask_or_index) -> "MeasurementSet":
        """The measurements selected by a boolean mask or index array, in time order."""
        idx = np.arange(len(self))[mask_or_index]
        return self._with(idx)

    def without(self, name: str) -> "MeasurementSet":
        """The set without component ``name`` (e.g. drop the IOD-only 'range')."""
        keep = [i for i, n in enumerate(self.names) if n != name]
        return self._with(np.arange(len(self)), keep, tuple(self.names[i] for i in keep))

    def site_keys(self) -> list[str]:
        """The distinct site keys in order of first appearance ([""] for a one-sensor set)."""
        if self.sites is None:
            return [""]
        return list(dict.fromkeys(self.sites.tolist()))
