"""Observation files: reading and writing through the registered readers.

    mset = read_observations("obs.psv", epoch="2026-01-01T00:00:00Z")        # format from the suffix
    mset = read_observations("obs.txt", epoch=..., format="mpc80")            # or named
    write_observations("obs.tdm", mset, epoch=..., format="tdm")
"""
from __future__ import annotations

from datetime import datetime, timezone
from os import PathLike
from pathlib import Path
from typing import Any

from cistrack import units
from cistrack.errors import MeasurementError
from cistrack.interrupts import plugin_fault
# Defined beside the Reader interface (what reader plugins import); re-exported for this module's callers.
from cistrack.interfaces.reader import FieldError, SeveralObjectsError, field_error, read_text_lines, show_field
from cistrack.model.measurement import MeasurementSet
from cistrack.plugin.registry import Registry, default_registry

__all__ = ["read_observations", "write_observations", "reader_for", "read_checked", "create_checked", "FieldError", "SeveralObjectsError", "field_error",
           "show_field", "read_text_lines"]


def reader_for(path: str | PathLike, format: str | None = None, registry: Registry | None = None,
               **params: Any):
    """The reader component for ``format`` (a registered reader name), or the one whose
    suffixes match ``path`` when ``format`` is None."""
    reg = registry or default_registry()
    if Path(path).is_dir():
        raise MeasurementError(f"{path}: is a directory, not an observation file; give the path of a file "
                               "(e.g. [measurements] file = \"obs.psv\")")
    if format is not None:
        return create_checked(reg, "reader", format, params)
    name = str(path).lower()
    matches = [e.name for e in reg.entries("reader")
               if any(name.endswith(s) for s in getattr(e.factory, "suffixes", ()))]
    if len(matches) > 1:
        raise MeasurementError(f"{path}: several readers claim its suffix: {', '.join(reg.describe('reader', m) for m in matches)}; "
                               "name the one that reads it: in cistrack fit --set measurements.reader.name=NAME, in a "
                               f"scenario [measurements] reader = {{ name = \"NAME\" }} (NAME one of {', '.join(matches)})")
    if len(matches) != 1:
        known = {e.name: list(getattr(e.factory, "suffixes", ())) for e in reg.entries("reader")}
        why = ("not an observation file of any known format: no reader recognises" if not matches
               else f"several readers ({', '.join(matches)}) recognise")
        raise MeasurementError(f"{path}: {why} this file name; give a file whose name ends in a known "
                               f"suffix, or name the format (one of {', '.join(f'{k} {v}' for k, v in known.items())})")
    return create_checked(reg, "reader", matches[0], params)


def create_checked(reg: Registry, kind: str, name: str, params: dict[str, Any]) -> Any:
    """``reg.create(kind, name, **params)``, a parameter the component does not take refused as a
    ConfigError naming it and the parameters it takes (not a TypeError from its constructor)."""
    from cistrack.errors import ConfigError, ParameterError

    try:
        return reg.create(kind, name, **params)
    except ParameterError as exc:
        if "unknown parameter" not in str(exc):
            raise
        raise ConfigError(str(exc)) from None


def read_observations(path: str | PathLike, epoch: str | datetime, format: str | None = None,
                      registry: Registry | None = None, **params: Any) -> MeasurementSet:
    """Read an observation file with the reader ``format`` (or the one matching its suffix);
    ``params`` are the reader's parameters (default sigmas, explicit sites, ...)."""
    if not isinstance(path, (str, PathLike)):
        raise MeasurementError(f"path={type(path).__name__}: give the path of one observation file (a str or a "
                               "path); read several with one call each")
    _check_epoch_years(epoch)
    return read_checked(reader_for(path, format, registry, **params), path, epoch, registry)


def read_checked(reader: Any, path: str | PathLike, epoch: str | datetime,
                 registry: Registry | None = None) -> MeasurementSet:
    """``reader.read(path, epoch)``, a reader that breaks its contract named (:class:`PluginError`):
    one that raises what is neither cistrack's error nor the system's, calls ``sys.exit``, or
    returns something other than a :class:`MeasurementSet`. A third-party reader's own cistrack
    error (a MeasurementSet it built with NaN values, say) is given with its name, distribution and
    the file (probe N13: it had come out naming none of them); ``registry`` (default: the
    installed plugins) says where the reader came from."""
    from cistrack.errors import CistrackError, PluginError, exception_text

    try:
        out = reader.read(path, epoch)
    except SeveralObjectsError:
        raise
    except CistrackError as exc:
        who, builtin = _reader_who(reader, registry)
        if builtin:
            raise
        raise MeasurementError(f"{who} failed on {path}: {exc}") from exc
    except OSError:
        raise
    except BaseException as exc:  # a plugin's fault, named (a KeyboardInterrupt only from a signal)
        if not plugin_fault(exc):
            raise
        raise PluginError(f"{_reader_who(reader, registry)[0]} failed on {path}: {exception_text(exc)}") from exc
    if not isinstance(out, MeasurementSet):
        raise PluginError(f"{_reader_who(reader, registry)[0]} returned {type(out).__name__} for {path}, not a "
                          "MeasurementSet (docs/plugins.md, Readers)")
    return out


def _reader_who(reader: Any, registry: Registry | None) -> tuple[str, bool]:
    """(the reader in messages: ``reader 'name' (distribution version)``, or its class and module
    when it is not registered; whether it is one of cistrack's own)."""
    from cistrack.plugin.registry import BUILTIN_DISTRIBUTION

    name = getattr(type(reader), "registry_name", None)
    reg = registry or default_registry()
    entry = next((e for e in reg.entries("reader") if e.name == name), None) if name else None
    if entry is None:
        module = type(reader).__module__
        return f"reader {type(reader).__name__!r} ({module})", module.startswith("cistrack.")
    return reg.describe("reader", name), entry.distribution == BUILTIN_DISTRIBUTION


def _check_epoch_years(epoch: Any) -> None:
    """Refuse an ``epoch`` outside the years cistrack supports (a scenario's, 1800-2200), naming it;
    one that is not a time is left to the reader, which names it."""
    from cistrack.scenario.work_limits import check_epoch_span

    try:
        when = units.parse_utc(epoch) if isinstance(epoch, str) else epoch
    except (ValueError, TypeError):
        return
    if isinstance(when, datetime):
        check_epoch_span(when if when.tzinfo else when.replace(tzinfo=timezone.utc), 0.0, "epoch")


def write_observations(path: str | PathLike, measurements: MeasurementSet, epoch: str | datetime,
                       format: str | None = None, registry: Registry | None = None, **params: Any) -> None:
    """Write ``measurements`` with the reader ``format`` (or the one matching the suffix). Their
    times are counted from ``epoch``: MeasurementError when the set records another epoch (its
    ``meta["epoch"]``, as readers set it), whose times would all be shifted by the difference."""
    _check_same_epoch(measurements, epoch)
    reader_for(path, format, registry, **params).write(path, measurements, epoch)


def _check_same_epoch(measurements: MeasurementSet, epoch: str | datetime) -> None:
    from cistrack import units

    own = (getattr(measurements, "meta", None) or {}).get("epoch")
    if own is None:
        return
    try:
        same = units.parse_utc(own) == units.parse_utc(epoch)
    except (TypeError, ValueError):
        return  # an unreadable epoch is the writer's to refuse, naming it
    if not same:
        raise MeasurementError(f"epoch={epoch!s}: the measurements' times are counted from {own} (their meta['epoch'], "
                               f"as they were read); writing them from another epoch would shift every time by the "
                               f"difference; pass epoch={own!r}")
