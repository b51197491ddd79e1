"""On-disk copy of astropy's parsed IERS Earth orientation table, so a process skips the parse.

astropy builds its default Earth orientation table (``IERS_Auto``: the bundled IERS-A
finals2000A.all with the bundled IERS-B eopc04 values substituted) by parsing two text files,
about 0.7-1.3 s of CPU in every process that converts a real-sky time. This module keeps the
parsed table's columns (values, masks, units, descriptions) and metadata as one ``.npz`` file in
the kernel cache directory (:func:`cistrack.propagation.kernels.kernel_cache_dir`, the same
ownership checks), named by a key of the astropy and astropy-iers-data versions and the path,
size and modification time of the four source files. Loading it rebuilds the same ``IERS_Auto``
table, column for column and bit for bit, in a few milliseconds; :func:`install` hands it to
astropy as the default table, so astropy's own interpolation then runs on it unchanged.

Falls back to astropy's parse, silently and with the same numbers, whenever the copy cannot be
used: none yet, another key (the files or versions changed), an unreadable or corrupt file, a
cache directory that cannot be created, is not the user's or is not writable (then nothing is
written either), a ``finals2000A.all`` in the working directory (astropy reads that one instead),
or a default table already chosen in this process. The file is written atomically (a temporary
file renamed over it), so a reader never sees half of one.
"""
from __future__ import annotations

import hashlib
import json
import os
import tempfile
import zipfile
from pathlib import Path

import numpy as np

__all__ = ["cache_key", "cache_path", "install", "load_table", "save_table"]

FORMAT = 1
"""Version of the file layout; part of the key."""
_MISS = (OSError, ValueError, KeyError, TypeError, EOFError, zipfile.BadZipFile)
_META_TYPES = {"int": (int, np.integer), "float": (float, np.floating), "str": (str,)}


def _sources() -> list[str]:
    from astropy.utils import iers

    return [iers.IERS_A_FILE, iers.IERS_A_README, iers.IERS_B_FILE, iers.IERS_B_README]


def cache_key() -> str:
    """Hex key of the table astropy would parse now: layout, versions, and each source file's
    path, size and modification time (ns). Raises ``OSError`` if a source file is missing."""
    import astropy
    import astropy_iers_data

    parts = [f"format={FORMAT}", f"astropy={astropy.__version__}",
             f"iers-data={astropy_iers_data.__version__}"]
    for name in _sources():
        st = os.stat(name)
        parts.append(f"{name}|{st.st_size}|{st.st_mtime_ns}")
    return hashlib.sha256("\n".join(parts).encode()).hexdigest()[:32]


def cache_path(directory: Path | None = None, key: str | None = None) -> Path:
    """``directory/iers-<key>.npz``; ``directory`` defaults to the kernel cache directory,
    checked (and created, mode 0700) by :func:`~cistrack.propagation.kernels.secure_cache_dir`
    (``ConfigError`` or ``OSError`` if it is unusable)."""
    from cistrack.propagation.kernels import secure_cache_dir

    return secure_cache_dir(directory) / f"iers-{key or cache_key()}.npz"


def _column_arrays(table) -> tuple[dict[str, np.ndarray], list[dict]]:
    """The table's columns as plain arrays (``c<i>``, mask ``m<i>``) and one description each."""
    arrays: dict[str, np.ndarray] = {}
    specs = []
    for i, name in enumerate(table.colnames):
        col = table[name]
        unit = getattr(col, "unit", None)
        kind = "quantity" if hasattr(col, "to_value") else ("masked" if hasattr(col, "mask") else "column")
        arrays[f"c{i}"] = np.asarray(col.value if kind == "quantity" else col.data)
        if kind == "masked":
            arrays[f"m{i}"] = np.asarray(col.mask, dtype=bool)
            arrays[f"c{i}"] = np.asarray(col.data.data)
        specs.append({"name": name, "kind": kind, "unit": None if unit is None else unit.to_string(),
                      "description": col.info.description, "format": col.info.format})
    return arrays, specs


def _meta_items(meta) -> list[list]:
    """[key, type, value] for each metadata entry; ``TypeError`` for a type not kept."""
    out = []
    for key, value in meta.items():
        kind = next((k for k, types in _META_TYPES.items() if isinstance(value, types)), None)
        if kind is None:
            raise TypeError(f"IERS table metadata {key!r} of type {type(value).__name__} is not cached")
        out.append([key, kind, value.item() if isinstance(value, np.generic) else value])
    return out


def save_table(table, path: Path, key: str) -> None:
    """Write ``table`` (an astropy IERS table) to ``path`` atomically, stamped with ``key``."""
    arrays, specs = _column_arrays(table)
    header = json.dumps({"key": key, "format": FORMAT, "columns": specs, "meta": _meta_items(table.meta)})
    fd, tmp = tempfile.mkstemp(prefix=".iers-", suffix=".tmp", dir=path.parent)
    try:
        with os.fdopen(fd, "wb") as fh:
            np.savez(fh, header=np.array(header), **arrays)
        os.replace(tmp, path)
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)


def _column(spec: dict, data, i: int):
    from astropy import units as u
    from astropy.table import Column, MaskedColumn

    values = data[f"c{i}"]
    if spec["kind"] == "quantity":
        col = u.Quantity(values, spec["unit"], copy=False)
    elif spec["kind"] == "masked":
        col = MaskedColumn(values, mask=data[f"m{i}"], name=spec["name"])
    else:
        col = Column(values, name=spec["name"])
    col.info.description = spec["description"]
    col.info.format = spec["format"]
    return col


def load_table(path: Path, key: str):
    """The ``IERS_Auto`` table stored at ``path``; ``ValueError`` if it holds another key, and
    the errors of a missing or corrupt file (``OSError``, ``ValueError``, ``KeyError``, ...)."""
    from astropy.utils import iers

    with np.load(path, allow_pickle=False) as data:
        header = json.loads(str(data["header"][()]))
        if header.get("key") != key or header.get("format") != FORMAT:
            raise ValueError(f"{path} holds another IERS table (key {header.get('key')!r})")
        specs = header["columns"]
        cols = [_column(spec, data, i) for i, spec in enumerate(specs)]
    meta = {k: {"int": np.int64, "float": np.float64, "str": str}[kind](v) for k, kind, v in header["meta"]}
    return iers.IERS_Auto(cols, names=[s["name"] for s in specs], meta=meta, copy=False)


def _parsed_and_saved(path: Path | None, key: str):
    """astropy's own parse of the default table, then a copy written to ``path`` if possible."""
    from astropy.utils import iers

    table = iers.IERS_Auto.open()
    if path is not None:
        try:
            save_table(table, path, key)
        except _MISS:
            pass                               # unwritable: the next process parses again
    return table


def install(directory: Path | None = None) -> bool:
    """Make astropy's default Earth orientation table the cached copy (parsing and caching it
    if needed). Returns True if the table came from the cache, False if it was parsed or a default
    table was already chosen. ``directory``: where the copy lives (default: the kernel cache)."""
    from astropy.utils import iers

    from cistrack.errors import ConfigError

    if iers.IERS_Auto.iers_table is not None or os.path.exists("finals2000A.all"):
        return False
    try:
        key = cache_key()
    except OSError:
        return False
    try:
        path: Path | None = cache_path(directory, key)
    except (ConfigError, OSError):
        path = None
    if path is not None:
        try:
            iers.IERS_Auto.iers_table = load_table(path, key)
            return True
        except _MISS:
            pass
    _parsed_and_saved(path, key)
    return False
