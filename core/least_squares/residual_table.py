"""Post-fit residuals per observation: O - C against the fitted orbit.

Angles are given in arcseconds; for right ascension the residual is multiplied by cos(Dec)
(a distance on the sky, as astrometric catalogues report it); a range component is given in km.
The normalised residual of a component is O - C over its one-sigma noise (both in the
component's own units, so RA's own sigma), and an observation's chi-square is the sum of the
squares of its normalised residuals (chi-square with m degrees of freedom when the noise is
right).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from cistrack.units import ARCSEC_RAD, LU_KM

__all__ = ["ResidualTable", "residual_table"]


@dataclass(frozen=True)
class ResidualTable:
    """Post-fit residuals of every observation (used or rejected).

    Attributes
    ----------
    times : (K,) float          TU since the epoch of the measurements
    sites : (K,) str            observing site key ("" when the set names none)
    kinds : (K,) str            "radec", "azel" or ""
    names : tuple of str        the m fitted components, e.g. ("right_ascension", "declination")
    units : tuple of str        unit of each ``o_c`` column: "arcsec" or "km"
    o_c : (K, m) float          observed minus computed: arcsec (RA times cos Dec) or km
    normalised : (K, m) float   O - C over the one-sigma noise
    chi2 : (K,) float           sum of the squared normalised residuals of each observation
    rejected : (K,) bool        left out of the fit as an outlier
    """

    times: np.ndarray
    sites: np.ndarray
    kinds: np.ndarray
    names: tuple[str, ...]
    units: tuple[str, ...]
    o_c: np.ndarray
    normalised: np.ndarray
    chi2: np.ndarray
    rejected: np.ndarray

    def __len__(self) -> int:
        return int(self.times.shape[0])

    def column_names(self) -> tuple[str, ...]:
        """Name of each ``o_c`` column as written by :meth:`rows`: e.g. "ra_cos_dec_arcsec"."""
        out = []
        for j, (name, unit) in enumerate(zip(self.names, self.units)):
            if name == "right_ascension" or (j == 0 and np.any(self.kinds == "radec") and name == "angle_1"):
                name = "ra_cos_dec"
            out.append(f"{name}_{unit}")
        return tuple(out)

    def rms(self, used_only: bool = True) -> np.ndarray:
        """Root mean square of each ``o_c`` column (m,) over the used (or all) observations."""
        keep = ~self.rejected if used_only else np.ones(len(self), dtype=bool)
        if not np.any(keep):
            return np.full(len(self.names), np.nan)
        return np.sqrt(np.mean(self.o_c[keep] ** 2, axis=0))

    def rows(self) -> list[dict[str, Any]]:
        """One dict per observation: t_tu, site, kind, ``o_c_<column>``, ``norm_<name>``, chi2,
        rejected; ready for a CSV or Parquet writer."""
        cols = self.column_names()
        out = []
        for i in range(len(self)):
            row: dict[str, Any] = {"t_tu": float(self.times[i]), "site": str(self.sites[i]),
                                   "kind": str(self.kinds[i])}
            for j, c in enumerate(cols):
                row[f"o_c_{c}"] = float(self.o_c[i, j])
            for j, name in enumerate(self.names):
                row[f"norm_{name}"] = float(self.normalised[i, j])
            row["chi2"] = float(self.chi2[i])
            row["rejected"] = bool(self.rejected[i])
            out.append(row)
        return out


def residual_table(times: np.ndarray, sites: np.ndarray, kinds: np.ndarray, names: tuple[str, ...],
                   values: np.ndarray, residuals: np.ndarray, sigmas: np.ndarray,
                   rejected: np.ndarray) -> ResidualTable:
    """The table from the measured ``values`` (K, m), ``residuals`` O - C (K, m) and ``sigmas``
    (K, m), all in radians / LU, and the ``rejected`` flags (K,)."""
    normalised = residuals / sigmas
    o_c = np.empty_like(residuals)
    units = []
    for j, name in enumerate(names):
        if "range" in name:
            o_c[:, j] = residuals[:, j] * LU_KM
            units.append("km")
        else:
            o_c[:, j] = residuals[:, j] / ARCSEC_RAD
            units.append("arcsec")
    radec = np.asarray(kinds) == "radec"
    if len(names) >= 2 and "range" not in names[1] and np.any(radec):
        o_c[radec, 0] *= np.cos(values[radec, 1])        # RA residual on the sky: times cos(Dec)
    return ResidualTable(times=np.asarray(times, dtype=float), sites=np.asarray(sites, dtype=str),
                         kinds=np.asarray(kinds, dtype=str), names=tuple(names), units=tuple(units),
                         o_c=o_c, normalised=normalised, chi2=np.sum(normalised ** 2, axis=1),
                         rejected=np.asarray(rejected, dtype=bool).copy())
