"""Per-step estimates of a run on disk: mean state, covariance and the full Gaussian mixture.

Written beside ``steps.parquet`` as ``estimates.parquet`` (one row per step, the same step
numbers), in the synodic frame in km and km/s (positions barycentric, velocities relative to the
rotating frame), so that a run's orbit estimate can be exported (``cistrack export``) or
re-analysed without re-running. Columns::

    step, kind, t_tu, utc               identifiers (utc ISO-8601)
    mean_km          list<double>[6]    moment-matched mean (x, y, z km; vx, vy, vz km/s)
    covariance_km    list<double>[36]   moment-matched covariance, row-major (km^2, km^2/s, km^2/s^2)
    n_components     int
    weights          list<double>[M]
    means_km         list<double>[M*6]  component means, row-major
    covariances_km   list<double>[M*36] component covariances, row-major
    nis, nis_dof     float, int         normalised innovation squared of the step's measurement
                                        under the prior (update steps; NaN, 0 otherwise), see
                                        :mod:`cistrack.evaluation.consistency`

Like the steps table, rows are written in part files of many steps while the run goes
(:mod:`cistrack.results.part_files`: a killed run keeps every part written) and merged at the end.
"""
from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from cistrack.errors import ConfigError
from cistrack.plugin.hookspecs import hookimpl
from cistrack.results.atomic_files import atomic_target
from cistrack.results.part_files import ROWS_PER_PART, SECONDS_PER_PART, PartWriter, read_checked, read_parts, write_checked
from cistrack.units import LU_KM, VU_KMS

__all__ = ["EstimateWriter", "Estimates", "read_estimates", "usable_estimates", "ESTIMATES", "KM_SCALE"]

ESTIMATES = "estimates.parquet"
_PARTS = "estimates-parts"
_COLUMNS = ("step", "kind", "t_tu", "utc", "mean_km", "covariance_km", "n_components", "weights", "means_km",
            "covariances_km")
"""The columns every estimates table has (``nis`` and ``nis_dof`` are read when present)."""
KM_SCALE = np.array([LU_KM, LU_KM, LU_KM, VU_KMS, VU_KMS, VU_KMS])
"""Nondimensional synodic state -> km, km/s, per component."""


def _to_km(mean: np.ndarray, cov: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    return mean * KM_SCALE, cov * np.multiply.outer(KM_SCALE, KM_SCALE)


def estimate_row(step, nis: float = float("nan"), nis_dof: int = 0) -> dict:
    """The estimates-table row of one step (see the module docstring)."""
    mix = step.belief.mixture
    mean, cov = _to_km(np.asarray(mix.mean), np.asarray(mix.covariance))
    means = np.asarray(mix.means) * KM_SCALE
    covs = np.asarray(mix.covariances) * np.multiply.outer(KM_SCALE, KM_SCALE)
    return {"step": int(step.index), "kind": step.kind, "t_tu": float(step.t), "utc": step.utc,
            "mean_km": mean.tolist(), "covariance_km": cov.reshape(-1).tolist(),
            "n_components": int(mix.n_components), "weights": np.asarray(mix.weights).tolist(),
            "means_km": means.reshape(-1).tolist(), "covariances_km": covs.reshape(-1).tolist(),
            "nis": float(nis), "nis_dof": int(nis_dof)}


def _arrow():
    """pyarrow and pyarrow.parquet, imported on use: ~35 ms that listings and --help never need."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    return pa, pq


class EstimateWriter:
    """Lifecycle observer writing ``estimates.parquet`` into ``directory``."""

    def __init__(self, directory: str | Path, rows_per_part: int = ROWS_PER_PART,
                 seconds_per_part: float = SECONDS_PER_PART) -> None:
        self.directory = Path(directory)
        self._parts = PartWriter(self.directory / _PARTS, rows_per_part, seconds_per_part)

    @hookimpl
    def cistrack_run_started(self, run) -> None:
        self._parts.start()
        if (self.directory / ESTIMATES).exists():
            (self.directory / ESTIMATES).unlink()

    @hookimpl
    def cistrack_step_predicted(self, run, step) -> None:
        if step.kind in ("predict", "initial"):
            self._write(step)

    @hookimpl
    def cistrack_step_updated(self, run, step) -> None:
        # the NIS under the prior, a metric of the run's residuals stage (cistrack.evaluation.residuals)
        self._write(step, float(step.metrics.get("nis", float("nan"))), int(step.metrics.get("nis_dof", 0)))

    def _write(self, step, nis: float = float("nan"), dof: int = 0) -> None:
        self._parts.add(step.index, estimate_row(step, nis, dof))

    @hookimpl
    def cistrack_run_finished(self, run, summary) -> None:
        self._parts.flush()
        parts = self._parts.parts()
        if parts:
            table = read_parts(self.directory / _PARTS)
            with atomic_target(self.directory / ESTIMATES, ESTIMATES + ".tmp") as tmp:  # no partial file on a full disk
                write_checked(table, tmp)
            for p in parts:
                p.unlink()
            try:
                (self.directory / _PARTS).rmdir()
            except OSError:
                pass


@dataclass
class Estimates:
    """A run's per-step estimates (K steps), synodic frame, km and km/s.

    Attributes
    ----------
    step : (K,) int; kind : (K,) str; t_tu : (K,) float; utc : (K,) str
    mean_km : (K, 6) float
    covariance_km : (K, 6, 6) float
    weights, means_km, covariances_km : lists of K arrays (M_k,), (M_k, 6), (M_k, 6, 6)
    nis : (K,) float (NaN where no measurement); nis_dof : (K,) int
    """

    step: np.ndarray
    kind: np.ndarray
    t_tu: np.ndarray
    utc: np.ndarray
    mean_km: np.ndarray
    covariance_km: np.ndarray
    weights: list
    means_km: list
    covariances_km: list
    nis: np.ndarray | None = None
    nis_dof: np.ndarray | None = None

    def __len__(self) -> int:
        return int(self.step.shape[0])


def read_estimates(directory: str | Path) -> Estimates:
    """The estimates of a run directory (``estimates.parquet``, or the parts of a killed run).

    Raises FileNotFoundError when there are none (also for ``estimates.parquet`` a symbolic link
    to nothing), ConfigError naming the file when one is not a readable estimates table (empty,
    truncated, another file's content)."""
    d = Path(directory)
    path = d / ESTIMATES
    if path.is_symlink() and not path.exists():
        raise FileNotFoundError(f"{path}: a symbolic link to {os.readlink(path)}, which does not exist; "
                                "no estimates to read")
    files = [path] if path.exists() else sorted((d / _PARTS).glob("part-*.parquet"))
    if not files:
        raise FileNotFoundError(f"{d}: no estimates ({ESTIMATES}); was the run written by cistrack "
                                f"with an output directory?")
    return _estimates_of(_read_tables(files))


def usable_estimates(directory: str | Path) -> Estimates:
    """The estimates of a run directory (:func:`read_estimates`) when they hold an orbit to export
    or predict from: ConfigError naming the file when the table has no rows, or naming the directory
    when a step appears twice or a time, mean, covariance or mixture value is NaN or infinite (a run
    never writes one: it ends ``filter-failed`` first). FileNotFoundError as :func:`read_estimates`."""
    d = Path(directory)
    est = read_estimates(d)
    again = f"run the scenario again into {d} with --overwrite"
    if len(est) == 0:
        where = d / ESTIMATES if (d / ESTIMATES).exists() else d / _PARTS
        raise ConfigError(f"{where}: holds no estimates; {again}")
    steps, counts = np.unique(est.step, return_counts=True)
    bad = f"step {int(steps[counts > 1][0])} appears {int(counts.max())} times" if counts.max() > 1 else \
        _first_not_finite(est)
    if bad:
        raise ConfigError(f"{d}: its estimates are damaged ({bad}; a run writes each step once, with finite "
                          f"states and times); {again}")
    return est


def _first_not_finite(est: Estimates) -> str:
    """``step 12's covariance_km holds NaN or inf``, naming the first step and column of ``est``
    holding a value that is not finite; "" when all are finite."""
    per_step = {"t_tu": est.t_tu.reshape(len(est), 1), "mean_km": est.mean_km.reshape(len(est), -1),
                "covariance_km": est.covariance_km.reshape(len(est), -1)}
    for k in range(len(est)):
        mixture = {"weights": est.weights[k], "means_km": est.means_km[k], "covariances_km": est.covariances_km[k]}
        for name, values in (*((n, v[k]) for n, v in per_step.items()), *mixture.items()):
            if not np.isfinite(values).all():
                return f"step {int(est.step[k])}'s {name} holds NaN or inf"
    return ""


def _read_tables(files: list[Path]):
    """The rows of ``files`` (parquet) as one table; ConfigError naming the file that is not one."""
    pa, pq = _arrow()
    tables = []
    for f in files:
        try:
            tables.append(read_checked(f))
        except (OSError, pa.ArrowException) as exc:  # ArrowInvalid: empty, truncated or not parquet
            size = f.stat().st_size if f.exists() else 0
            raise ConfigError(f"{f}: not a readable estimates table ({size} bytes: {exc}); write it again with "
                              "'cistrack run' into this directory") from None
    missing = [c for c in _COLUMNS if any(c not in t.column_names for t in tables)]
    if missing:
        raise ConfigError(f"{files[0] if len(files) == 1 else files[0].parent}: not an estimates table (no column "
                          f"{', '.join(missing)}); write it again with 'cistrack run' into this directory")
    return pa.concat_tables(tables, promote_options="default") if len(tables) > 1 else tables[0]


def _estimates_of(table) -> Estimates:
    """:class:`Estimates` from the columns of an estimates table (any row order)."""
    cols = table.to_pydict()
    order = np.argsort(np.asarray(cols["step"]))
    k = len(order)
    m = [int(cols["n_components"][i]) for i in order]
    return Estimates(
        step=np.asarray(cols["step"], dtype=int)[order], kind=np.asarray(cols["kind"])[order],
        t_tu=np.asarray(cols["t_tu"], dtype=float)[order], utc=np.asarray(cols["utc"])[order],
        mean_km=np.asarray([cols["mean_km"][i] for i in order], dtype=float).reshape(k, 6),
        covariance_km=np.asarray([cols["covariance_km"][i] for i in order], dtype=float).reshape(k, 6, 6),
        weights=[np.asarray(cols["weights"][i], dtype=float) for i in order],
        means_km=[np.asarray(cols["means_km"][i], dtype=float).reshape(mm, 6) for i, mm in zip(order, m)],
        covariances_km=[np.asarray(cols["covariances_km"][i], dtype=float).reshape(mm, 6, 6) for i, mm in zip(order, m)],
        nis=np.asarray(cols["nis"], dtype=float)[order] if "nis" in cols else None,
        nis_dof=np.asarray(cols["nis_dof"], dtype=int)[order] if "nis_dof" in cols else None,
    )
